// calibrate-mount on rendered sequences: a sensor.yaml with an injected mount error (pitch
// +3 deg, roll +1.5 deg) against the truth in gt/extrinsics.yaml, an error-free sequence, the
// degenerate cases, and the command line's files loaded back.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>

#include "cli_runner.h"
#include "ssta/core/error.h"
#include "ssta/files/file_util.h"
#include "ssta/pipeline/mount_calibration.h"
#include "ssta/synth/sequence_synthesizer.h"
#include "temp_dir.h"

namespace ssta {
namespace {

namespace fs = std::filesystem;
constexpr double kDeg = 3.14159265358979323846 / 180.0;
constexpr int kFrames = 12;

/// Small, quick yard: 320x240 with the default field of view.
synth::SynthOptions SmallYard(double pitch_error_deg, double roll_error_deg) {
  synth::SynthOptions o;
  o.scene = "yard";
  o.frames = kFrames;
  o.seed = 3;
  o.rig.width = 320;
  o.rig.height = 240;
  o.rig.focal_px = 210;
  o.grid_resolution_m = 0.25;
  o.faults.mount_pitch_error_deg = pitch_error_deg;
  o.faults.mount_roll_error_deg = roll_error_deg;
  return o;
}

/// Renders each sequence on first use, once for the whole suite (CTest runs every case in its
/// own process, so a case renders only what it reads).
class MountCalibrationTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { dir_ = std::make_unique<testing::TempDir>(); }
  static void TearDownTestSuite() { dir_.reset(); }
  static std::string Faulty() { return Rendered("faulty", 3.0, 1.5); }
  static std::string Clean() { return Rendered("clean", 0.0, 0.0); }

 private:
  static std::string Rendered(const std::string& name, double pitch_error_deg, double roll_error_deg) {
    const std::string path = *dir_ / name;
    if (!fs::exists(path + "/gt/extrinsics.yaml")) {
      synth::WriteSyntheticSequence(SmallYard(pitch_error_deg, roll_error_deg), path);
    }
    return path;
  }
  static std::unique_ptr<testing::TempDir> dir_;
};
std::unique_ptr<testing::TempDir> MountCalibrationTest::dir_;

double AngleDeg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle() / kDeg;
}

Eigen::Matrix3d TrueRotation(const std::string& sequence) {
  return LoadCameraCalibration(sequence + "/gt/extrinsics.yaml").body_T_camera.linear();
}

TEST_F(MountCalibrationTest, RecoversTheInjectedMountErrorWithinAFifthOfADegree) {
  const Sequence sequence = Sequence::Open(Faulty());
  const Eigen::Matrix3d truth = TrueRotation(Faulty());
  ASSERT_NEAR(AngleDeg(truth, sequence.calibration().left.body_T_camera.linear()), 3.35, 0.05);
  const MountCalibration c = CalibrateMount(sequence, Config{}, MountCalibrationOptions{});
  const MountRefinementResult& r = c.refinement;
  std::cout << c.BriefReport();
  ASSERT_EQ(r.status, RefinementStatus::kDetermined) << r.message;
  const double error_deg = AngleDeg(truth, r.body_T_camera_refined.linear());
  std::cout << "refined vs true cam0 rotation: " << error_deg << " deg\n";
  EXPECT_LT(error_deg, 0.2) << c.BriefReport();
  EXPECT_NEAR(r.pitch_correction_deg, -3.0, 0.25);
  EXPECT_NEAR(r.roll_correction_deg, -1.5, 0.25);
  EXPECT_GT(r.pitch_sigma_deg, 0.0);
  EXPECT_LT(r.pitch_sigma_deg, 0.5 * r.prior_sigma_deg);
  EXPECT_GE(r.frames_used, kFrames - 2);
  // cam1 follows from the rig: the pair's relative pose is unchanged.
  EXPECT_TRUE(c.refined.LeftTRight().isApprox(sequence.calibration().LeftTRight(), 1e-9));
  EXPECT_LT(AngleDeg(truth, c.refined.left.body_T_camera.linear()), 0.2);
}

