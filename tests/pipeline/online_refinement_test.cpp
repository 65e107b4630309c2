// build-map with online mount refinement on rendered yards whose sensor.yaml carries an
// injected mount error (pitch +3 deg, roll +1.5 deg; the truth in gt/extrinsics.yaml): the map's
// accuracy against the error-free run, the refined rotation against the truth, the degenerate
// cases (no ground evidence, a window that adds too little to the prior) and --resume.

#include <gtest/gtest.h>

#include <iostream>
#include <memory>
#include <optional>

#include "cli_runner.h"
#include "ssta/eval/grid_evaluator.h"
#include "ssta/files/file_util.h"
#include "ssta/mapping/map_export.h"
#include "ssta/pipeline/map_builder.h"
#include "ssta/synth/sequence_synthesizer.h"
#include "ssta_test_paths.h"
#include "temp_dir.h"

namespace ssta {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

/// A cautious vehicle: semi-traversable from 7 deg, non-traversable from 14 deg. A 3.35 deg
/// mount tilt moves the slope of every surface by up to that much, so the flat ground's noisy
/// per-pixel slopes and the yard's 8 deg ramp cross these thresholds. With the default vehicle
/// (15 / 25 deg) the yard's surfaces stay in their class under such an error and the map's
/// accuracy hardly changes (measured 0.35 error-free vs 0.34 with the error, 320x240).
VehicleOptions CautiousVehicle() {
  VehicleOptions v;
  v.semi_slope_deg = 7.0;
  v.max_slope_deg = 14.0;
  return v;
}

/// Yard with labels to 12 m; `full_size`: the default 640x480 rig, else a quick 320x240 one with
/// the same field of view.
synth::SynthOptions SmallYard(int frames, double pitch_error_deg, double roll_error_deg, bool full_size = false) {
  synth::SynthOptions o;
  o.scene = "yard";
  o.frames = frames;
  o.seed = 1;
  if (!full_size) {
    o.rig.width = 320;
    o.rig.height = 240;
    o.rig.focal_px = 210;
  }
  o.render.max_label_range_m = 12.0;
  o.vehicle = CautiousVehicle();
  o.faults.mount_pitch_error_deg = pitch_error_deg;
  o.faults.mount_roll_error_deg = roll_error_deg;
  return o;
}

Config CautiousConfig(bool online) {
  Config config;
  config.vehicle = CautiousVehicle();
  config.refinement.online = online;
  // The far verdicts a tilt error flips are what these runs score; judged over their smear
  // (map.class_smeared_surface_hazards) most of them are undecided in every run alike.
  config.map.fusion.class_smeared_surface_hazards = false;
  return config;
}

struct MapRun {
  BuildMapSummary summary;
  double accuracy = 0.0;
  double mean_iou = 0.0;
};

MapRun BuildAndScore(const std::string& sequence, const Config& config, const testing::TempDir& dir) {
  BuildMapOptions options;
  options.map_path = dir / "m.ot";
  MapRun run;
  run.summary = BuildMap(Sequence::Open(sequence), "yard", config, options);
  ExportGrid(TraversabilityMap::Load(options.map_path), dir / "grid");
  const auto scores = EvaluateExportedGrid(dir / "grid", sequence);
  run.accuracy = scores.matrix.Accuracy();
  run.mean_iou = scores.matrix.MeanIou();
  return run;
}

double AngleToTruthDeg(const std::string& sequence, const Eigen::Isometry3d& body_T_camera) {
  const Eigen::Matrix3d truth = LoadCameraCalibration(sequence + "/gt/extrinsics.yaml").body_T_camera.linear();
  return Eigen::AngleAxisd(truth.transpose() * body_T_camera.linear()).angle() / kDeg;
}

TEST(OnlineRefinement, MapMatchesTheErrorFreeRunAndWithoutItIsWorse) {
  testing::TempDir dir;
  // Full size: at 320x240 the far range where a tilt error flips classes is too coarse for the
  // difference to stand out of the noise.
  synth::WriteSyntheticSequence(SmallYard(20, 0.0, 0.0, true), dir / "clean");
  synth::WriteSyntheticSequence(SmallYard(20, 3.0, 1.5, true), dir / "faulty");
  testing::TempDir a, b, c, d;
  const MapRun reference = BuildAndScore(dir / "clean", CautiousConfig(false), a);
  const MapRun refined = BuildAndScore(dir / "faulty", CautiousConfig(true), b);
  const MapRun without = BuildAndScore(dir / "faulty", CautiousConfig(false), c);
  const MapRun clean_refined = BuildAndScore(dir / "clean", CautiousConfig(true), d);
  RecordProperty("error_free", std::to_string(reference.accuracy));
  RecordProperty("refined", std::to_string(refined.accuracy));
  RecordProperty("unrefined", std::to_string(without.accuracy));
  RecordProperty("error_free_refined", std::to_string(clean_refined.accuracy));
  std::cout << "map accuracy: error-free " << reference.accuracy << ", mount error refined online "
            << refined.accuracy << ", not refined " << without.accuracy << ", error-free refined "
            << clean_refined.accuracy << "\nmean IoU: " << reference.mean_iou << ", " << refined.mean_iou << ", "
            << without.mean_iou << ", " << clean_refined.mean_iou << "\n"
            << refined.summary.refinement->BriefReport();

  // Measured (640x480, 20 frames) accuracy 0.718 error-free, 0.719 refined, 0.709 not refined;
  // mean IoU 0.434, 0.438, 0.422. The refined run's mean IoU moves by about 0.01 with changes
  // elsewhere (segmentation roughness 8 -> 9 deg: 0.486 -> 0.477, the error-free run 0.489
  // both times), so it is held to 0.015 and to recovering most of what the error costs, which
  // is about 0.01 of either figure.
  EXPECT_NEAR(refined.accuracy, reference.accuracy, 0.01);
  EXPECT_NEAR(refined.mean_iou, reference.mean_iou, 0.015);
  EXPECT_GT(refined.accuracy - without.accuracy, 0.6 * (reference.accuracy - without.accuracy));
  EXPECT_GT(refined.mean_iou - without.mean_iou, 0.6 * (reference.mean_iou - without.mean_iou));
  EXPECT_LT(without.accuracy, reference.accuracy - 0.005);
  EXPECT_LT(without.mean_iou, reference.mean_iou - 0.008);
  EXPECT_NEAR(clean_refined.accuracy, reference.accuracy, 0.01);

  // The mount in use at the end is the truth within 0.25 deg, inside the solve's own 1 sigma of
  // 0.26 deg (measured 0.21 deg, 3.35 deg before; 0.15 deg while the matcher also dropped the
  // bottom 4 rows, where SGBM's disparity leans by 0.08 px from left to right).
  const OnlineRefinementSummary& r = *refined.summary.refinement;
  ASSERT_TRUE(r.last_applied) << r.BriefReport();
  EXPECT_NEAR(AngleToTruthDeg(dir / "faulty", r.body_T_camera_configured), 3.35, 0.05);
  EXPECT_LT(AngleToTruthDeg(dir / "faulty", r.body_T_camera), 0.25) << r.BriefReport();
  EXPECT_NEAR(r.last_applied->pitch_correction_deg, -3.0, 0.3);
  EXPECT_NEAR(r.last_applied->roll_correction_deg, -1.5, 0.3);
  EXPECT_LT(r.last_applied->pitch_sigma_deg, 0.5);
  EXPECT_EQ(r.rejected_total(), 0) << r.BriefReport();
  // The first solve comes when the window holds min_frames frames with evidence; those frames
  // are processed again with the refined mount before they are fused.
  EXPECT_EQ(r.frames_before_first_applied, Config{}.refinement.min_frames);
  EXPECT_EQ(r.frames_reprocessed, r.frames_before_first_applied);
  EXPECT_EQ(refined.summary.frames_used, 20);
  // The error-free sequence needs almost no correction.
  ASSERT_TRUE(clean_refined.summary.refinement->last_applied);
  EXPECT_LT(AngleToTruthDeg(dir / "clean", clean_refined.summary.refinement->body_T_camera), 0.25);
}

/// A short faulty yard for the cases that do not score a map.
class OnlineRefinementShort : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = std::make_unique<testing::TempDir>();
    synth::WriteSyntheticSequence(SmallYard(8, 3.0, 1.5), *dir_ / "faulty");
  }
  static void TearDownTestSuite() { dir_.reset(); }
  static std::string Faulty() { return *dir_ / "faulty"; }

 private:
  static std::unique_ptr<testing::TempDir> dir_;
};
std::unique_ptr<testing::TempDir> OnlineRefinementShort::dir_;

