"""ssta.Map against `ssta query` / `ssta export` on the same map: the same answers, the same
errors."""

import sys
import threading
from concurrent.futures import ThreadPoolExecutor

import matplotlib.image
import numpy as np
import pytest

import ssta
from conftest import cli_error, read_csv

# The CSV's precision per column (QueryCsvRow): compare to half its last digit.
CSV_DECIMALS = {"x": 4, "y": 4, "z": 4, "cost": 4, "probability": 4, "slope_deg": 2, "step_m": 3,
                "confidence": 4, "frame_mean_slope_deg": 2, "frame_mean_step_m": 3, "mean_cost": 4, "max_cost": 4, "fraction_observed": 4, "distance_m": 4,
                "pitch_deg": 2, "roll_deg": 2, "drivable_confidence": 4}


def assert_rows_match_csv(rows, csv_columns, columns_of_rows=None):
    """Each column of the CLI's CSV equals the structured rows' field: ids exactly, numbers to
    the CSV's precision, NaN where the CSV says nan."""
    for name, expected in csv_columns.items():
        field = (columns_of_rows or {}).get(name, name)
        if expected.dtype.kind == "U":  # text: the same strings
            np.testing.assert_array_equal(rows[field], expected, err_msg=name)
            continue
        got = rows[field].astype(np.float64)
        assert got.shape == expected.shape, name
        np.testing.assert_array_equal(np.isnan(got), np.isnan(expected), err_msg=name)
        tolerance = 0.5 * 10.0 ** -CSV_DECIMALS.get(name, 0) + 1e-9
        np.testing.assert_allclose(got, expected, rtol=0, atol=tolerance, equal_nan=True, err_msg=name)


def assert_structured_equal(a, b):
    """Structured arrays equal field by field, NaN equal to NaN."""
    assert a.dtype.names == b.dtype.names and a.shape == b.shape
    for name in a.dtype.names:
        np.testing.assert_array_equal(a[name], b[name], err_msg=name)


@pytest.fixture(scope="module")
def the_map(yard_map):
    return ssta.Map.open(yard_map)


@pytest.fixture(scope="module")
def points(the_map):
    """A grid over the map's bounds and a margin beyond them (unobserved columns too)."""
    x0, y0, _, x1, y1, _ = the_map.bounds
    xs, ys = np.meshgrid(np.linspace(x0 - 1, x1 + 1, 61), np.linspace(y0 - 1, y1 + 1, 45))
    return np.column_stack([xs.ravel(), ys.ravel()])


def cli_query(cli, tmp_path, map_path, points, *extra):
    csv_path = tmp_path / "points.csv"
    np.savetxt(csv_path, points, delimiter=",", fmt="%.17g")
    return read_csv(cli("query", "--map", map_path, "--points", csv_path, *extra).stdout)


def test_query_xy_equals_cli(the_map, yard_map, points, cli, tmp_path):
    rows = the_map.query(points)
    assert rows.dtype.names == ("x", "y", "z", "class", "cost", "probability", "slope_deg", "step_m",
                                "observations", "confidence", "decided_by", "frame_mean_slope_deg",
                                "frame_mean_step_m", "height_m", "observed")
    expected = cli_query(cli, tmp_path, yard_map, points)
    assert_rows_match_csv(rows, expected)
    # The test would pass on an empty map: the grid must reach every class the map holds.
    assert {1, 2, 3} <= set(rows["class"]) and 0 in rows["class"]
    assert np.array_equal(rows["observed"], ~np.isnan(rows["z"]))


