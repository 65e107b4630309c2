// End to end on rendered sequences with exact ground truth: synth -> classify / build-map ->
// export -> eval. These pin the project's measured accuracy so that a change that loses it
// fails; the figures are in docs/accuracy.md. Every scene here belongs to the tuning set.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <vector>

#include "ssta/eval/footprint_evaluator.h"
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

// What a planner is told about the truth's footprints (1.0 x 0.6 m, every 0.5 m, four headings)
// by the map MapGridScore left in `dir`, answered as exported: `ssta eval footprints
// --as-exported`.
FootprintEvalSummary FootprintScore(const std::string& seq_dir, const testing::TempDir& dir) {
  const ClassGrid truth = ReadGroundTruthGrid(seq_dir);
  const TraversabilityMap map = TraversabilityMap::Load(dir / "m.ot");
  const FootprintEvalOptions footprint;
  const double reach = 0.5 * std::hypot(footprint.length_m, footprint.width_m);
  const Eigen::Vector2d size(truth.classes.width() * truth.resolution_m, truth.classes.height() * truth.resolution_m);
  const ExportedSurface exported(map, Eigen::AlignedBox2d(truth.origin_m - Eigen::Vector2d::Constant(reach),
                                                          truth.origin_m + size + Eigen::Vector2d::Constant(reach)));
  const auto oracle = [&](const FootprintPose& pose) {
    const FootprintResult r =
        map.QueryFootprint({pose.x_m, pose.y_m, pose.yaw_rad, footprint.length_m, footprint.width_m}, exported);
    return FootprintAnswer{static_cast<std::uint8_t>(r.worst), r.fraction_observed};
  };
  return ScoreFootprints(truth, footprint, oracle, ReadDrivenPath(seq_dir).points);
}

TEST(EndToEnd, YardClassifiedWithSgbm) {
  testing::TempDir dir;
  synth::WriteSyntheticSequence(Yard(10), dir / "seq");
  const ConfusionMatrix m = ClassifyAndScore(dir / "seq", dir / "out");
  RecordProperty("accuracy", std::to_string(m.Accuracy()));
  RecordProperty("mean_iou", std::to_string(m.MeanIou()));
  // Measured 0.923 / 0.479 on these 10 frames (truth to 20 m; docs/accuracy.md).
  EXPECT_GT(m.Accuracy(), 0.91);
  EXPECT_GT(m.MeanIou(), 0.45);
  EXPECT_GT(m.Coverage(), 0.97);
}

TEST(EndToEnd, LocalStepsLeaveLevelGroundOffTheDominantPlaneTraversable) {
  // On the rendered hills the ground beyond a rise or the ditch stands 0.3-2 m off each frame's
  // dominant plane: eq. 5 calls it a step. The shipped local steps (the class rule of
  // docs/interfaces.md, section 3) measure only the jumps within the step radius. Measured on
  // every 2nd of 30 frames: traversable pixels called non-traversable 53.6 k -> 16.0 k.
  testing::TempDir dir;
  synth::WriteSyntheticSequence(Hills(30), dir / "seq");
  Config eq5;
  eq5.analysis.step_reference = StepReference::kDominantPlane;
  const ConfusionMatrix before = ClassifyAndScore(dir / "seq", dir / "eq5", eq5, 2);
  const ConfusionMatrix after = ClassifyAndScore(dir / "seq", dir / "shipped", Config{}, 2);
  const int trav = static_cast<int>(TravClass::kTraversable), non = static_cast<int>(TravClass::kNonTraversable);
  RecordProperty("traversable_called_non_before", std::to_string(before.Count(trav, non)));
  RecordProperty("traversable_called_non_after", std::to_string(after.Count(trav, non)));
  EXPECT_LT(after.Count(trav, non), 0.4 * before.Count(trav, non));
}

