// Stereo calibration on OpenCV's 13 chessboard pairs (tests/data/opencv-chessboard-stereo), through
// the library and through the built `ssta calibrate-stereo`.

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "cli_runner.h"
#include "ssta/calibration/stereo_calibrator.h"
#include "ssta/io/camera_calibration.h"
#include "ssta/files/file_util.h"
#include "ssta/io/image_io.h"
#include "ssta/io/sequence.h"
#include "ssta/stereo/rectifier.h"
#include "ssta_test_paths.h"
#include "temp_dir.h"

namespace ssta {
namespace {

namespace fs = std::filesystem;
using testing::RunResult;
using testing::RunSsta;
using testing::TempDir;

const std::string kData = std::string(SSTA_TEST_DATA_DIR) + "/opencv-chessboard-stereo";
const char* const kPairNumbers[] = {"01", "02", "03", "04", "05", "06", "07",
                                    "08", "09", "11", "12", "13", "14"};

std::vector<std::string> Images(const std::string& side) {
  std::vector<std::string> paths;
  for (const char* n : kPairNumbers) paths.push_back(kData + "/" + side + n + ".jpg");
  return paths;
}

std::string Quote(const std::string& s) { return "'" + s + "'"; }

/// The standard run of the command on all 13 pairs.
RunResult CalibrateAll(const TempDir& dir, const std::string& extra = "") {
  return RunSsta("calibrate-stereo --left " + Quote(kData + "/left*.jpg") + " --right " +
                 Quote(kData + "/right*.jpg") + " --board 9x6 --square 0.025 --out " +
                 (dir / "rig") + " " + extra);
}

/// The first line of the output that mentions "error".
std::string ErrorLine(const std::string& output) {
  const std::size_t at = output.find("error");
  if (at == std::string::npos) return "";
  const std::size_t begin = output.rfind('\n', at);
  const std::size_t end = output.find('\n', at);
  return output.substr(begin == std::string::npos ? 0 : begin + 1,
                       end == std::string::npos ? std::string::npos : end - begin - 1);
}

TEST(StereoCalibratorOptions, MessagesStartWithTheOptionName) {
  std::string error;
  StereoCalibratorOptions o;
  EXPECT_TRUE(o.IsValid(&error)) << error;
  o.square_m = 0.0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error.rfind("square:", 0), 0u) << error;
  o = StereoCalibratorOptions{};
  o.board_cols = o.board_rows = 7;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error.rfind("board:", 0), 0u) << error;
  o = StereoCalibratorOptions{};
  o.min_pairs = 2;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error.rfind("min-pairs:", 0), 0u) << error;
  o = StereoCalibratorOptions{};
  o.body_T_cam0.linear() *= 2.0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error.rfind("body-T-cam0:", 0), 0u) << error;
}

TEST(StereoCalibrator, ExpandGlobSortsAndPairsByName) {
  const std::vector<std::string> left = ExpandGlob(kData + "/left*.jpg");
  ASSERT_EQ(left.size(), 13u);
  EXPECT_EQ(fs::path(left.front()).filename(), "left01.jpg");
  EXPECT_EQ(fs::path(left.back()).filename(), "left14.jpg");
  EXPECT_TRUE(std::is_sorted(left.begin(), left.end()));
  EXPECT_TRUE(ExpandGlob(kData + "/nothing*.jpg").empty());
}