def test_query_slope_and_step_are_those_that_decided_the_class(the_map, points):
    rows = the_map.query(points)
    vehicle = the_map.metadata["vehicle"]
    classified = np.isin(rows["class"], [1, 2, 3])
    assert set(rows["decided_by"][classified]) <= {"frames", "surface", "both"}
    assert set(rows["decided_by"][~classified]) == {""}
    # Where the fused surface decided or co-decided, the row's slope and step are its plane's,
    # so they lie in the class's band: a traversable cell is not steep nor a step, a
    # non-traversable one not level ground (the surface's class weighs their sigmas, so the
    # bands are the outer ones).
    surface = classified & np.isin(rows["decided_by"], ["surface", "both"])
    assert surface.sum() >= 20, "the grid must meet columns the surface judged"
    slope, step = rows["slope_deg"][surface], np.abs(rows["step_m"][surface])
    cls = rows["class"][surface]
    assert np.all(np.isfinite(slope)) and np.all(np.isfinite(step))
    assert np.all((slope[cls == 1] <= vehicle["max_slope_deg"]) & (step[cls == 1] <= vehicle["max_step_m"]))
    assert np.all((slope[cls == 3] > vehicle["semi_slope_deg"]) | (step[cls == 3] > vehicle["semi_step_m"]))
    # Where the frames' votes decided alone, no slope or step decided: NaN; their means stay.
    frames = rows["decided_by"] == "frames"
    assert frames.any()
    assert np.all(np.isnan(rows["slope_deg"][frames])) and np.all(np.isnan(rows["step_m"][frames]))
    assert np.isfinite(rows["frame_mean_slope_deg"][frames]).any()
    # The frames' means of a column are those of its top voxel, which the frames judge.
    voted = classified & np.isfinite(rows["frame_mean_slope_deg"])
    voxels = the_map.query(np.column_stack([rows["x"], rows["y"], rows["z"]])[voted])
    assert set(voxels["decided_by"]) == {"frames"}
    np.testing.assert_array_equal(voxels["frame_mean_slope_deg"], rows["frame_mean_slope_deg"][voted])
    assert np.all(np.isnan(voxels["slope_deg"]))  # a voxel's class is the votes'


def test_query_xyz_equals_cli(the_map, yard_map, points, cli, tmp_path):
    xyz = np.column_stack([points, np.full(len(points), 0.05)])
    expected = cli_query(cli, tmp_path, yard_map, xyz)
    assert_rows_match_csv(the_map.query(xyz), expected)


@pytest.mark.parametrize("fill_holes,local_ground", [(5, 0.0), (0, 0.0), (3, 0.5)])
def test_query_as_exported_equals_cli(the_map, yard_map, points, cli, tmp_path, fill_holes, local_ground):
    rows = the_map.query(points, as_exported=True, fill_holes=fill_holes, local_ground_radius_m=local_ground)
    expected = cli_query(cli, tmp_path, yard_map, points, "--as-exported", "--fill-holes", fill_holes,
                         "--local-ground", local_ground)
    assert_rows_match_csv(rows, expected)


def test_query_accepts_other_real_dtypes(the_map, points):
    as_float32 = the_map.query(points.astype(np.float32))
    np.testing.assert_array_equal(as_float32["class"], the_map.query(points.astype(np.float32).astype(np.float64))["class"])
    integer_rows = the_map.query(np.array([[3, 0], [4, 1]], dtype=np.int32))
    np.testing.assert_array_equal(integer_rows["class"], the_map.query(np.array([[3.0, 0.0], [4.0, 1.0]]))["class"])


FOOTPRINTS = [(3.0, 0.0, 0.0, 1.2, 0.8), (4.0, 1.0, 30.0, 1.0, 0.6), (6.5, -1.5, 90.0, 2.0, 1.0),
              (9.0, 2.0, -45.0, 0.5, 0.5), (40.0, 40.0, 0.0, 1.0, 1.0)]


