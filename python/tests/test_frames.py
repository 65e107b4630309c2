"""ssta.classify and the calibrations against `ssta classify --left --right --calib0 --calib1`."""

import json

import matplotlib.image
import numpy as np
import pytest

import ssta
from conftest import cli_error


def read_u8(path):
    return np.round(matplotlib.image.imread(path) * 255).astype(np.uint8)


@pytest.fixture(scope="module")
def pair(yard):
    left = sorted((yard / "cam0" / "data").glob("*.png"))[3]
    return left, yard / "cam1" / "data" / left.name


@pytest.fixture(scope="module")
def calibration(yard):
    return ssta.StereoCalibration.load(yard / "cam0" / "sensor.yaml", yard / "cam1" / "sensor.yaml")


@pytest.fixture(scope="module")
def cli_frame(cli, yard, pair, tmp_path_factory):
    out = tmp_path_factory.mktemp("classified")
    cli("classify", "--left", pair[0], "--right", pair[1], "--calib0", yard / "cam0" / "sensor.yaml",
        "--calib1", yard / "cam1" / "sensor.yaml", "--out", out, "-q")
    stem = pair[0].stem
    return read_u8(out / "labels" / f"{stem}.png"), json.loads((out / "frames" / f"{stem}.json").read_text())


def test_rules_count_as_the_cli_report_says(pair, calibration, cli_frame):
    _, report = cli_frame
    result = ssta.classify(read_u8(pair[0]), read_u8(pair[1]), calibration)
    labels, rules = result["labels"], result["rules"]
    assert rules.shape == labels.shape and rules.dtype == np.uint8
    assert ssta.LABEL_RULES[3] == "segment" and len(set(ssta.LABEL_RULES)) == len(ssta.LABEL_RULES)
    # The frame JSON's pixels_by_rule are the counts of these two images, rule by rule.
    classes = ["unknown", "traversable", "semi-traversable", "non-traversable", "undecided"]
    for rule_id, name in enumerate(ssta.LABEL_RULES):
        for class_id, class_name in enumerate(classes):
            count = int(np.count_nonzero((rules == rule_id) & (labels == class_id)))
            assert report["pixels_by_rule"][name][class_name] == count, (name, class_name)


def test_labels_and_segments_equal_cli(pair, calibration, cli_frame):
    labels, report = cli_frame
    result = ssta.classify(read_u8(pair[0]), read_u8(pair[1]), calibration)
    np.testing.assert_array_equal(result["labels"], labels)
    assert {1, 3} <= set(np.unique(labels))  # a frame with ground and obstacles
    segments = result["segments"]
    np.testing.assert_array_equal(segments["id"], np.arange(len(segments)))
    assert len(report["segments"]) > 10
    for s in report["segments"]:  # the report lists the segments of min_plane_points or more
        row = segments[s["id"]]
        assert row["class"] == s["class"] and row["inliers"] == s["inliers"]
        assert row["slope_deg"] == pytest.approx(s["slope_deg"], abs=1e-3)
        np.testing.assert_allclose(row["centroid"], s["centroid"], rtol=1e-5, atol=1e-6)  # JSON: 6 digits
        assert result["segment_reasons"][s["id"]] == s["reason"]
    assert result["quality"] == {"passed": report["quality"]["passed"], "judged": report["quality"]["judged"],
                                 "reason": report["quality"].get("reason", "")}
    assert result["ground_plane"]["found"]
    assert result["disparity"].dtype == np.float32 and result["segment_ids"].dtype == np.int32


def test_colour_images_are_made_grey(pair, calibration):
    grey_left, grey_right = read_u8(pair[0]), read_u8(pair[1])
    as_rgb = [np.repeat(image[:, :, None], 3, axis=2) for image in (grey_left, grey_right)]
    np.testing.assert_array_equal(ssta.classify(*as_rgb, calibration)["labels"],
                                  ssta.classify(grey_left, grey_right, calibration)["labels"])