TEST(EndToEnd, TheFramesDoNotCallTheDropOffsLipOpenGround) {
  // The rendered drop-off's lower level is hidden below its 0.8 m edge from the first frames:
  // each frame's labels leave the lip band (the ground within step_radius_m of the edge)
  // traversable unless the view over the edge marks it (analysis.hidden_drops). A lip is
  // undecided where the ray over it is gentler than max_slope_deg: no more traversable pixels
  // may turn non-traversable. Measured on every 3rd of 30 frames: truly non-traversable pixels
  // called traversable or semi-traversable 34.3 k -> 26.9 k (the rest: the rings of the small
  // hole and the rocks); traversable ones called non-traversable 1023 either way.
  testing::TempDir dir;
  synth::WriteSyntheticSequence(Dropoff(30), dir / "seq");
  Config off;
  off.analysis.hidden_drops = false;
  const ConfusionMatrix before = ClassifyAndScore(dir / "seq", dir / "off", off, 3);
  const ConfusionMatrix after = ClassifyAndScore(dir / "seq", dir / "shipped", Config{}, 3);
  const int trav = static_cast<int>(TravClass::kTraversable), semi = static_cast<int>(TravClass::kSemiTraversable);
  const int non = static_cast<int>(TravClass::kNonTraversable);
  const auto unsafe = [&](const ConfusionMatrix& m) { return m.Count(non, trav) + m.Count(non, semi); };
  RecordProperty("unsafe_before", std::to_string(unsafe(before)));
  RecordProperty("unsafe_after", std::to_string(unsafe(after)));
  RecordProperty("traversable_called_non_before", std::to_string(before.Count(trav, non)));
  RecordProperty("traversable_called_non_after", std::to_string(after.Count(trav, non)));
  EXPECT_LT(unsafe(after), 0.85 * unsafe(before));
  EXPECT_EQ(after.Count(trav, non), before.Count(trav, non));
}

TEST(EndToEnd, TheMapCallsTheFloorBelowADropOffTraversable) {
  // Level ground is traversable at any height: the lower level of the rendered drop-off, 0.8 m
  // down from x = 6 m. Measured on these 30 frames: 619 of its 619 observed columns within
  // x in [7, 11] m, |y| < 1.5 m are traversable.
  testing::TempDir dir;
  synth::SynthOptions o = Dropoff(30);
  synth::WriteSyntheticSequence(o, dir / "seq");
  BuildMapOptions options;
  options.map_path = dir / "m.ot";
  BuildMap(Sequence::Open(dir / "seq"), "dropoff", Config{}, options);
  const TraversabilityMap map = TraversabilityMap::Load(options.map_path);
  int observed = 0, traversable = 0;
  std::vector<double> heights;
  for (double x = 7.05; x < 11.0; x += 0.1) {
    for (double y = -1.45; y < 1.5; y += 0.1) {
      const CellInfo cell = map.TopSurfaceAt(x, y);
      if (!cell.observed) continue;
      ++observed;
      traversable += cell.cls == TravClass::kTraversable;
      heights.push_back(cell.surface_z_m);
    }
  }
  ASSERT_FALSE(heights.empty());
  std::nth_element(heights.begin(), heights.begin() + heights.size() / 2, heights.end());
  EXPECT_LT(heights[heights.size() / 2], -0.5);  // the lower level, 0.8 m down
  RecordProperty("observed", std::to_string(observed));
  RecordProperty("traversable", std::to_string(traversable));
  EXPECT_GT(observed, 400);
  EXPECT_GT(traversable, 0.95 * observed);
}

TEST(EndToEnd, ImuCorrectionUndoesRollPitchDriftInTheMap) {
  testing::TempDir dir;
  synth::SynthOptions clean = Yard(20);
  synth::SynthOptions drift = clean;
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
  // Measured 0.787 / 0.787 / 0.761 grid accuracy (truth to 20 m; undecided counts as wrong, and
  // far ground beside a jump is undecided: map.class_smeared_surface_hazards).
  EXPECT_LT(without.Accuracy(), with_imu.Accuracy() - 0.01)
      << "uncorrected " << without.Accuracy() << " vs corrected " << with_imu.Accuracy();
  EXPECT_GT(reference.Accuracy(), 0.77);
}