@pytest.mark.parametrize("as_exported,min_confidence", [(False, 0.0), (True, 0.0), (False, 0.8), (True, 0.8)])
def test_footprints_equal_cli(the_map, yard_map, cli, as_exported, min_confidence):
    poses = np.array([(x, y, np.radians(yaw_deg)) for x, y, yaw_deg, _, _ in FOOTPRINTS])
    extra = (["--as-exported"] if as_exported else []) + ["--min-confidence", min_confidence]
    for (x, y, yaw_deg, length, width), pose in zip(FOOTPRINTS, poses):
        got = the_map.footprints(pose[None, :], length, width, as_exported=as_exported,
                                 min_confidence=min_confidence)
        expected = read_csv(cli("query", "--map", yard_map, "--footprint",
                                f"{x},{y},{yaw_deg},{length},{width}", *extra).stdout)
        assert_rows_match_csv(got, expected, {})
    # All poses in one call answer as one at a time (one exported surface serves them all).
    same = [(x, y, np.radians(yaw)) for x, y, yaw, _, _ in FOOTPRINTS]
    together = the_map.footprints(np.array(same), 1.2, 0.8, as_exported=as_exported)
    one_by_one = np.concatenate([the_map.footprints(np.array([p]), 1.2, 0.8, as_exported=as_exported) for p in same])
    assert_structured_equal(together, one_by_one)


@pytest.mark.parametrize("as_exported,min_confidence", [(False, 0.0), (True, 0.0), (False, 0.8)])
def test_path_equals_cli(the_map, yard_map, cli, tmp_path, as_exported, min_confidence):
    vertices = np.array([[1.5, 0.0], [5.0, 0.5], [8.0, -2.0], [12.0, -2.0]])
    np.savetxt(tmp_path / "path.csv", vertices, delimiter=",", header="x,y", comments="")
    extra = (["--as-exported"] if as_exported else []) + ["--min-confidence", min_confidence]
    result = cli("query", "--map", yard_map, "--path", tmp_path / "path.csv", "--width", 0.8, *extra)
    got = the_map.path(vertices, 0.8, as_exported=as_exported, min_confidence=min_confidence)
    assert_rows_match_csv(got["samples"], read_csv(result.stdout))
    # The verdict the CLI prints on stderr: "path L m, N samples, worst class W, blocked at D m, P % observed".
    verdict = result.stderr.strip()
    assert f"path {got['length_m']:.2f} m, {len(got['samples'])} samples, worst class {got['worst']}," in verdict
    if got["blocked"]:
        assert f"blocked at {got['first_non_traversable_distance_m']:.2f} m" in verdict
        assert got["first_non_traversable"] is not None
    else:
        assert "not blocked" in verdict and got["first_non_traversable"] is None


def test_a_confidence_bar_makes_only_the_unsure_drivable_answers_undecided(the_map):
    # Every 0.5 m over the yard's mapped area, heading 0: the footprints a planner with a bar of
    # 0.8 is told are those without one, except that a drivable answer whose least sure
    # drivable cell is under 0.8 is undecided (4), as `eval footprints --min-confidence` counts.
    x_min, y_min, _, x_max, y_max, _ = the_map.bounds
    xs, ys = np.meshgrid(np.arange(x_min, x_max, 0.5), np.arange(y_min, y_max, 0.5))
    poses = np.column_stack([xs.ravel(), ys.ravel(), np.zeros(xs.size)])
    plain = the_map.footprints(poses, 1.0, 0.6)
    barred = the_map.footprints(poses, 1.0, 0.6, min_confidence=0.8)
    unsure = np.isin(plain["worst"], (1, 2)) & (plain["drivable_confidence"] < 0.8)
    assert 0 < unsure.sum() < np.isin(plain["worst"], (1, 2)).sum()  # the bar has work to do
    np.testing.assert_array_equal(barred["worst"][unsure], 4)
    np.testing.assert_array_equal(barred["worst"][~unsure], plain["worst"][~unsure])
    assert np.all(np.isnan(barred["drivable_confidence"]) | (barred["drivable_confidence"] >= 0.8))
    # A point query takes the same bar: a drivable cell under it has class 4 and no cost.
    rows = the_map.query(poses[:, :2], min_confidence=0.8)
    low = the_map.query(poses[:, :2])
    below = np.isin(low["class"], (1, 2)) & (low["confidence"] < 0.8)
    np.testing.assert_array_equal(rows["class"][below], 4)
    assert np.all(np.isnan(rows["cost"][below]))
    with pytest.raises(ValueError, match="min_confidence"):
        the_map.footprints(poses[:1], 1.0, 0.6, min_confidence=1.5)