TEST_F(MountCalibrationTest, ErrorFreeSequenceNeedsNoCorrection) {
  const MountCalibration c = CalibrateMount(Sequence::Open(Clean()), Config{}, MountCalibrationOptions{});
  ASSERT_TRUE(c.refinement.applied()) << c.refinement.message;
  EXPECT_LT(std::abs(c.refinement.pitch_correction_deg), 0.2) << c.BriefReport();
  EXPECT_LT(std::abs(c.refinement.roll_correction_deg), 0.2) << c.BriefReport();
  EXPECT_LT(AngleDeg(TrueRotation(Clean()), c.refined.left.body_T_camera.linear()), 0.2);
  std::cout << "error-free: pitch " << c.refinement.pitch_correction_deg << " deg, roll "
            << c.refinement.roll_correction_deg << " deg\n";
}

// SGBM's one-pass modes aggregate from above only, which pulls the ground's disparity toward the
// smaller disparities of the rows above: a bias e that pitches the ground by about e h / (f b)
// (here 0.8 m high, f 210 px, b 0.12 m: 0.18 deg per 0.1 px). calibrate-mount matches with hh4
// and a sub-pixel refinement instead; the error-free drive then needs almost no correction.
TEST_F(MountCalibrationTest, UnbiasedMatchingLevelsTheErrorFreeGround) {
  const Sequence sequence = Sequence::Open(Clean());
  const MountCalibration unbiased = CalibrateMount(sequence, Config{}, MountCalibrationOptions{});
  MountCalibrationOptions configured;
  configured.refinement.unbiased_matching = false;
  const MountCalibration one_pass = CalibrateMount(sequence, Config{}, configured);
  std::cout << "error-free drive, pitch correction: unbiased " << unbiased.refinement.pitch_correction_deg
            << " deg, as configured (3way) " << one_pass.refinement.pitch_correction_deg << " deg\n";
  EXPECT_NE(unbiased.matching_note.find("hh4 instead of 3way and stereo.subpixel_window_px 7"), std::string::npos)
      << unbiased.matching_note;
  EXPECT_NE(unbiased.BriefReport().find(unbiased.matching_note), std::string::npos);
  EXPECT_NE(unbiased.Json().find("\"matching_note\": \"matched with"), std::string::npos) << unbiased.Json();
  EXPECT_TRUE(one_pass.matching_note.empty()) << one_pass.matching_note;
  EXPECT_LT(std::abs(unbiased.refinement.pitch_correction_deg), 0.1) << unbiased.BriefReport();
  EXPECT_LT(std::abs(unbiased.refinement.roll_correction_deg), 0.1) << unbiased.BriefReport();
  EXPECT_GT(std::abs(one_pass.refinement.pitch_correction_deg), 0.1) << one_pass.BriefReport();
  // What the config already has is kept: a mode that aggregates both ways, a refinement of its
  // own, another matcher; and nothing is matched with the true disparity.
  MountCalibrationOptions few;
  few.frames.max_frames = 6;
  few.refinement.min_frames = 3;
  Config hh;
  hh.stereo.sgbm_mode = SgbmMode::kHh;
  hh.stereo.subpixel_window_px = 5;
  EXPECT_TRUE(CalibrateMount(sequence, hh, few).matching_note.empty());
  Config bm;
  bm.stereo.algorithm = MatcherType::kBlockMatching;
  const std::string bm_note = CalibrateMount(sequence, bm, few).matching_note;
  EXPECT_EQ(bm_note.find("sgbm_mode"), std::string::npos) << bm_note;
  EXPECT_NE(bm_note.find("subpixel_window_px 7"), std::string::npos) << bm_note;
  few.oracle_disparity = true;
  EXPECT_TRUE(CalibrateMount(sequence, Config{}, few).matching_note.empty());
}