// The reference (left_intrinsics.yml) was solved by OpenCV's calibration sample with a fixed
// aspect ratio (fx = fy) and five distortion coefficients (k3 = 0.238); ours has fx and fy
// free and k3 = 0 because the ASL format holds k1, k2, p1, p2 only. Without k3 the focal length
// absorbs part of the radial profile, so the two differ by more than their noise: measured
// 533.8 px against 535.9 (0.4 %), principal point within 0.6 px. Tolerance: 1 % on the focal
// lengths (5.4 px) and 2 px on the principal point, twice the model difference; a wrong square
// count, a swapped image set or a failed distortion fit moves them far more.
TEST(StereoCalibrator, LeftIntrinsicsAgreeWithOpenCvReference) {
  TempDir dir;
  const RunResult r = CalibrateAll(dir);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  cv::FileStorage reference(kData + "/left_intrinsics.yml", cv::FileStorage::READ);
  ASSERT_TRUE(reference.isOpened());
  cv::Mat k;
  reference["camera_matrix"] >> k;
  ASSERT_EQ(k.rows, 3);
  const CameraCalibration left = LoadCameraCalibration(dir / "rig/cam0/sensor.yaml");
  const double f_ref = k.at<double>(0, 0);
  std::printf("left intrinsics: fu %.2f fv %.2f cu %.2f cv %.2f; reference f %.2f cu %.2f cv %.2f\n",
              left.fu, left.fv, left.cu, left.cv, f_ref, k.at<double>(0, 2), k.at<double>(1, 2));
  EXPECT_NEAR(left.fu, f_ref, 0.01 * f_ref);
  EXPECT_NEAR(left.fv, k.at<double>(1, 1), 0.01 * f_ref);
  EXPECT_NEAR(left.cu, k.at<double>(0, 2), 2.0);
  EXPECT_NEAR(left.cv, k.at<double>(1, 2), 2.0);
  EXPECT_EQ(left.width, 640);
  EXPECT_EQ(left.height, 480);
}

TEST(StereoCalibrator, StereoRmsUnderOnePixelWithFullCoverageFigures) {
  const StereoCalibrator calibrator{StereoCalibratorOptions{}};
  const StereoCalibrationSummary s = calibrator.Calibrate(Images("left"), Images("right"));
  std::printf("%s", s.BriefReport().c_str());
  EXPECT_EQ(s.pairs_used, 13);
  EXPECT_LT(s.stereo_rms_px, 1.0);
  EXPECT_LT(s.left_mono_rms_px, 1.0);
  EXPECT_LT(s.right_mono_rms_px, 1.0);
  // The stereo solve has fewer free board poses than the two mono solves, never a better fit.
  EXPECT_GE(s.stereo_rms_px, std::min(s.left_mono_rms_px, s.right_mono_rms_px) - 1e-6);
  EXPECT_GT(s.left_coverage, 0.3);
  EXPECT_LE(s.left_coverage, 1.0);
  EXPECT_GT(s.right_coverage, 0.3);
  // cam1 sits to the right of cam0 (+x), a few squares away, with little rotation.
  const Eigen::Vector3d t = s.cam0_T_cam1.translation();
  EXPECT_GT(t.x(), 0.0);
  EXPECT_GT(std::abs(t.x()), 0.9 * s.baseline_m);
  EXPECT_NEAR(s.baseline_m, t.norm(), 1e-12);
  EXPECT_GT(s.baseline_m, 0.02);
  EXPECT_LT(s.baseline_m, 0.2);
  const std::string json = s.ToJson();
  EXPECT_NE(json.find("\"baseline_m\""), std::string::npos);
  EXPECT_NE(json.find("\"stereo\""), std::string::npos);
}