def test_project_at_a_confidence_bar_equals_the_grid_export_at_it(the_map, yard_map, cli, tmp_path):
    cli("export", "--map", yard_map, "--format", "grid", "--out", tmp_path / "grid", "--min-confidence", 0.8)
    classes_png = np.round(matplotlib.image.imread(tmp_path / "grid_classes.png") * 255).astype(np.uint8)
    barred = the_map.project(as_exported=True, min_confidence=0.8)
    np.testing.assert_array_equal(barred["class"], classes_png)
    plain = the_map.project(as_exported=True)
    assert (barred["class"] == 4).sum() > (plain["class"] == 4).sum()  # the bar withheld some
    with pytest.raises(ValueError, match="min_confidence"):
        the_map.project(min_confidence=-1.0)


def test_project_as_exported_equals_grid_export(the_map, yard_map, cli, tmp_path):
    cli("export", "--map", yard_map, "--format", "grid", "--out", tmp_path / "grid")
    classes_png = np.round(matplotlib.image.imread(tmp_path / "grid_classes.png") * 255).astype(np.uint8)
    grid = the_map.project(as_exported=True)
    np.testing.assert_array_equal(grid["class"], classes_png)
    yaml_text = (tmp_path / "grid.yaml").read_text()
    origin_line = next(line for line in yaml_text.splitlines() if line.startswith("origin:"))
    origin = [float(v) for v in origin_line.split("[")[1].split("]")[0].split(",")][:2]
    np.testing.assert_allclose(grid["origin"], origin, atol=1e-6)
    assert grid["resolution_m"] == the_map.resolution_m
    x0, x1, y0, y1 = grid["extent"]
    assert (x1 - x0, y1 - y0) == pytest.approx((grid["class"].shape[1] * 0.1, grid["class"].shape[0] * 0.1))


def attitude_cost(pitch_deg, roll_deg, vehicle):
    """The attitude's cost (docs/interfaces.md, section 5): f = the largest fraction of a limit;
    0 up to 0.8, 0.25 + 0.5 (f - 0.8) / 0.2 up to 1, then 1."""
    pitch_limit = vehicle["max_pitch_deg"] if pitch_deg >= 0 else vehicle["max_descent_deg"]
    f = max(abs(pitch_deg) / pitch_limit, abs(roll_deg) / vehicle["max_roll_deg"])
    return 0.0 if f <= 0.8 else 0.25 + 0.5 * (f - 0.8) / 0.2 if f <= 1.0 else 1.0