TEST_F(MountCalibrationTest, TrueDisparityLeavesTheGroundModelsErrorAlone) {
  MountCalibrationOptions options;
  options.oracle_disparity = true;
  const MountCalibration c = CalibrateMount(Sequence::Open(Faulty()), Config{}, options);
  ASSERT_EQ(c.refinement.status, RefinementStatus::kDetermined) << c.BriefReport();
  EXPECT_LT(AngleDeg(TrueRotation(Faulty()), c.refinement.body_T_camera_refined.linear()), 0.2) << c.BriefReport();
  EXPECT_TRUE(c.skipped.empty()) << c.BriefReport();

  // The oracle reads the truth: without gt/disparity no frame is usable, and the error names
  // the sequence's own truth file.
  const std::string copy = Faulty() + "_without_disparity";
  fs::copy(Faulty(), copy, fs::copy_options::recursive);
  fs::remove_all(copy + "/gt/disparity");
  try {
    CalibrateMount(Sequence::Open(copy), Config{}, options);
    FAIL() << "calibrated without the true disparity";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(copy + "/gt/disparity/"), std::string::npos) << e.what();
  }
}

TEST_F(MountCalibrationTest, NoUsableGroundPlaneIsAnError) {
  MountCalibrationOptions options;
  options.frames.max_frames = 3;
  options.refinement.max_range_m = 0.3;  // every ground point is farther than this
  try {
    CalibrateMount(Sequence::Open(Faulty()), Config{}, options);
    FAIL() << "no error without ground planes";
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("no frame has a usable ground plane"), std::string::npos) << m;
    EXPECT_NE(m.find(Faulty()), std::string::npos) << m;
  }
}

TEST_F(MountCalibrationTest, TooFewFramesAndTightPriorAreReportedAndNotApplied) {
  const Sequence sequence = Sequence::Open(Faulty());
  MountCalibrationOptions few;
  few.frames.max_frames = 2;
  const MountCalibration a = CalibrateMount(sequence, Config{}, few);
  EXPECT_EQ(a.refinement.status, RefinementStatus::kTooFewFrames);
  EXPECT_TRUE(a.refined.left.body_T_camera.isApprox(sequence.calibration().left.body_T_camera));

  MountCalibrationOptions tight;
  tight.frames.max_frames = 6;
  tight.refinement.min_frames = 3;
  tight.refinement.prior_sigma_deg = 0.02;
  const MountCalibration b = CalibrateMount(sequence, Config{}, tight);
  EXPECT_EQ(b.refinement.status, RefinementStatus::kNotBetterThanPrior) << b.refinement.message;
  EXPECT_TRUE(b.refined.left.body_T_camera.isApprox(sequence.calibration().left.body_T_camera));
  EXPECT_TRUE(b.refined.right.body_T_camera.isApprox(sequence.calibration().right.body_T_camera));
}

// A short drive over hills: its 12 frames never reach the ground they see, so the body reference
// stands in for the path reference. The ground 1-8 m ahead tilts from the wheel plane under each
// body the same way in every frame, which no scatter shows: solved, the error-free mount would
// turn by several degrees with a sigma under one. The poses show the body tilting by about a
// degree over the drive, so the ground is not uniform, and the configured mount is kept.
TEST_F(MountCalibrationTest, ShortDriveOverNonUniformGroundKeepsTheMount) {
  testing::TempDir dir;
  synth::SynthOptions hills = SmallYard(0.0, 0.0);
  hills.scene = "hills";
  hills.seed = 1;
  synth::WriteSyntheticSequence(hills, dir / "hills");
  const Sequence sequence = Sequence::Open(dir / "hills");
  const MountCalibration c = CalibrateMount(sequence, Config{}, MountCalibrationOptions{});
  const MountRefinementResult& r = c.refinement;
  std::cout << c.BriefReport();
  EXPECT_LT(c.frames_on_path, MountCalibrationOptions{}.refinement.min_frames);
  EXPECT_NE(c.reference_note.find("the body reference is used"), std::string::npos) << c.reference_note;
  EXPECT_EQ(r.status, RefinementStatus::kTerrainTooRough) << r.message;
  EXPECT_NE(r.message.find("the ground is not uniform"), std::string::npos) << r.message;
  // What the body reference made of this drive: far from the true (configured) mount, yet
  // confident. Had it been applied, the mount would be off by this much.
  EXPECT_GT(std::hypot(r.pitch_correction_deg, r.roll_correction_deg), 1.0) << c.BriefReport();
  EXPECT_LT(std::max(r.pitch_sigma_deg, r.roll_sigma_deg), 1.0) << c.BriefReport();
  EXPECT_TRUE(c.refined.left.body_T_camera.isApprox(sequence.calibration().left.body_T_camera));
  EXPECT_TRUE(c.refined.right.body_T_camera.isApprox(sequence.calibration().right.body_T_camera));
}