TEST_F(OnlineRefinementShort, FramesWithoutGroundEvidenceKeepTheConfiguredMountAndAreAllFused) {
  testing::TempDir dir;
  Config config = CautiousConfig(true);
  config.refinement.max_range_m = 0.3;  // every ground point is farther: no frame has evidence
  config.refinement.window_frames = 5;  // the warm-up gives up after 5 frames
  BuildMapOptions options;
  options.map_path = dir / "m.ot";
  const BuildMapSummary s = BuildMap(Sequence::Open(Faulty()), "yard", config, options);
  ASSERT_TRUE(s.refinement);
  const OnlineRefinementSummary& r = *s.refinement;
  EXPECT_EQ(s.frames_used, 8);
  EXPECT_EQ(r.frames_offered, 8);
  EXPECT_EQ(r.frames_with_evidence, 0);
  ASSERT_EQ(r.no_evidence.size(), 8u);
  EXPECT_NE(r.no_evidence.front().reason.find("fewer than min_points_per_frame"), std::string::npos)
      << r.no_evidence.front().reason;
  EXPECT_EQ(r.solves, 0);
  EXPECT_FALSE(r.last_applied);
  EXPECT_TRUE(r.body_T_camera.isApprox(Sequence::Open(Faulty()).calibration().left.body_T_camera));
  EXPECT_EQ(r.frames_reprocessed, 5);  // held by the warm-up, then fused with the configured mount
  EXPECT_FALSE(TraversabilityMap::Load(options.map_path).metadata().refined_mount);
  EXPECT_NE(s.BriefReport().find("no solve: fewer frames with ground evidence than min_frames"), std::string::npos)
      << s.BriefReport();
}