def test_project_headings_agree_with_footprints_and_the_grid_export(the_map, yard_map, cli, tmp_path):
    grid = the_map.project(as_exported=True, headings=8)
    h, w = grid["class"].shape
    stack = grid["cost_heading"]
    assert stack.shape == (h, w, 8) and stack.dtype == np.float32
    assert grid["headings_deg"] == [0.0, 45.0, 90.0, 135.0, 180.0, 225.0, 270.0, 315.0]
    # The class cost, never lowered; unknown where the class cost is.
    cost = grid["cost"][:, :, None]
    np.testing.assert_array_equal(np.isnan(stack), np.isnan(np.broadcast_to(cost, stack.shape)))
    known = ~np.isnan(stack)
    assert known.any() and np.all(stack[known] >= np.broadcast_to(cost, stack.shape)[known])

    # Each layer is the heading cost of the footprint query centred at the pixel.
    vehicle = the_map.metadata["vehicle"]
    x0, y0 = grid["origin"]
    r = grid["resolution_m"]
    rows, cols = np.nonzero(known[:, :, 0])
    checked = 0
    for v, u in list(zip(rows, cols))[:: max(1, len(rows) // 40)]:
        for k in range(8):
            pose = np.array([[x0 + (u + 0.5) * r, y0 + (h - 1 - v + 0.5) * r, np.radians(45.0 * k)]])
            f = the_map.footprints(pose, 1.0, 0.6, as_exported=True)[0]
            assert f["within_limits"] == (f["attitude"] in (1, 2))
            expected = grid["cost"][v, u]
            if np.isfinite(f["pitch_deg"]):
                expected = max(expected, attitude_cost(f["pitch_deg"], f["roll_deg"], vehicle))
            assert stack[v, u, k] == pytest.approx(expected, abs=1e-4), (v, u, k)
            checked += 1
    assert checked >= 8 * 20

    # `ssta export --format grid --headings 8` writes the same costs, one 8-bit PNG per heading.
    cli("export", "--map", yard_map, "--format", "grid", "--headings", 8, "--out", tmp_path / "g")
    for k, deg in enumerate(grid["headings_deg"]):
        png = np.round(matplotlib.image.imread(tmp_path / f"g_cost_heading_{deg:g}.png") * 255).astype(np.int32)
        want = np.where(np.isnan(stack[:, :, k]), 255, np.round(np.nan_to_num(stack[:, :, k]) * 254)).astype(np.int32)
        assert np.abs(png - want).max() <= 1, deg


def test_project_headings_arguments_name_themselves(the_map):
    with pytest.raises(ValueError, match="headings: must be in 0..360"):
        the_map.project(headings=-1)
    with pytest.raises(ValueError, match="heading_footprint: footprint_width_m"):
        the_map.project(headings=8, heading_footprint=(1.0, 0.0))


def test_project_pixels_equal_point_queries(the_map):
    """Project at the map's resolution is TopSurfaceAt of each pixel centre (row 0 the largest y)."""
    grid = the_map.project(region=(2.0, -2.0, 6.0, 1.0))
    h, w = grid["class"].shape
    x0, y0 = grid["origin"]
    r = grid["resolution_m"]
    v, u = np.mgrid[0:h, 0:w]
    centres = np.column_stack([(x0 + (u + 0.5) * r).ravel(), (y0 + (h - 1 - v + 0.5) * r).ravel()])
    rows = the_map.query(centres)
    np.testing.assert_array_equal(grid["class"].ravel(), rows["class"])
    np.testing.assert_allclose(grid["cost"].ravel(), rows["cost"], atol=1e-6, equal_nan=True)
    assert grid["cost"].dtype == np.float32 and grid["class"].dtype == np.uint8


def test_metadata_names_the_map_and_its_vehicle(the_map, yard_map, cli):
    meta = the_map.metadata
    assert meta["file"] == str(yard_map)
    assert meta["sequences"] == ["yard"]
    assert meta["frames_inserted"] == 6
    assert meta["resolution_m"] == the_map.resolution_m == 0.1
    if ssta.MAP_ONLY:  # no ssta.Config: the map holds the shipped vehicle, as `ssta config` prints it
        config = cli("config").stdout
        vehicle = config[config.index("\nvehicle:"):]
        assert f"\n  max_slope_deg: {meta['vehicle']['max_slope_deg']:g} " in vehicle, vehicle
    else:
        assert meta["vehicle"] == ssta.Config().vehicle.to_dict()
    assert meta["software_version"] == ssta.__version__
    assert meta["sensor_path"].shape[1] == 3 and len(meta["sensor_path"]) >= 2
    assert meta["refined_mount"] is None


# ----------------------------------------------------------------------------------------------
# Errors: the argument or file at fault is named; the library's are the command line's.

def test_missing_map_is_file_not_found_naming_it(tmp_path):
    missing = tmp_path / "nowhere.ot"
    with pytest.raises(FileNotFoundError) as e:
        ssta.Map.open(missing)
    assert e.value.filename == str(missing)
    assert str(missing) in str(e.value)


def test_corrupt_map_is_ssta_error_with_the_cli_message(tmp_path):
    corrupt = tmp_path / "corrupt.ot"
    corrupt.write_bytes(b"# Octomap OcTree binary file\nnot a map\n")
    with pytest.raises(ssta.Error) as e:
        ssta.Map.open(corrupt)
    assert isinstance(e.value, ValueError)
    assert str(e.value) == cli_error("query", "--map", corrupt, "--at", "1,1")
    assert str(corrupt) in str(e.value)


@pytest.mark.parametrize("points,message", [
    (np.zeros((3, 4)), "points: expected shape (N, 2 or 3) with N >= 1, got (3, 4)"),
    (np.zeros(2), "points: expected shape (N, 2 or 3) with N >= 1, got (2,)"),
    (np.zeros((0, 2)), "points: expected shape (N, 2 or 3) with N >= 1, got (0, 2)"),
    (np.array([["a", "b"]]), "points: expected real numbers (float64), got dtype <U1"),
    (np.zeros((2, 2), dtype=complex), "points: expected real numbers (float64), got dtype complex128"),
    (np.array([[1.0, 2.0], [3.0, 4.0], [np.nan, 1.0]]), "points: row 2 holds NaN or infinity"),
    (np.array([[1.0, np.inf]]), "points: row 0 holds NaN or infinity"),
])
def test_bad_points_raise_value_error_naming_them(the_map, points, message):
    with pytest.raises(ValueError) as e:
        the_map.query(points)
    assert str(e.value) == message
    assert not isinstance(e.value, ssta.Error)  # an argument's fault, not the library's


def test_bad_query_arguments_name_themselves(the_map):
    with pytest.raises(ValueError, match=r"^points: as_exported answers \(x, y\) points"):
        the_map.query(np.zeros((1, 3)), as_exported=True)
    with pytest.raises(ValueError, match=r"^fill_holes: must be in 0\.\.8"):
        the_map.query(np.zeros((1, 2)), as_exported=True, fill_holes=9)
    with pytest.raises(ValueError, match=r"^local_ground_radius_m: must be a finite number >= 0"):
        the_map.query(np.zeros((1, 2)), as_exported=True, local_ground_radius_m=-1)
    with pytest.raises(ValueError, match=r"^poses: expected shape \(N, 3\)"):
        the_map.footprints(np.zeros((2, 2)), 1.0, 1.0)
    with pytest.raises(ValueError, match=r"^poses: row 1 holds NaN"):
        the_map.footprints(np.array([[1.0, 1.0, 0.0], [1.0, np.nan, 0.0]]), 1.0, 1.0)
    with pytest.raises(ValueError, match=r"^length_m: must be a finite number >= 0"):
        the_map.footprints(np.zeros((1, 3)), -1.0, 1.0)
    with pytest.raises(ValueError, match=r"^width_m: must be a finite number >= 0"):
        the_map.path(np.zeros((2, 2)), float("nan"))
    with pytest.raises(ValueError, match=r"^vertices: row 0 holds NaN"):
        the_map.path(np.array([[np.nan, 0.0], [1.0, 1.0]]), 0.5)
    with pytest.raises(ValueError, match=r"^region: expected four finite numbers"):
        the_map.project(region=(1.0, 1.0, 0.0, 2.0))
    with pytest.raises(ValueError, match=r"^resolution_m: must be a finite number > 0"):
        the_map.project(resolution_m=0.0)
    with pytest.raises(ValueError, match=r"^path: expected a path \(str or os.PathLike\), got int"):
        ssta.Map.open(3)


def test_library_limits_name_the_argument_and_row(the_map, yard_map):
    # A footprint over more than 10^7 columns: the CLI names its option, the binding the row.
    with pytest.raises(ssta.Error) as e:
        the_map.footprints(np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 0.0]]), 1e4, 1e4)
    cli = cli_error("query", "--map", yard_map, "--footprint", "0,0,0,1e4,1e4")
    assert str(e.value) == "poses[0]: " + cli.split(": ", 1)[1]