TEST_F(MountCalibrationTest, CliWritesSensorFilesThatOpenAsASequence) {
  testing::TempDir dir;
  const std::string report = dir / "report.json";
  auto r = testing::RunSsta("calibrate-mount --sequence " + Faulty() + " --out-dir " + (dir / "rig") + " --report " +
                            report + " -q");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string json = ReadTextFile(report);
  for (const char* key : {"\"status\": \"determined\"", "\"pitch_sigma_deg\"", "\"cam1_T_BS\"", "\"skipped\""}) {
    EXPECT_NE(json.find(key), std::string::npos) << key;
  }

  // A copy of the sequence with the written calibration opens and carries the truth.
  const fs::path copy = dir.path() / "copy";
  fs::copy(Faulty(), copy, fs::copy_options::recursive);
  for (const char* cam : {"cam0", "cam1"}) {
    fs::copy_file(dir.path() / "rig" / cam / "sensor.yaml", copy / cam / "sensor.yaml",
                  fs::copy_options::overwrite_existing);
  }
  const Sequence refined = Sequence::Open(copy.string());
  const Sequence original = Sequence::Open(Faulty());
  EXPECT_EQ(refined.frames().size(), original.frames().size());
  EXPECT_LT(AngleDeg(TrueRotation(Faulty()), refined.calibration().left.body_T_camera.linear()), 0.2);
  EXPECT_TRUE(refined.calibration().LeftTRight().isApprox(original.calibration().LeftTRight(), 1e-9));
  EXPECT_EQ(refined.calibration().left.fu, original.calibration().left.fu);
  EXPECT_EQ(refined.calibration().left.width, original.calibration().left.width);

  // --out FILE puts cam1 beside it.
  r = testing::RunSsta("calibrate-mount --sequence " + Faulty() + " --out " + (dir / "one/cam0_sensor.yaml") + " -q");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const CameraCalibration cam0 = LoadCameraCalibration(dir / "one/cam0_sensor.yaml");
  const CameraCalibration cam1 = LoadCameraCalibration(dir / "one/cam1_sensor.yaml");
  EXPECT_TRUE(cam0.body_T_camera.isApprox(refined.calibration().left.body_T_camera, 1e-9));
  EXPECT_TRUE(cam1.body_T_camera.isApprox(refined.calibration().right.body_T_camera, 1e-9));
}

TEST_F(MountCalibrationTest, CliWritesNothingWhenNotDetermined) {
  testing::TempDir dir;
  auto r = testing::RunSsta("calibrate-mount --sequence " + Faulty() + " --max-frames 2 --out " + (dir / "c0.yaml") +
                            " --report " + (dir / "r.json") + " -q");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("too_few_frames"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "c0.yaml"));
  EXPECT_TRUE(fs::exists(dir / "r.json"));

  r = testing::RunSsta("calibrate-mount --sequence " + Faulty() + " -q");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--out"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace ssta
