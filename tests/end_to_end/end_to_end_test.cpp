// End to end on rendered sequences with exact ground truth: synth -> classify / build-map ->
// export -> eval. These pin the project's measured accuracy so that a change that loses it
// fails; the figures and the issue targets are in docs/accuracy.md.

#include <gtest/gtest.h>

#include "ssta/eval/grid_evaluator.h"
#include "ssta/eval/label_evaluator.h"
#include "ssta/mapping/map_export.h"
#include "ssta/pipeline/map_builder.h"
#include "ssta/pipeline/sequence_classifier.h"
#include "ssta/synth/sequence_synthesizer.h"
#include "ssta/pipeline/config.h"
#include "ssta_test_paths.h"
#include "temp_dir.h"

namespace ssta {
namespace {

synth::SynthOptions Yard(int frames) {
  synth::SynthOptions o;
  o.scene = "yard";
  o.frames = frames;
  o.seed = 1;
  o.render.max_label_range_m = 12.0;
  return o;
}

synth::SynthOptions Hills(int frames) {
  synth::SynthOptions o = Yard(frames);
  o.scene = "hills";
  return o;
}

synth::SynthOptions Dropoff(int frames) {
  synth::SynthOptions o = Yard(frames);
  o.scene = "dropoff";
  return o;
}

synth::SynthOptions Forest(int frames) {
  synth::SynthOptions o = Yard(frames);
  o.scene = "forest";
  return o;
}

// Classifies every `every`-th frame and scores those frames.
ConfusionMatrix ClassifyAndScore(const std::string& seq_dir, const std::string& out_dir,
                                 const Config& config = Config{}, int every = 1) {
  const Sequence seq = Sequence::Open(seq_dir);
  ClassifyOptions options;
  options.out_dir = out_dir;
  options.frames.every = every;
  ClassifySequence(seq, config, options);
  LabelEvalOptions eval;  // the frames not classified are left out; with every frame, none is
  if (every > 1) eval.missing_prediction = MissingPrediction::kSkip;
  return EvaluateLabelFolders(out_dir, seq_dir, eval).total;
}

ConfusionMatrix MapGridScore(const std::string& seq_dir, const Config& config, const testing::TempDir& dir) {
  BuildMapOptions options;
  options.map_path = dir / "m.ot";
  BuildMap(Sequence::Open(seq_dir), "yard", config, options);
  ExportGrid(TraversabilityMap::Load(options.map_path), dir / "grid");
  return EvaluateExportedGrid(dir / "grid", seq_dir).matrix;
}

TEST(EndToEnd, YardClassifiedWithSgbm) {
  testing::TempDir dir;
  synth::WriteSyntheticSequence(Yard(10), dir / "seq");
  const ConfusionMatrix m = ClassifyAndScore(dir / "seq", dir / "out");
  RecordProperty("accuracy", std::to_string(m.Accuracy()));
  RecordProperty("mean_iou", std::to_string(m.MeanIou()));
  // Measured 0.965 / 0.754 on 10 frames (docs/accuracy.md); the issue's target is 0.90 / 0.75,
  // held here. Without the face test, the fragment planes and the consensus fill
  // (analysis.face_window_px, fragment_tolerance_px, undecided_fill_radius_px: 0) it was
  // 0.936 / 0.607.
  EXPECT_GT(m.Accuracy(), 0.95);
  EXPECT_GT(m.MeanIou(), 0.75);
  EXPECT_GT(m.Coverage(), 0.97);
}

TEST(EndToEnd, HillsGroundBeyondARiseIsNotAStep) {
  // On the rendered hills the ground beyond a rise or the ditch stands 0.3-2 m off each frame's
  // dominant plane: eq. 5 calls it a step. The shipped step reference (reachable_large) reaches
  // those large surfaces from the ground without a jump. Measured on every 2nd of 30 frames
  // (docs/accuracy.md): traversable pixels called non-traversable 56.7 k -> 33.3 k, accuracy
  // 0.752 -> 0.763.
  testing::TempDir dir;
  synth::WriteSyntheticSequence(Hills(30), dir / "seq");
  Config eq5;
  eq5.analysis.step_reference = StepReference::kDominantPlane;
  const ConfusionMatrix before = ClassifyAndScore(dir / "seq", dir / "eq5", eq5, 2);
  const ConfusionMatrix after = ClassifyAndScore(dir / "seq", dir / "shipped", Config{}, 2);
  const int trav = static_cast<int>(TravClass::kTraversable), non = static_cast<int>(TravClass::kNonTraversable);
  RecordProperty("traversable_called_non_before", std::to_string(before.Count(trav, non)));
  RecordProperty("traversable_called_non_after", std::to_string(after.Count(trav, non)));
  EXPECT_LT(after.Count(trav, non), 0.75 * before.Count(trav, non));
  EXPECT_GT(after.Accuracy(), before.Accuracy() + 0.005);
}

TEST(EndToEnd, HillsMapJudgesStepsByTheGroundAroundEachCell) {
  // The map knows the ground around each cell where a frame knows only its dominant plane: the
  // grid export calls a level cell at the height of the traversable ground within 1 m
  // traversable (local_ground_radius_m). Measured on these 20 frames (docs/accuracy.md): grid
  // accuracy 0.355 -> 0.467.
  testing::TempDir dir;
  synth::WriteSyntheticSequence(Hills(20), dir / "seq");
  BuildMapOptions options;
  options.map_path = dir / "m.ot";
  BuildMap(Sequence::Open(dir / "seq"), "hills", Config{}, options);
  const TraversabilityMap map = TraversabilityMap::Load(options.map_path);
  GridExportOptions observed;
  observed.local_ground_radius_m = 0.0;
  ExportGrid(map, dir / "observed", observed);
  ExportGrid(map, dir / "judged");
  const ConfusionMatrix before = EvaluateExportedGrid(dir / "observed", dir / "seq").matrix;
  const ConfusionMatrix after = EvaluateExportedGrid(dir / "judged", dir / "seq").matrix;
  const int trav = static_cast<int>(TravClass::kTraversable), non = static_cast<int>(TravClass::kNonTraversable);
  RecordProperty("accuracy_observed", std::to_string(before.Accuracy()));
  RecordProperty("accuracy_judged", std::to_string(after.Accuracy()));
  EXPECT_LT(after.Count(trav, non), 0.75 * before.Count(trav, non));
  EXPECT_GT(after.Accuracy(), before.Accuracy() + 0.05);
  // Some truly non-traversable cells go (the ditch's edge: its top voxel is the ground's), far
  // fewer than the ground cells won.
  const long won = after.Count(trav, trav) - before.Count(trav, trav);
  const long lost = before.Count(non, non) - after.Count(non, non);
  RecordProperty("traversable_won", std::to_string(won));
  RecordProperty("non_traversable_lost", std::to_string(lost));
  EXPECT_GT(won, 10 * lost);
}

TEST(EndToEnd, ImuCorrectionUndoesRollPitchDriftInTheMap) {
  testing::TempDir dir;
  synth::SynthOptions clean = Yard(20);
  synth::SynthOptions drift = clean;
  // 3 deg/s: with the map's points at sub-pixel disparity, 1.5 deg/s cost the uncorrected map
  // only 0.9 points (0.852 against 0.860; docs/accuracy.md).
  drift.faults.pose_drift_roll_deg_per_s = 3.0;
  drift.faults.pose_drift_pitch_deg_per_s = 3.0;
  synth::WriteSyntheticSequence(clean, dir / "clean");
  synth::WriteSyntheticSequence(drift, dir / "drift");

  const Config corrected;  // gravity.source auto: roll and pitch from the IMU attitude filter
  Config uncorrected;
  uncorrected.gravity.source = GravitySource::kPose;
  testing::TempDir a, b, c;
  const ConfusionMatrix reference = MapGridScore(dir / "clean", corrected, a);
  const ConfusionMatrix with_imu = MapGridScore(dir / "drift", corrected, b);
  const ConfusionMatrix without = MapGridScore(dir / "drift", uncorrected, c);
  RecordProperty("drift_free", std::to_string(reference.Accuracy()));
  RecordProperty("imu_corrected", std::to_string(with_imu.Accuracy()));
  RecordProperty("uncorrected", std::to_string(without.Accuracy()));
  EXPECT_NEAR(with_imu.Accuracy(), reference.Accuracy(), 0.02);
  EXPECT_NEAR(with_imu.MeanIou(), reference.MeanIou(), 0.02);
  // Measured (docs/accuracy.md): accuracy 0.873 / 0.873 / 0.858, mean IoU 0.613 / 0.613 / 0.568.
  // Ground kept from grazing rays holds the uncorrected map's accuracy up (mostly traversable
  // cells); the tilt shows in its obstacles and slopes, which the mean IoU weighs.
  EXPECT_LT(without.Accuracy(), with_imu.Accuracy() - 0.01)
      << "uncorrected " << without.Accuracy() << " vs corrected " << with_imu.Accuracy();
  EXPECT_LT(without.MeanIou(), with_imu.MeanIou() - 0.03)
      << "uncorrected " << without.MeanIou() << " vs corrected " << with_imu.MeanIou();
  // Grid accuracy measured 0.873 on these 20 frames (docs/accuracy.md); the issue's target is 0.90.
  EXPECT_GT(reference.Accuracy(), 0.845);
}

TEST(EndToEnd, DropOffAndForestMapsReachTheIssuesAccuracy) {
  // Issue 4: the exported grid scored against the rendered truth reaches 0.90. Measured on 20
  // frames, seed 1 (docs/accuracy.md): drop-off 0.955, forest 0.920 (seeds 2 and 3: 0.919 /
  // 0.954 and 0.902 / 0.939). The yard (0.876 on 30 frames) and the hills (0.746) do not reach
  // it; docs/accuracy.md says where and why. Coverage is asserted too: an empty map would score
  // no wrong cell it saw.
  for (const synth::SynthOptions& scene : {Dropoff(20), Forest(20)}) {
    SCOPED_TRACE(scene.scene);
    testing::TempDir seq, out;
    synth::WriteSyntheticSequence(scene, seq / "seq");
    const ConfusionMatrix m = MapGridScore(seq / "seq", Config{}, out);
    RecordProperty(scene.scene + "_accuracy", std::to_string(m.Accuracy()));
    EXPECT_GE(m.Accuracy(), 0.90);
    EXPECT_GT(m.Coverage(), 0.95);
  }
}

TEST(EndToEnd, RealtimeOverlayKeepsTheDropOffMap) {
  // config/realtime.yaml matches at half size and subsamples the normals (about 30 frames/s,
  // docs/performance.md). Half-size matching makes a few drop-off frames call the lower level
  // traversable; the overlay lets rays clear that verdict (map.free_space_keeps_traversable:
  // false). Measured on these 20 frames: shipped 0.955, overlay 0.937, overlay with the
  // verdicts kept 0.769.
  testing::TempDir dir;
  synth::WriteSyntheticSequence(Dropoff(20), dir / "seq");
  const Config realtime = LoadConfig(std::string(SSTA_CONFIG_DIR) + "/realtime.yaml");
  ASSERT_EQ(realtime.stereo.downscale, 2);
  ASSERT_EQ(realtime.normals.subsample, 2);
  Config kept = realtime;
  kept.map.fusion.free_space_keeps_traversable = true;
  testing::TempDir a, b, c;
  const ConfusionMatrix shipped = MapGridScore(dir / "seq", Config{}, a);
  const ConfusionMatrix fast = MapGridScore(dir / "seq", realtime, b);
  const ConfusionMatrix fast_kept = MapGridScore(dir / "seq", kept, c);
  RecordProperty("shipped", std::to_string(shipped.Accuracy()));
  RecordProperty("realtime", std::to_string(fast.Accuracy()));
  RecordProperty("realtime_kept", std::to_string(fast_kept.Accuracy()));
  EXPECT_GT(fast.Accuracy(), shipped.Accuracy() - 0.03);
  EXPECT_GT(fast.MeanIou(), shipped.MeanIou() - 0.03);
  EXPECT_LT(fast_kept.Accuracy(), fast.Accuracy() - 0.10);
}

}  // namespace
}  // namespace ssta
