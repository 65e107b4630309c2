// Which rule set each pixel's class (LabelRule): the table, the rule image of FrameAnalyzer on an
// analytic world where one known rule fires, and the per-rule counts of a rendered frame.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <map>
#include <set>
#include <string>
#include <utility>

#include "ssta/analysis/frame_analysis.h"
#include "ssta/analysis/label_rule.h"
#include "ssta/geometry/normal_estimator.h"
#include "ssta/pipeline/frame_pipeline.h"
#include "ssta/pipeline/frame_report.h"
#include "ssta/synth/scene.h"
#include "ssta/synth/sequence_synthesizer.h"
#include "ssta/synth/stereo_renderer.h"
#include "ssta/synth/vehicle_trajectory.h"

namespace ssta {
namespace {

constexpr auto kNon = static_cast<std::uint8_t>(TravClass::kNonTraversable);

TEST(LabelRules, TheTableIsInValueOrderWithOneNameEach) {
  std::set<std::string> names;
  for (int i = 0; i < kNumLabelRules; ++i) {
    EXPECT_EQ(static_cast<int>(LabelRules()[i].rule), i);
    EXPECT_FALSE(LabelRules()[i].name.empty());
    names.insert(std::string(LabelRules()[i].name));
  }
  EXPECT_EQ(names.size(), static_cast<std::size_t>(kNumLabelRules));
  EXPECT_EQ(LabelRuleName(LabelRule::kLocalStep), "local_step");
  EXPECT_EQ(LabelRuleName(static_cast<LabelRule>(kNumLabelRules)), "invalid");
}

// A level floor 1 m below a camera looking down (organized top-down: pixel (v, u) at x = -1 +
// 0.01 u, z = 1 + 0.01 v, 200 x 200 px) with a 0.8 x 0.8 m crate top 0.3 m above it, each its
// own level segment (0 the floor, 1 the crate).
struct CrateOnFloor {
  static constexpr int n = 200;
  Image3f cloud{n, n, NanVector3f()};
  Image3f normals{n, n, Eigen::Vector3f(0, -1, 0)};
  ImageI32 ids{n, n, 0};
  ImageF disparity{n, n, 0.0f};
  RectifiedGeometry g;

  CrateOnFloor() {
    for (int v = 0; v < n; ++v) {
      for (int u = 0; u < n; ++u) {
        const double x = -1.0 + 0.01 * u, z = 1.0 + 0.01 * v;
        const bool crate = x >= -0.4 && x < 0.4 && z >= 1.6 && z < 2.4;
        cloud(v, u) = Eigen::Vector3f(static_cast<float>(x), crate ? 0.7f : 1.0f, static_cast<float>(z));
        ids(v, u) = crate ? 1 : 0;
      }
    }
    g.full_width = g.crop_width = n;
    g.full_height = g.crop_height = n;
    g.f = 400.0;
    g.cu = g.cv = n / 2.0;
    g.baseline_m = 0.12;
  }