# ----------------------------------------------------------------------------------------------
# Threads

def test_concurrent_queries_give_the_same_answers(the_map, points):
    expected = the_map.query(points)
    with ThreadPoolExecutor(max_workers=4) as pool:
        results = list(pool.map(lambda _: the_map.query(points), range(8)))
    for rows in results:
        assert_structured_equal(rows, expected)


def test_query_releases_the_gil(the_map):
    """While one thread runs a long query, another runs Python: the query holds no GIL.

    No timing: with a switch interval far longer than the test, a thread holding the GIL keeps
    it until it lets go of its own accord. The worker holds it up to the query; the main thread,
    woken meanwhile, can run only if the query lets go. It then counts to a fixed number and
    blocks, handing the GIL back. The worker, once the query returned, reads the count: the
    whole count if the GIL was released, 0 if it was held. Up to five queries, so that a main
    thread the OS did not schedule during one query does not fail the test."""
    x0, y0, _, x1, y1, _ = the_map.bounds
    big = np.column_stack([np.linspace(x0, x1, 500_000), np.linspace(y0, y1, 500_000)])
    target = 1000
    count = 0
    counted = threading.Event()
    started = threading.Event()
    finished = threading.Event()
    seen = []

    def worker():
        started.set()  # wakes the main thread, which then waits for the GIL
        for _ in range(5):
            the_map.query(big)
            if counted.is_set():
                break
        seen.append(count)
        finished.set()

    interval = sys.getswitchinterval()
    sys.setswitchinterval(1000.0)
    try:
        thread = threading.Thread(target=worker)
        thread.start()
        assert started.wait(timeout=600)
        while count < target:
            count += 1
        counted.set()
        assert finished.wait(timeout=600)  # blocks: the worker takes the GIL back
        thread.join()
    finally:
        sys.setswitchinterval(interval)
    # Held, the GIL would have kept the main thread from counting until every query returned.
    assert seen == [target], "the main thread did not run during the queries: the query holds the GIL"