def test_calibration_from_arrays_equals_sensor_yaml(pair, calibration):
    left, right = calibration.left, calibration.right
    from_arrays = ssta.StereoCalibration(
        ssta.CameraCalibration(left.width, left.height, left.K, left.distortion, left.body_T_camera),
        ssta.CameraCalibration(right.width, right.height, right.K, right.distortion, right.body_T_camera))
    np.testing.assert_array_equal(from_arrays.right.body_T_camera, right.body_T_camera)
    images = read_u8(pair[0]), read_u8(pair[1])
    np.testing.assert_array_equal(ssta.classify(*images, from_arrays)["labels"],
                                  ssta.classify(*images, calibration)["labels"])


def test_a_pipeline_answers_as_classify_and_takes_a_config(pair, calibration):
    images = read_u8(pair[0]), read_u8(pair[1])
    pipeline = ssta.FramePipeline(calibration)
    first = pipeline.classify(*images)["labels"]
    np.testing.assert_array_equal(pipeline.classify(*images)["labels"], first)
    np.testing.assert_array_equal(ssta.classify(*images, calibration)["labels"], first)
    strict = ssta.Config()
    strict.vehicle.max_slope_deg = 5.0
    strict.vehicle.semi_slope_deg = 2.0
    strict_labels = ssta.classify(*images, calibration, strict)["labels"]
    assert (strict_labels == 3).sum() > (first == 3).sum()


def test_bad_images_name_the_argument(pair, calibration):
    left, right = read_u8(pair[0]), read_u8(pair[1])
    with pytest.raises(ValueError, match=r"^left: expected a uint8 image, got dtype float64"):
        ssta.classify(left.astype(np.float64), right, calibration)
    with pytest.raises(ValueError, match=r"^right: expected shape \(H, W\) grey or \(H, W, 3\) RGB, got \(240, 320, 4\)"):
        ssta.classify(left, np.zeros((240, 320, 4), np.uint8), calibration)
    with pytest.raises(ValueError, match=r"^up: must be a finite, non-zero vector"):
        ssta.classify(left, right, calibration, up=(0.0, np.nan, 1.0))
    with pytest.raises(ssta.Error):  # another size than the calibration's
        ssta.classify(left[:200], right[:200], calibration)


def test_bad_calibrations(yard, tmp_path):
    with pytest.raises(FileNotFoundError) as e:
        ssta.StereoCalibration.load(yard / "cam0" / "sensor.yaml", tmp_path / "cam1.yaml")
    assert e.value.filename == str(tmp_path / "cam1.yaml")
    broken = tmp_path / "sensor.yaml"
    broken.write_text((yard / "cam0" / "sensor.yaml").read_text().replace("intrinsics: [", "intrinsics: [-"))
    with pytest.raises(ssta.Error) as e:
        ssta.CameraCalibration.load(broken)
    assert str(broken) in str(e.value)
    left = str(yard / "cam0" / "data" / "x.png")
    assert str(e.value) == cli_error("classify", "--left", left, "--right", left, "--calib0", broken,
                                     "--calib1", yard / "cam1" / "sensor.yaml", "--out", tmp_path / "out")
    K = np.array([[200.0, 0, 160], [0, 200, 120], [0, 0, 1]])
    with pytest.raises(ValueError, match=r"^K: expected \[\[fu, 0, cu\]"):
        ssta.CameraCalibration(320, 240, K + np.array([[0, 1.0, 0], [0, 0, 0], [0, 0, 0]]))
    with pytest.raises(ValueError, match=r"^body_T_camera: "):
        ssta.CameraCalibration(320, 240, K, body_T_camera=np.eye(4) * 2)
    with pytest.raises(ValueError, match=r"^distortion: expected four numbers"):
        ssta.CameraCalibration(320, 240, K, distortion=[0.1])
    with pytest.raises(ValueError):  # the pair's check: no baseline
        ssta.StereoCalibration(ssta.CameraCalibration(320, 240, K), ssta.CameraCalibration(320, 240, K))