  AnalysisResult Analyze(const VehicleOptions& vehicle, const AnalysisOptions& options) const {
    return FrameAnalyzer(vehicle, options).Analyze({&g, &disparity, &cloud, &normals, &ids, 2, {0, -1, 0}});
  }
};

// The crate on the floor: the segments are traversable by slope, and the only rule that can make
// a pixel non-traversable is the local step, within step_radius_m (0.2 m) of the crate's edge on
// both sides.
TEST(LabelRules, LocalStepsMarkTheRingAroundACrateOnFlatGround) {
  const CrateOnFloor world;
  const int n = CrateOnFloor::n;
  const AnalysisResult a = world.Analyze({}, AnalysisOptions{});  // shipped: local steps, every refinement on
  ASSERT_TRUE(a.quality.passed) << a.quality.reason;
  ASSERT_EQ(a.rules.width(), n);
  const auto rule_at = [&](double x, double z) {
    return static_cast<LabelRule>(a.rules(static_cast<int>(std::lround((z - 1.0) / 0.01)),
                                          static_cast<int>(std::lround((x + 1.0) / 0.01))));
  };
  const auto label_at = [&](double x, double z) {
    return a.labels(static_cast<int>(std::lround((z - 1.0) / 0.01)), static_cast<int>(std::lround((x + 1.0) / 0.01)));
  };
  // Far from the crate: the floor segment's verdict; on the ring: the local step.
  EXPECT_EQ(rule_at(-0.8, 1.2), LabelRule::kSegment);
  EXPECT_EQ(label_at(-0.8, 1.2), 1);
  EXPECT_EQ(rule_at(0.0, 2.0), LabelRule::kSegment);  // the crate's level middle, 0.4 m from its edges
  for (const auto& [x, z] : {std::pair{0.0, 1.55}, {0.0, 1.65}, {-0.45, 2.0}, {0.45, 2.0}, {0.0, 2.45}}) {
    EXPECT_EQ(rule_at(x, z), LabelRule::kLocalStep) << x << ", " << z;
    EXPECT_EQ(label_at(x, z), kNon) << x << ", " << z;
  }
  // Every non-traversable pixel is the local step's, and every pixel the local step changed is
  // non-traversable; the rest of the image is the segments'.
  int ring = 0;
  for (std::size_t i = 0; i < a.labels.size(); ++i) {
    const auto rule = static_cast<LabelRule>(a.rules[i]);
    ASSERT_EQ(a.labels[i] == kNon, rule == LabelRule::kLocalStep) << i;
    ASSERT_TRUE(rule == LabelRule::kLocalStep || rule == LabelRule::kSegment) << LabelRuleName(rule);
    ring += rule == LabelRule::kLocalStep;
  }
  // The band reaches 0.1-0.3 m around the edges (cells of 0.1 m): at least the 1.0 m square less
  // the 0.6 m one, at most the 1.4 m square less the 0.2 m one [1 px = 1 cm^2].
  EXPECT_GT(ring, 6400);
  EXPECT_LT(ring, 19200);
}

// The same crate on the floor, with a quality check the floor's plane fails only on its share
// of the view (84 % of the pixels against a minimum of 90 %), as on rolling ground where no one
// plane holds much. The local rule measures against gravity, not against that plane: the frame
// keeps every verdict the passing frame has. The paper's rule (steps against the plane) leaves
// it undecided, and so does the local rule when the plane puts the camera at a height the
// vehicle rules out (a scale error, or no ground in view).
TEST(LabelRules, UnderTheLocalRuleAPlaneThatHoldsLittleOfTheViewLeavesTheFrameJudged) {
  const CrateOnFloor world;
  const int n = CrateOnFloor::n;
  const auto count = [](const ImageU8& image, std::uint8_t value) {
    return std::count(image.data(), image.data() + image.size(), value);
  };
  const auto same = [](const ImageU8& a, const ImageU8& b) {
    return a.size() == b.size() && std::equal(a.data(), a.data() + a.size(), b.data());
  };
  const AnalysisOptions shipped;
  const AnalysisResult passing = world.Analyze({}, shipped);
  ASSERT_TRUE(passing.quality.passed) << passing.quality.reason;
  ASSERT_TRUE(passing.quality.judged);

  AnalysisOptions strict = shipped;
  strict.min_ground_share = 0.9;
  const AnalysisResult judged = world.Analyze({}, strict);
  EXPECT_FALSE(judged.quality.passed);
  EXPECT_TRUE(judged.quality.judged);
  EXPECT_NE(judged.quality.reason.find("too small: share 0.840"), std::string::npos) << judged.quality.reason;
  EXPECT_TRUE(same(judged.labels, passing.labels));
  EXPECT_TRUE(same(judged.rules, passing.rules));
  EXPECT_GT(count(judged.labels, kNon), 6400);  // the crate's ring, as above

  AnalysisOptions paper = strict;
  paper.step_reference = StepReference::kDominantPlane;
  const AnalysisResult unjudged = world.Analyze({}, paper);
  EXPECT_FALSE(unjudged.quality.judged);
  EXPECT_EQ(count(unjudged.labels, static_cast<std::uint8_t>(TravClass::kUndecided)), n * n);

  VehicleOptions low;
  low.max_camera_height_m = 0.5;  // the floor 1 m below: implausible for this vehicle
  const AnalysisResult implausible = world.Analyze(low, shipped);
  EXPECT_FALSE(implausible.quality.passed);
  EXPECT_FALSE(implausible.quality.judged);
  EXPECT_NE(implausible.quality.reason.find("implausible camera height"), std::string::npos);
  EXPECT_EQ(count(implausible.labels, static_cast<std::uint8_t>(TravClass::kUndecided)), n * n);
  EXPECT_EQ(count(implausible.rules, static_cast<std::uint8_t>(LabelRule::kQualityCheck)), n * n);
}

// A rendered yard frame, through the whole pipeline: the rules' pixels add up to the labels'
// pixels of each class, each rule gives only the classes it can, and the frame's JSON reports
// the same counts.
TEST(LabelRules, CountsPerRuleAddUpToTheLabelsOfEachClassOnARenderedYard) {
  synth::SynthOptions o;
  const Config shipped;
  o.vehicle = shipped.vehicle;
  const synth::Scene scene = synth::MakeScene("yard", o.seed, o.ramp_slope_deg);
  const synth::VehicleTrajectory trajectory(scene, o.motion);
  const synth::StereoRenderer renderer(scene, o.rig, o.render, nullptr, o.seed);
  const Eigen::Isometry3d body_T_cam0 = synth::TrueBodyTCam0(o.rig, o.motion);
  StereoCalibration rig{renderer.Intrinsics(), renderer.Intrinsics()};
  rig.left.body_T_camera = body_T_cam0;
  rig.right.body_T_camera = body_T_cam0 * Eigen::Translation3d(o.rig.baseline_m, 0, 0);
  const Eigen::Isometry3d world_T_body = trajectory.WorldTBody(1.5);
  const synth::StereoFrame pair = renderer.Render(world_T_body * body_T_cam0, 0);
  const Eigen::Vector3d up_camera =
      (body_T_cam0.linear().transpose() * world_T_body.linear().transpose() * Eigen::Vector3d::UnitZ()).normalized();
  FramePipeline pipeline(rig, shipped);
  const FrameResult r = pipeline.Process(pair.left, pair.right, up_camera);
  ASSERT_TRUE(r.analysis.quality.passed);
  ASSERT_EQ(r.rules.width(), r.labels.width());
  ASSERT_EQ(r.rules.height(), r.labels.height());

  std::array<std::array<long, kNumClasses>, kNumLabelRules> by_rule{};
  std::array<long, kNumClasses> by_class{};
  for (std::size_t i = 0; i < r.labels.size(); ++i) {
    ASSERT_LT(r.rules[i], kNumLabelRules);
    ASSERT_LT(r.labels[i], kNumClasses);
    ++by_rule[r.rules[i]][r.labels[i]];
    ++by_class[r.labels[i]];
  }
  for (int c = 0; c < kNumClasses; ++c) {
    long sum = 0;
    for (int k = 0; k < kNumLabelRules; ++k) sum += by_rule[k][c];
    EXPECT_EQ(sum, by_class[c]) << ClassName(static_cast<TravClass>(c));
  }
  const auto count = [&](LabelRule rule, TravClass c) { return by_rule[static_cast<int>(rule)][static_cast<int>(c)]; };
  const auto total = [&](LabelRule rule) {
    long sum = 0;
    for (const long k : by_rule[static_cast<int>(rule)]) sum += k;
    return sum;
  };
  // Rules that can only blank a pixel give unknown alone; the fills only decide.
  for (const LabelRule blank : {LabelRule::kNoDepth, LabelRule::kTexture, LabelRule::kOutside}) {
    EXPECT_EQ(count(blank, TravClass::kUnknown), total(blank)) << LabelRuleName(blank);
  }
  EXPECT_EQ(count(LabelRule::kConsensusFill, TravClass::kUndecided), 0);
  EXPECT_EQ(count(LabelRule::kLocalStep, TravClass::kTraversable), 0);  // it only makes things worse
  // The paper's segment verdicts decide most of the frame; the refinements each change some.
  EXPECT_GT(count(LabelRule::kSegment, TravClass::kTraversable), by_class[1] / 2);
  for (const LabelRule rule : {LabelRule::kPixelSlope, LabelRule::kLocalStep, LabelRule::kConsensusFill}) {
    EXPECT_GT(total(rule), 100) << LabelRuleName(rule);
  }
  // The JSON's counts are these.
  const std::string json = FrameReportJson(r, "frame");
  std::string local = "\"local_step\": {";
  for (int c = 0; c < kNumClasses; ++c) {
    local += (c ? ", \"" : "\"") + std::string(ClassName(static_cast<TravClass>(c))) +
             "\": " + std::to_string(by_rule[static_cast<int>(LabelRule::kLocalStep)][c]);
  }
  EXPECT_NE(json.find("\"pixels_by_rule\": {"), std::string::npos);
  EXPECT_NE(json.find(local + "}"), std::string::npos) << local;
}

// The demo yard (seed 1) seen 0.17-0.37 s into its run: the ground in the bottom 100 rows, in
// front of the camera, is flat and free. In the blank band where the far ground meets the sky,
// the matcher finds disparities of 71-75 px: points 0.7 m ahead at the camera's height, hanging
// over the far ground the rows below them see. In the local steps' grid they stand 0.8 m above
// the nearest ground, and the local step rule made a block of 3,000-10,000 px of it
// non-traversable. Left out as floating (SupportedPixels with the disparity), they make none.
TEST(LabelRules, FloatingMatchesInTheBlankHorizonBandBlockNoGroundInFront) {
  synth::SynthOptions o;
  const Config shipped;
  ASSERT_GT(shipped.analysis.label_min_texture, 0.0);
  o.vehicle = shipped.vehicle;
  const synth::Scene scene = synth::MakeScene("yard", 1, o.ramp_slope_deg);
  const synth::VehicleTrajectory trajectory(scene, o.motion);
  const synth::StereoRenderer renderer(scene, o.rig, o.render, nullptr, 1);
  const Eigen::Isometry3d body_T_cam0 = synth::TrueBodyTCam0(o.rig, o.motion);
  StereoCalibration rig{renderer.Intrinsics(), renderer.Intrinsics()};
  rig.left.body_T_camera = body_T_cam0;
  rig.right.body_T_camera = body_T_cam0 * Eigen::Translation3d(o.rig.baseline_m, 0, 0);
  FramePipeline pipeline(rig, shipped);
  const RectifiedGeometry& g = pipeline.geometry();
  ASSERT_EQ(g.crop_height, g.full_height);  // a rectified rig: no crop
  const int bottom_v0 = g.crop_height - 100;
  int worst_before = 0;
  for (int k = 1; k <= 4; ++k) {
    const double t = 0.1 + k / o.rig.rate_hz;
    const Eigen::Isometry3d world_T_body = trajectory.WorldTBody(t);
    const synth::StereoFrame pair = renderer.Render(world_T_body * body_T_cam0, k);
    const Eigen::Vector3d up_camera =
        (body_T_cam0.linear().transpose() * world_T_body.linear().transpose() * Eigen::Vector3d::UnitZ()).normalized();
    const FrameResult r = pipeline.Process(pair.left, pair.right, up_camera);
    ASSERT_TRUE(r.analysis.quality.passed) << r.analysis.quality.reason;
    int red = 0;
    for (int v = bottom_v0; v < g.crop_height; ++v) {
      for (int u = 0; u < g.crop_width; ++u) red += r.labels(v, u) == kNon;
    }
    EXPECT_LT(red, 100) << "t = " << t;  // of 64,000 px of free ground

    // The same frame with every point in the local steps' grid: the block comes back, set by the
    // local step rule.
    const Image3f normals = EstimateNormals(r.cloud, shipped.normals);
    const AnalysisResult all_points =
        FrameAnalyzer(shipped.vehicle, shipped.analysis, shipped.stereo.disparity_sigma_px)
            .Analyze({&g, &r.disparity, &r.cloud, &normals, &r.segment_ids, r.num_segments, r.up_rectified});
    int red_before = 0, by_local_step = 0;
    std::map<int, int> by_rule;
    for (int v = bottom_v0; v < g.crop_height; ++v) {
      for (int u = 0; u < g.crop_width; ++u) {
        if (all_points.labels(v, u) != kNon) continue;
        ++red_before;
        by_local_step += static_cast<LabelRule>(all_points.rules(v, u)) == LabelRule::kLocalStep;
        ++by_rule[all_points.rules(v, u)];
      }
    }
    std::string rules;
    for (const auto& [rule, count] : by_rule) rules += " " + std::to_string(rule) + ":" + std::to_string(count);
    // Nearly all by the local step rule; a small segment at the block's edge may add its own
    // verdict (56 px of 5279 in one frame).
    EXPECT_GE(by_local_step, 0.97 * red_before) << "red pixels by rule id:" << rules;
    worst_before = std::max(worst_before, red_before);
  }
  EXPECT_GT(worst_before, 3000);
}

// SupportedPixels with the disparity on a 100 x 100 image whose horizon is row 50: rows 60-99 a
// textured base at 20 px, rows 0-59 blank grey. Above the horizon a blank wall continuing the
// base at 20 px keeps its support; a blank sky at 3 px (depth known to 8 % at best) does not; a
// blank piece at 40 px, nearer than the base below it, floats and loses it also below the
// horizon.
TEST(SupportedPixels, KeepBlankWallsOnTheirBaseAndDropSkiesAndFloatingPieces) {
  const int n = 100;
  RectifiedGeometry g;
  g.full_width = g.crop_width = n;
  g.full_height = g.crop_height = n;
  g.f = 100.0;
  g.cu = g.cv = 50.0;
  g.baseline_m = 0.1;
  ImageU8 image(n, n, 128);
  std::uint32_t state = 12345;
  for (int v = 60; v < n; ++v) {
    for (int u = 0; u < n; ++u) {
      state = state * 1664525u + 1013904223u;
      image(v, u) = static_cast<std::uint8_t>(64 + (state >> 25));  // 64..191
    }
  }
  const Eigen::Vector3d up(0, -1, 0);
  auto supported_rows = [&](float blank_d, int v0, int v1) {
    ImageF disparity(n, n, 20.0f);
    for (int v = 0; v < 60; ++v) {
      for (int u = 0; u < n; ++u) disparity(v, u) = blank_d;
    }
    const ImageU8 s = SupportedPixels(image, g, 9, 2.0, up, disparity);
    int count = 0;
    for (int v = v0; v < v1; ++v) {
      for (int u = 0; u < n; ++u) count += s(v, u);
    }
    return count;
  };
  const int above = 45 * n;  // rows 0-44: blank and above the horizon, clear of the base's block
  EXPECT_EQ(supported_rows(20.0f, 0, 45), above);  // a wall
  EXPECT_EQ(supported_rows(3.0f, 0, 45), 0);       // a sky
  EXPECT_EQ(supported_rows(40.0f, 0, 45), 0);      // floating above the horizon
  EXPECT_EQ(supported_rows(40.0f, 51, 55), 0);     // and below it
  EXPECT_EQ(supported_rows(3.0f, 51, 55), 4 * n);  // blank and farther below the horizon: a surface
  // Without the disparity only texture and the horizon count: the wall is lost.
  const ImageU8 plain = SupportedPixels(image, g, 9, 2.0, up);
  int wall = 0;
  for (int v = 0; v < 45; ++v) {
    for (int u = 0; u < n; ++u) wall += plain(v, u);
  }
  EXPECT_EQ(wall, 0);
}

/// Pixels of the demo yard's sky (seed 1, blank grey with the renderer's pixel noise of
/// `noise_grey` grey levels) over three frames, and how many of them keep a class or stay
/// undecided under `config`: above the horizon, clear of the skyline's block.
std::pair<long, long> SkyAndClassed(double noise_grey, const Config& config) {
  synth::SynthOptions o;
  o.vehicle = config.vehicle;
  o.render.sensor_noise_grey = noise_grey;
  const synth::Scene scene = synth::MakeScene("yard", 1, o.ramp_slope_deg);
  const synth::VehicleTrajectory trajectory(scene, o.motion);
  const synth::StereoRenderer renderer(scene, o.rig, o.render, nullptr, 1);
  const Eigen::Isometry3d body_T_cam0 = synth::TrueBodyTCam0(o.rig, o.motion);
  StereoCalibration rig{renderer.Intrinsics(), renderer.Intrinsics()};
  rig.left.body_T_camera = body_T_cam0;
  rig.right.body_T_camera = body_T_cam0 * Eigen::Translation3d(o.rig.baseline_m, 0, 0);
  FramePipeline pipeline(rig, config);
  const RectifiedGeometry& g = pipeline.geometry();
  long sky = 0, classed = 0;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Isometry3d world_T_body = trajectory.WorldTBody(0.1 + 3 * k / o.rig.rate_hz);
    const synth::StereoFrame pair = renderer.Render(world_T_body * body_T_cam0, 3 * k);
    const Eigen::Vector3d up_camera =
        (body_T_cam0.linear().transpose() * world_T_body.linear().transpose() * Eigen::Vector3d::UnitZ()).normalized();
    const FrameResult r = pipeline.Process(pair.left, pair.right, up_camera);
    const int margin = config.stereo.block_size;
    for (int v = 0; v < g.crop_height; ++v) {
      for (int u = 0; u < g.crop_width; ++u) {
        // A pixel whose ray points above the horizon by more than the block's rows.
        const Eigen::Vector3d ray((u - g.cu) / g.f, (v + margin - g.cv) / g.f, 1.0);
        if (ray.dot(r.up_rectified) <= 0.0) continue;
        ++sky;
        classed += r.labels(v + g.crop_v0, u + g.crop_u0) != 0;
      }
    }
  }
  return {sky, classed};
}

// The sky keeps no class but for speckles where the matcher's smoothing carries the skyline's
// disparity up: at most 0.1 % of it.
TEST(SupportedPixels, TheRenderedSkyGetsNoClasses) {
  const Config shipped;
  const auto [sky, classed] = SkyAndClassed(synth::RenderOptions{}.sensor_noise_grey, shipped);
  ASSERT_GT(sky, 3 * 50000);
  EXPECT_LE(classed, sky / 1000);
}

// A noisy camera's sky (3 grey levels of noise, as on the noisiest random rigs) varies by more
// than label_min_texture's 2 grey levels over a block: the texture test asks for 1.5 times the
// noise measured in each image, and the sky still keeps no class. With a fixed threshold,
// SGBM's matches in the noise give classes to much of it.
TEST(SupportedPixels, ANoisyCamerasSkyGetsNoClasses) {
  const Config shipped;
  const auto [sky, classed] = SkyAndClassed(3.0, shipped);
  ASSERT_GT(sky, 3 * 50000);
  EXPECT_LE(classed, sky / 1000);
  Config fixed = shipped;
  fixed.analysis.texture_noise_multiple = 0.0;
  const auto [sky_fixed, classed_fixed] = SkyAndClassed(3.0, fixed);
  EXPECT_GT(classed_fixed, sky_fixed / 20);
}

}  // namespace
}  // namespace ssta