// The written files are read back as a sequence (cam0/cam1 data.csv added around them) and the
// pairs rectified with the project's Rectifier; corresponding chessboard corners, detected
// again in the rectified images, must lie on the same row.
TEST(StereoCalibrator, WrittenFilesLoadAsSequenceAndRectifyOntoTheSameRows) {
  TempDir dir;
  const RunResult r = CalibrateAll(dir);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string rig = dir / "rig";
  EXPECT_TRUE(fs::exists(rig + "/rectified_pair.png"));
  EXPECT_TRUE(fs::exists(rig + "/calibration_report.json"));
  for (const std::string cam : {"cam0", "cam1"}) {
    fs::create_directories(rig + "/" + cam + "/data");
    std::ofstream csv(rig + "/" + cam + "/data.csv");
    csv << "#timestamp [ns],filename\n";
    const std::vector<std::string> images = Images(cam == "cam0" ? "left" : "right");
    for (std::size_t i = 0; i < images.size(); ++i) {
      const std::string name = std::to_string(1000000000 * (i + 1)) + ".jpg";
      fs::copy_file(images[i], rig + "/" + cam + "/data/" + name);
      csv << 1000000000 * (i + 1) << "," << name << "\n";
    }
  }
  const Sequence sequence = Sequence::Open(rig);
  ASSERT_EQ(sequence.frames().size(), 13u);
  const Rectifier rectifier(sequence.calibration(), RectifierOptions{});
  ASSERT_FALSE(rectifier.passes_through());

  double sum_dv = 0.0, max_dv = 0.0;
  int corners = 0, pairs = 0;
  for (const StereoFrame& frame : sequence.frames()) {
    RectifiedPair pair = rectifier.Rectify(ReadGreyImage(frame.left_path), ReadGreyImage(frame.right_path));
    const cv::Mat left(pair.left.height(), pair.left.width(), CV_8UC1, pair.left.data());
    const cv::Mat right(pair.right.height(), pair.right.width(), CV_8UC1, pair.right.data());
    std::vector<cv::Point2f> cl, cr;
    if (!cv::findChessboardCorners(left, {9, 6}, cl) || !cv::findChessboardCorners(right, {9, 6}, cr)) continue;
    const cv::TermCriteria stop(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 40, 0.001);
    cv::cornerSubPix(left, cl, {5, 5}, {-1, -1}, stop);
    cv::cornerSubPix(right, cr, {5, 5}, {-1, -1}, stop);
    if ((cl.back() - cl.front()).dot(cr.back() - cr.front()) < 0) std::reverse(cr.begin(), cr.end());
    for (std::size_t i = 0; i < cl.size(); ++i) {
      // cam1 lies to the right, so a point in front has a positive disparity u_left - u_right.
      EXPECT_GT(cl[i].x - cr[i].x, 0.0f);
      const double dv = std::abs(cl[i].y - cr[i].y);
      sum_dv += dv;
      max_dv = std::max(max_dv, dv);
      ++corners;
    }
    ++pairs;
  }
  ASSERT_GE(pairs, 10) << "the board should be found again in most rectified pairs";
  const double mean_dv = sum_dv / corners;
  std::printf("epipolar error after rectification: mean %.3f px, max %.3f px over %d corners in %d pairs\n",
              mean_dv, max_dv, corners, pairs);
  EXPECT_LT(mean_dv, 1.0);
  const std::string json = ReadTextFile(rig + "/calibration_report.json");
  EXPECT_NE(json.find("\"mean_abs_dv_px\""), std::string::npos);
}