TEST_F(OnlineRefinementShort, AWindowThatAddsTooLittleToThePriorIsRejectedAndNotApplied) {
  testing::TempDir dir;
  Config config = CautiousConfig(true);
  config.refinement.min_frames = 3;
  config.refinement.solve_every_frames = 2;
  config.refinement.prior_sigma_deg = 0.02;  // a window of a few frames cannot beat this prior
  BuildMapOptions options;
  options.map_path = dir / "m.ot";
  const BuildMapSummary s = BuildMap(Sequence::Open(Faulty()), "yard", config, options);
  const OnlineRefinementSummary& r = *s.refinement;
  EXPECT_EQ(s.frames_used, 8);
  EXPECT_GE(r.solves, 3);
  EXPECT_EQ(r.applied, 0);
  EXPECT_EQ(r.rejected[1], r.solves) << r.BriefReport();  // all not_better_than_prior
  EXPECT_EQ(r.last_rejection.rfind("not_better_than_prior", 0), 0u) << r.last_rejection;
  EXPECT_TRUE(r.body_T_camera.isApprox(r.body_T_camera_configured));
  EXPECT_NE(s.Json().find("\"not_better_than_prior\": " + std::to_string(r.solves)), std::string::npos) << s.Json();
}

TEST_F(OnlineRefinementShort, CliReportsTheRefinementAndResumeStartsFromTheRecordedMount) {
  testing::TempDir dir;
  const std::string map = dir / "m.ot";
  auto first = testing::RunSsta("build-map --sequence " + Faulty() + " --map " + map + " --refine --json " +
                                (dir / "first.json"));
  ASSERT_EQ(first.exit_code, 0) << first.output;
  EXPECT_NE(first.output.find("online mount refinement: "), std::string::npos) << first.output;
  EXPECT_NE(first.output.find("pitch correction -"), std::string::npos) << first.output;
  const std::string json = ReadTextFile(dir / "first.json");
  for (const char* key : {"\"refinement\": {", "\"applied\": 1", "\"pitch_sigma_deg\"", "\"frames_reprocessed\": 5"}) {
    EXPECT_NE(json.find(key), std::string::npos) << key << "\n" << json;
  }
  const std::optional<RefinedMount> recorded = TraversabilityMap::Load(map).metadata().refined_mount;
  ASSERT_TRUE(recorded);
  const Sequence sequence = Sequence::Open(Faulty());
  EXPECT_TRUE(recorded->configured.isApprox(sequence.calibration().left.body_T_camera, 1e-12));
  EXPECT_LT(AngleToTruthDeg(Faulty(), recorded->refined), 0.5);  // one solve over 5 frames

  // Resumed: no warm-up, the recorded mount from the first frame on.
  BuildMapOptions options;
  options.map_path = map;
  options.resume = true;
  // Another sequence name: a resumed run of the same sequence skips the frames the map holds.
  // The same frames again are allowed as an overlap (they would be refused otherwise).
  options.allow_overlap = true;
  const BuildMapSummary resumed = BuildMap(sequence, "yard-again", CautiousConfig(true), options);
  EXPECT_TRUE(resumed.refinement->body_T_camera_start.isApprox(recorded->refined, 1e-12));
  EXPECT_EQ(resumed.refinement->frames_reprocessed, 0);
  EXPECT_EQ(resumed.frames_used, 8);

  // Without --refine nothing changes: no refinement in the summary, the configured mount.
  const BuildMapSummary plain = BuildMap(sequence, "yard", CautiousConfig(false), options);
  EXPECT_FALSE(plain.refinement);
  EXPECT_EQ(plain.Json().find("refinement"), std::string::npos);
}