TEST(EndToEnd, DropOffAndForestMapsHoldTheirAccuracy) {
  // Grid accuracy over every cell the cameras saw within 20 m (unknown counts as wrong).
  // Measured on 20 frames, seed 1: drop-off 0.896, forest 0.886. Coverage is asserted too: an
  // empty map would score no wrong cell it saw.
  for (const synth::SynthOptions& scene : {Dropoff(20), Forest(20)}) {
    SCOPED_TRACE(scene.scene);
    testing::TempDir seq, out;
    synth::WriteSyntheticSequence(scene, seq / "seq");
    const ConfusionMatrix m = MapGridScore(seq / "seq", Config{}, out);
    RecordProperty(scene.scene + "_accuracy", std::to_string(m.Accuracy()));
    EXPECT_GE(m.Accuracy(), 0.87);
    EXPECT_GT(m.Coverage(), 0.90);
    const FootprintEvalSummary footprints = FootprintScore(seq / "seq", out);
    const double unsafe = footprints.matrix.UnsafeRate(), blocked = footprints.matrix.FalselyBlockedRate();
    RecordProperty(scene.scene + "_footprints_unsafe", std::to_string(unsafe));
    RecordProperty(scene.scene + "_footprints_falsely_blocked", std::to_string(blocked));
    std::cout << scene.scene << " footprints: unsafe " << unsafe << ", falsely blocked " << blocked << " of " << footprints.matrix.Scored() << " scored\n";
    // Floors, not the targets of docs/accuracy.md (unsafe <= 5 %, falsely blocked <= 10 %):
    // measured unsafe 0.225 (drop-off: its lip) and 0.041 (forest), falsely blocked 0.076 and
    // 0.063. A change that loses obstacles or blocks free ground beyond these fails.
    const bool dropoff = scene.scene == "dropoff";
    EXPECT_LE(unsafe, dropoff ? 0.30 : 0.08);
    EXPECT_LE(blocked, dropoff ? 0.10 : 0.09);
    EXPECT_GT(footprints.matrix.Scored(), 200);
  }
}

TEST(EndToEnd, RealtimeOverlayKeepsTheDropOffMap) {
  // config/realtime.yaml matches at half size (docs/performance.md). Measured on these 20
  // frames: accuracy 0.909 shipped, 0.906 overlay; mean IoU 0.452 and 0.392 (the overlay's
  // half-size disparity blurs the drop-off's lip band).
  testing::TempDir dir;
  synth::WriteSyntheticSequence(Dropoff(20), dir / "seq");
  const Config realtime = LoadConfig(std::string(SSTA_CONFIG_DIR) + "/realtime.yaml");
  ASSERT_EQ(realtime.stereo.downscale, 2);
  testing::TempDir a, b;
  const ConfusionMatrix shipped = MapGridScore(dir / "seq", Config{}, a);
  const ConfusionMatrix fast = MapGridScore(dir / "seq", realtime, b);
  RecordProperty("shipped", std::to_string(shipped.Accuracy()));
  RecordProperty("realtime", std::to_string(fast.Accuracy()));
  RecordProperty("shipped_mean_iou", std::to_string(shipped.MeanIou()));
  RecordProperty("realtime_mean_iou", std::to_string(fast.MeanIou()));
  EXPECT_GT(fast.Accuracy(), shipped.Accuracy() - 0.03);
  EXPECT_GT(fast.MeanIou(), shipped.MeanIou() - 0.08);
}

TEST(EndToEnd, ARandomTuningSceneHoldsItsLabelAndMapAccuracy) {
  // A `random` scene (terrain, rig and light drawn from the seed) of the tuning set
  // (scripts/accuracy.sh tuning), 15 frames. Measured: labels 0.949 / 0.594, map within 10 m of
  // the path 0.921.
  testing::TempDir dir;
  synth::SynthOptions o;
  o.scene = "random";
  o.seed = 5;
  o.frames = 15;
  synth::DrawRandomRig(o.seed, &o);
  synth::WriteSyntheticSequence(o, dir / "seq");
  const ConfusionMatrix labels = ClassifyAndScore(dir / "seq", dir / "out", Config{}, 3);
  RecordProperty("labels_accuracy", std::to_string(labels.Accuracy()));
  RecordProperty("labels_mean_iou", std::to_string(labels.MeanIou()));
  EXPECT_GT(labels.Accuracy(), 0.90);
  EXPECT_GT(labels.MeanIou(), 0.45);
  BuildMapOptions options;
  options.map_path = dir / "m.ot";
  BuildMap(Sequence::Open(dir / "seq"), "random", Config{}, options);
  ExportGrid(TraversabilityMap::Load(options.map_path), dir / "grid");
  const GridEvalSummary grid = EvaluateExportedGrid(dir / "grid", dir / "seq");
  double within_10m = 0.0;
  for (const DistanceBand& band : grid.by_distance) {
    if (band.to_m <= 10.0 + 1e-9) within_10m = band.accuracy_within;
  }
  RecordProperty("map_within_10m", std::to_string(within_10m));
  EXPECT_GT(within_10m, 0.91);
}

}  // namespace
}  // namespace ssta