TEST(StereoCalibratorCli, ConfigRectificationIsWhatTheCheckUses) {
  // With alpha 0 cv::stereoRectify zooms in until every rectified pixel has a source pixel: the
  // common area is the whole 640x480 image and the focal length grows. The report must give the
  // geometry of a Rectifier built with those options from the written files, not the default's.
  TempDir dir;
  std::ofstream(dir / "alpha0.yaml") << "rectification:\n  alpha: 0\n";
  const RunResult r = CalibrateAll(dir, "--config " + (dir / "alpha0.yaml"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string rig = dir / "rig";
  const StereoCalibration written = LoadStereoCalibration(rig + "/cam0/sensor.yaml", rig + "/cam1/sensor.yaml");
  RectifierOptions alpha0;
  alpha0.alpha = 0.0;
  const RectifiedGeometry zoomed = Rectifier(written, alpha0).geometry();
  const RectifiedGeometry shipped = Rectifier(written, RectifierOptions{}).geometry();
  EXPECT_EQ(zoomed.crop_width, 640);
  EXPECT_EQ(zoomed.crop_height, 480);
  EXPECT_GT(zoomed.f, shipped.f * 1.1);
  const std::string json = ReadTextFile(rig + "/calibration_report.json");
  const std::size_t f_at = json.find("\"rectified_f_px\": ");
  ASSERT_NE(f_at, std::string::npos) << json;
  EXPECT_NEAR(std::stod(json.substr(f_at + 18)), zoomed.f, 1e-6);
  EXPECT_NE(json.find("\"common_area\": [640, 480]"), std::string::npos) << json;

  // A bad value is one error naming the file and key, before any calibration is written.
  std::ofstream(dir / "bad.yaml") << "rectification:\n  alpha: 2\n";
  TempDir other;
  const RunResult bad = CalibrateAll(other, "--config " + (dir / "bad.yaml"));
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(ErrorLine(bad.output).find("bad.yaml: rectification.alpha: must be a number in [0, 1]"), std::string::npos)
      << bad.output;
  EXPECT_FALSE(fs::exists(other / "rig"));
}

TEST(StereoCalibrator, BodyTransformPlacesCam0AndComposesCam1) {
  TempDir dir;
  // A forward-looking camera on a body (x forward, z up), 0.2 m ahead, 0.5 m up.
  const std::string body_T_cam0 = "0,0,1,0.2,-1,0,0,0,0,-1,0,0.5,0,0,0,1";
  RunResult r = CalibrateAll(dir, "--quiet --body-T-cam0 " + body_T_cam0);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const StereoCalibration placed = LoadStereoCalibration(dir / "rig/cam0/sensor.yaml", dir / "rig/cam1/sensor.yaml");
  Eigen::Matrix4d expected;
  expected << 0, 0, 1, 0.2, -1, 0, 0, 0, 0, -1, 0, 0.5, 0, 0, 0, 1;
  EXPECT_TRUE(placed.left.body_T_camera.matrix().isApprox(expected, 1e-12));

  // The same rig with identity: cam0_T_cam1 must not depend on where the body puts cam0.
  TempDir plain;
  r = CalibrateAll(plain, "--quiet");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const StereoCalibration identity = LoadStereoCalibration(plain / "rig/cam0/sensor.yaml", plain / "rig/cam1/sensor.yaml");
  EXPECT_TRUE(identity.left.body_T_camera.matrix().isIdentity(1e-15));
  EXPECT_TRUE(placed.LeftTRight().matrix().isApprox(identity.right.body_T_camera.matrix(), 1e-9));
  EXPECT_TRUE(placed.right.body_T_camera.matrix().isApprox(expected * identity.right.body_T_camera.matrix(), 1e-9));

  // The same transform from YAML: a T_BS block (as in sensor.yaml) through the command, and a
  // top-level data list through the library.
  WriteTextAtomically(dir / "body.yaml", "T_BS:\n  rows: 4\n  cols: 4\n  data: [" + body_T_cam0 + "]\n");
  TempDir from_file;
  r = CalibrateAll(from_file, "--quiet --body-T-cam0 " + (dir / "body.yaml"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(LoadCameraCalibration(from_file / "rig/cam0/sensor.yaml").body_T_camera.matrix().isApprox(expected, 1e-12));
  WriteTextAtomically(dir / "flat.yaml", "data: [" + body_T_cam0 + "]\n");
  EXPECT_TRUE(LoadBodyTransform(dir / "flat.yaml").matrix().isApprox(expected, 1e-12));
  WriteTextAtomically(dir / "bad.yaml", "T_BS:\n  data: [2,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]\n");
  try {
    LoadBodyTransform(dir / "bad.yaml");
    ADD_FAILURE() << "a scaled rotation must be rejected";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.yaml: T_BS.data: rotation part is not orthonormal"), std::string::npos) << e.what();
  }
}

TEST(StereoCalibrator, PairWithoutBoardIsSkippedWithAReason) {
  TempDir dir;
  const std::string blank = dir / "blank.png";
  ASSERT_TRUE(cv::imwrite(blank, cv::Mat(480, 640, CV_8UC1, cv::Scalar(128))));
  std::vector<std::string> left = Images("left"), right = Images("right");
  left.resize(7);
  right.resize(7);
  right[2] = blank;
  left[5] = blank;
  const StereoCalibrationSummary s = StereoCalibrator(StereoCalibratorOptions{}).Calibrate(left, right);
  EXPECT_EQ(s.pairs_used, 5);
  EXPECT_TRUE(s.pairs[2].board_in_left);
  EXPECT_FALSE(s.pairs[2].board_in_right);
  EXPECT_EQ(s.pairs[2].skip_reason, "board not found in the right image");
  EXPECT_EQ(s.pairs[5].skip_reason, "board not found in the left image");
  EXPECT_TRUE(std::isnan(s.pairs[2].left_stereo_rms_px));
  EXPECT_TRUE(s.pairs[0].used());
  EXPECT_LT(s.stereo_rms_px, 1.0);
  const std::string report = s.BriefReport();
  EXPECT_NE(report.find("skipped: board not found in the right image"), std::string::npos) << report;
  EXPECT_NE(report.find("pairs used: 5 of 7"), std::string::npos) << report;
}

// Pair 5 gets the right image of pair 6: both views show a board, but no rig explains them.
TEST(StereoCalibrator, DropOutliersRemovesAMispairedImage) {
  std::vector<std::string> right = Images("right");
  right[4] = right[5];
  StereoCalibratorOptions options;
  const StereoCalibrationSummary flagged = StereoCalibrator(options).Calibrate(Images("left"), right);
  EXPECT_TRUE(flagged.pairs[4].outlier);
  EXPECT_FALSE(flagged.pairs[4].dropped);
  EXPECT_EQ(flagged.pairs_used, 13);
  // The bad pair drags every pair's error up, yet only it is flagged.
  for (std::size_t i = 0; i < flagged.pairs.size(); ++i) {
    if (i != 4) {
      EXPECT_FALSE(flagged.pairs[i].outlier) << "pair " << i + 1;
    }
  }
  EXPECT_GT(flagged.stereo_rms_px, 1.0);
  EXPECT_NE(flagged.BriefReport().find("WARNING: the stereo RMS error is above"), std::string::npos);

  options.drop_outliers = true;
  const StereoCalibrationSummary dropped = StereoCalibrator(options).Calibrate(Images("left"), right);
  std::printf("%s", dropped.BriefReport().c_str());
  EXPECT_TRUE(dropped.pairs[4].outlier);
  EXPECT_TRUE(dropped.pairs[4].dropped);
  EXPECT_FALSE(dropped.pairs[4].used());
  EXPECT_GT(std::max(dropped.pairs[4].left_stereo_rms_px, dropped.pairs[4].right_stereo_rms_px), 5.0);
  EXPECT_EQ(dropped.pairs_used, 12);
  EXPECT_LT(dropped.stereo_rms_px, 1.0);
  EXPECT_LT(dropped.stereo_rms_px, flagged.stereo_rms_px);
  const std::string report = dropped.BriefReport();
  EXPECT_NE(report.find("OUTLIER, dropped"), std::string::npos) << report;
  EXPECT_EQ(report.find("WARNING"), std::string::npos) << report;
}

TEST(StereoCalibratorCli, TooFewBoardsNamesTheImagesAndExitsWithTwo) {
  TempDir dir;
  const RunResult r = RunSsta("calibrate-stereo --left " + Quote(kData + "/left0[12].jpg") + " --right " +
                              Quote(kData + "/right0[12].jpg") + " --square 0.025 --out " + (dir / "rig"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  const std::string line = ErrorLine(r.output);
  EXPECT_NE(line.find("too few boards"), std::string::npos) << r.output;
  EXPECT_NE(line.find("2 of 2 pairs"), std::string::npos) << r.output;
  EXPECT_NE(line.find("left01.jpg/right01.jpg"), std::string::npos) << r.output;
  EXPECT_NE(line.find("--min-pairs"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "rig/cam0/sensor.yaml"));
}

TEST(StereoCalibratorCli, DifferentImageCountsExitWithTwo) {
  TempDir dir;
  const RunResult r = RunSsta("calibrate-stereo --left " + Quote(kData + "/left0*.jpg") + " --right " +
                              Quote(kData + "/right1*.jpg") + " --square 0.025 --out " + (dir / "rig"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  const std::string line = ErrorLine(r.output);
  EXPECT_NE(line.find("--left/--right: 9 left images but 4 right images"), std::string::npos) << r.output;
}

TEST(StereoCalibratorCli, DifferentImageSizesNameTheFileAndExitWithTwo) {
  TempDir dir;
  fs::create_directories(dir / "in");
  for (const char* n : {"01", "03", "04", "05", "06"}) {
    fs::copy_file(kData + "/left" + n + ".jpg", dir / ("in/L" + std::string(n) + ".jpg"));
    fs::copy_file(kData + "/right" + n + ".jpg", dir / ("in/R" + std::string(n) + ".jpg"));
  }
  cv::Mat image = cv::imread(dir / "in/R04.jpg"), small;
  cv::resize(image, small, cv::Size(320, 240));
  ASSERT_TRUE(cv::imwrite(dir / "in/R04.jpg", small));
  const RunResult r = RunSsta("calibrate-stereo --left " + Quote(dir / "in/L*.jpg") + " --right " +
                              Quote(dir / "in/R*.jpg") + " --square 0.025 --out " + (dir / "rig"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  const std::string line = ErrorLine(r.output);
  EXPECT_NE(line.find("R04.jpg: image is 320x240 but"), std::string::npos) << r.output;
  EXPECT_NE(line.find("640x480"), std::string::npos) << r.output;
}

TEST(StereoCalibratorCli, BadArgumentsNameTheOption) {
  TempDir dir;
  RunResult r = RunSsta("calibrate-stereo --left " + Quote(kData + "/nothing*.png") + " --right " +
                        Quote(kData + "/right*.jpg") + " --square 0.025 --out " + (dir / "rig"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(ErrorLine(r.output).find("--left: no file matches"), std::string::npos) << r.output;

  r = RunSsta("calibrate-stereo --left " + Quote(kData + "/left*.jpg") + " --right " +
              Quote(kData + "/right*.jpg") + " --board 9by6 --square 0.025 --out " + (dir / "rig"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(ErrorLine(r.output).find("--board: expected COLSxROWS"), std::string::npos) << r.output;

  r = RunSsta("calibrate-stereo --left " + Quote(kData + "/left*.jpg") + " --right " +
              Quote(kData + "/right*.jpg") + " --square -1 --out " + (dir / "rig"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(ErrorLine(r.output).find("--square:"), std::string::npos) << r.output;

  r = RunSsta("calibrate-stereo --left " + Quote(kData + "/left*.jpg") + " --right " +
              Quote(kData + "/right*.jpg") + " --square 0.025 --body-T-cam0 1,2,3 --out " + (dir / "rig"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(ErrorLine(r.output).find("--body-T-cam0: expected 16 numbers"), std::string::npos) << r.output;
}

TEST(StereoCalibratorCli, SwappedCamerasAreRejected) {
  TempDir dir;
  const RunResult r = RunSsta("calibrate-stereo --left " + Quote(kData + "/right*.jpg") + " --right " +
                              Quote(kData + "/left*.jpg") + " --square 0.025 --out " + (dir / "rig"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(ErrorLine(r.output).find("check that --left holds the left camera"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace ssta