TEST(OnlineRefinement, EurocMiniAgreesWithTheStillRecordingsWindows) {
  // The 3 pairs of tests/data (1 s into the recording, the MAV on the floor), the ground
  // referenced to gravity: the mean accelerometer over the recording, in cam0. On the 95-frame
  // recording (scripts/euroc_refine_spread.sh, windows of 10 frames, same gravity) the windows
  // gave pitch +0.785 (std 0.021, range 0.748..0.816) and roll -0.380 (std 0.044, range
  // -0.457..-0.322) deg; these 3 frames measured +0.795 / -0.381. A window of 3 frames from the
  // same recording must land in that spread, widened by 0.1 deg for its fewer frames.
  Config config = LoadConfig(std::string(SSTA_CONFIG_DIR) + "/sensors/euroc.yaml");
  config.gravity.source = GravitySource::kFixed;
  config.gravity.up_camera = Eigen::Vector3d(0.03568, -0.92761, -0.37183);
  config.refinement.online = true;
  config.refinement.ground_reference = GroundReference::kGravity;
  config.refinement.min_frames = 3;
  config.refinement.window_frames = 3;
  testing::TempDir dir;
  BuildMapOptions options;
  options.map_path = dir / "m.ot";
  options.static_platform = true;
  const BuildMapSummary s =
      BuildMap(Sequence::Open(std::string(SSTA_TEST_DATA_DIR) + "/euroc-v1-01-mini"), "euroc", config, options);
  const OnlineRefinementSummary& r = *s.refinement;
  ASSERT_EQ(r.history.size(), 1u) << r.BriefReport();
  ASSERT_EQ(r.history[0].status, RefinementStatus::kDetermined) << r.BriefReport();
  EXPECT_GT(r.history[0].pitch_correction_deg, 0.748 - 0.1) << r.BriefReport();
  EXPECT_LT(r.history[0].pitch_correction_deg, 0.816 + 0.1) << r.BriefReport();
  EXPECT_GT(r.history[0].roll_correction_deg, -0.457 - 0.1) << r.BriefReport();
  EXPECT_LT(r.history[0].roll_correction_deg, -0.322 + 0.1) << r.BriefReport();
  EXPECT_EQ(s.frames_used, 3);
}

}  // namespace
}  // namespace ssta