def test_diff_equals_cli(the_map, yard, yard_map, cli, tmp_path):
    """Map.diff against `ssta diff-maps` on the yard's map and a map of its first 3 frames."""
    part = tmp_path / "part.ot"
    cli("build-map", "--sequence", yard, "--map", part, "--max-frames", 3, "-q")
    if ssta.MAP_ONLY:  # the picture needs OpenCV: a map-only module computes the diff but writes nothing
        with pytest.raises(ValueError, match="^out: writing the diff's picture needs the full ssta build"):
            the_map.diff(ssta.Map.open(part), out=tmp_path / "py")
        assert not (tmp_path / "py").exists()
        d = the_map.diff(ssta.Map.open(part))
    else:
        d = the_map.diff(ssta.Map.open(part), out=tmp_path / "py")
    report = cli("diff-maps", yard_map, part, "--out", tmp_path / "cli").stdout
    for name, count in d["counts"].items():
        assert f"  {name}: {count}\n" in report, (name, report)
    assert d["counts"]["no_longer_seen"] > 0  # the later frames saw farther
    if not ssta.MAP_ONLY:
        assert (tmp_path / "py" / "diff.csv").read_text() == (tmp_path / "cli" / "diff.csv").read_text()
    rows = (tmp_path / "cli" / "diff.csv").read_text().splitlines()[1:]
    assert len(rows) == int(np.sum(d["change"] >= 2))  # every change but none and unchanged
    assert d["change"].shape == d["class_a"].shape == d["confidence_b"].shape
    assert np.all(d["change"][(d["class_a"] == d["class_b"]) & (d["class_a"] >= 1) & (d["class_a"] <= 3)] == 1)
