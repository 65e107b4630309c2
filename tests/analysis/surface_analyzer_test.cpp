#include <gtest/gtest.h>

#include <random>

#include <cmath>
#include <cstdint>
#include <functional>
#include <string>

#include <Eigen/Geometry>

#include "analytic_world.h"
#include "ssta/analysis/frame_analysis.h"
#include "ssta/analysis/surface_analyzer.h"
#include "ssta/core/units.h"

namespace ssta {
namespace {

using testing::AnalyticWorld;
using testing::PaintFloor;
using testing::PaintRamp;
using testing::PlanesOnly;

TEST(SurfaceAnalyzer, FloorIsTheTraversableGroundAtCameraHeight) {
  AnalyticWorld w(100, 100);
  PaintFloor(w, 0, 0, 100, 0, 100, 1.0);
  const AnalysisResult r = w.Analyze();
  ASSERT_TRUE(r.ground.found);
  EXPECT_TRUE(r.quality.passed) << r.quality.reason;
  EXPECT_NEAR(r.ground.camera_height_m, 1.0, 1e-6);
  EXPECT_NEAR(r.segments[0].slope_deg, 0.0, 1e-3);
  EXPECT_NEAR(r.ground.rms_m, 0.0, 1e-4);
  EXPECT_NEAR(r.segments[0].normal.dot(AnalyticWorld::kUp), 1.0, 1e-9);
  EXPECT_NEAR(r.segments[0].plane(3), 1.0, 1e-6);
  EXPECT_EQ(r.labels(50, 50), static_cast<std::uint8_t>(TravClass::kTraversable));
}

TEST(SurfaceAnalyzer, RampsOfKnownSlopeGetTheirSlopeClass) {
  for (const auto& [slope, expected] : std::vector<std::pair<double, TravClass>>{
           {10.0, TravClass::kTraversable}, {20.0, TravClass::kSemiTraversable}, {35.0, TravClass::kNonTraversable}}) {
    AnalyticWorld w(200, 100);
    PaintFloor(w, 0, 0, 100, 0, 100);
    // A short ramp so that its centroid stays within semi_step of the floor plane.
    PaintRamp(w, 1, 0, 4, 100, 200, slope);
    AnalysisOptions options = PlanesOnly();
    options.inliers_min_ratio = 0.01;  // the ramp (400 px) is a full segment
    const AnalysisResult r = w.Analyze({}, options);
    ASSERT_TRUE(r.quality.passed) << r.quality.reason;
    EXPECT_NEAR(r.segments[1].slope_deg, slope, 1e-3) << slope;
    EXPECT_EQ(r.segments[1].slope_class, expected) << slope;
    EXPECT_EQ(r.labels(2, 150), static_cast<std::uint8_t>(r.segments[1].verdict));
  }
}

TEST(SurfaceAnalyzer, StepsOfKnownHeightGetTheirStepClass) {
  for (const auto& [height, expected] : std::vector<std::pair<double, TravClass>>{
           {0.05, TravClass::kTraversable}, {0.15, TravClass::kSemiTraversable}, {0.30, TravClass::kNonTraversable}}) {
    AnalyticWorld w(200, 100);
    PaintFloor(w, 0, 0, 100, 0, 100, 1.0);
    PaintFloor(w, 1, 0, 50, 100, 200, 1.0 - height);  // a raised flat top (y down: smaller y)
    AnalysisOptions options = PlanesOnly();
    options.inliers_min_ratio = 0.01;
    const AnalysisResult r = w.Analyze({}, options);
    ASSERT_TRUE(r.quality.passed) << r.quality.reason;
    EXPECT_EQ(r.ground.segment_id, 0);
    EXPECT_NEAR(r.segments[1].step_m, height, 1e-6);
    EXPECT_EQ(r.segments[1].slope_class, TravClass::kTraversable);
    EXPECT_EQ(r.segments[1].step_class, expected) << height;
    EXPECT_EQ(r.segments[1].verdict, expected) << height;
  }
}

TEST(SurfaceAnalyzer, BoxFaceIsNonTraversableAndItsTopIsAStep) {
  AnalyticWorld w(200, 100);
  PaintFloor(w, 0, 0, 100, 0, 100);
  // Box front face: vertical, facing the camera, 0.4 m tall, 1 m wide.
  w.Paint(1, 0, 20, 100, 150, {0.0, 1.0, 3.0}, {1, 0, 0}, {0, -1, 0});
  // Box top at 0.4 m above the floor.
  w.Paint(2, 20, 40, 100, 150, {0.0, 0.6, 3.0}, {1, 0, 0}, {0, 0, 1});
  AnalysisOptions options = PlanesOnly();
  options.inliers_min_ratio = 0.01;
  const AnalysisResult r = w.Analyze({}, options);
  ASSERT_TRUE(r.quality.passed);
  EXPECT_NEAR(r.segments[1].slope_deg, 90.0, 1e-3);
  EXPECT_EQ(r.segments[1].verdict, TravClass::kNonTraversable);
  EXPECT_NEAR(r.segments[2].step_m, 0.4, 1e-6);
  EXPECT_EQ(r.segments[2].verdict, TravClass::kNonTraversable);
}

TEST(SurfaceAnalyzer, SmallObstacleIsFlaggedUnlessPaperExact) {
  AnalyticWorld w(100, 100);
  PaintFloor(w, 0, 0, 100, 0, 100);
  w.Paint(1, 0, 10, 0, 10, {0.0, 1.0, 3.0}, {1, 0, 0}, {0, -1, 0});  // 100 px wall, < 2 %
  w.Paint(2, 10, 20, 0, 10, {0.0, 1.0, 4.0}, {1, 0, 0}, {0, 0, 1});  // 100 px flat patch
  const AnalysisResult ours = w.Analyze();
  EXPECT_TRUE(ours.segments[1].small);
  EXPECT_EQ(ours.segments[1].verdict, TravClass::kNonTraversable);
  EXPECT_EQ(ours.segments[2].verdict, TravClass::kUndecided);  // small and harmless: no verdict
  AnalysisOptions paper = PlanesOnly();
  paper.small_segments = SmallSegmentPolicy::kPaper;
  const AnalysisResult exact = w.Analyze({}, paper);
  EXPECT_EQ(exact.segments[1].verdict, TravClass::kUndecided);
  EXPECT_EQ(exact.labels(5, 5), static_cast<std::uint8_t>(TravClass::kUndecided));
}

TEST(SurfaceAnalyzer, TinySegmentsAreJudgedByHeightButNotBySlope) {
  AnalyticWorld w(100, 100);
  PaintFloor(w, 0, 0, 100, 0, 100);
  // 10 points of a horizontal patch 0.5 m above the floor: its centroid is enough to tell.
  w.Paint(1, 0, 2, 0, 5, {0.0, 0.5, 3.0}, {1, 0, 0}, {0, 0, 1});
  // 10 points of a vertical patch touching the floor: too few for its slope to be trusted.
  w.Paint(2, 2, 4, 0, 5, {0.0, 1.0, 3.0}, {1, 0, 0}, {0, -1, 0}, 0.01);
  const AnalysisResult r = w.Analyze();
  ASSERT_TRUE(r.quality.passed);
  EXPECT_NEAR(r.segments[1].step_m, 0.5, 1e-6);
  EXPECT_EQ(r.segments[1].verdict, TravClass::kNonTraversable);
  EXPECT_NEAR(r.segments[2].slope_deg, 90.0, 1e-3);
  EXPECT_LT(r.segments[2].step_m, 0.02);
  EXPECT_EQ(r.segments[2].verdict, TravClass::kUndecided);
}

TEST(SurfaceAnalyzer, ASmallSegmentKnowsWhenTheStereoNoiseExplainsItsSlope) {
  // A small patch 12 m ahead, 0.6 m wide and 0.28 m long up a 30 deg incline (30 x 15 points,
  // 2 cm apart): steeper than max_slope_deg (25), its points spanning 0.15 m in height, less
  // than max_step_m (0.2).
  AnalyticWorld w(200, 200);
  PaintFloor(w, 0, 100, 200, 0, 200);
  const double incline = DegToRad(30.0);
  const Eigen::Vector3d along(0.0, -std::sin(incline), std::cos(incline));
  w.Paint(1, 0, 15, 0, 30, {0.0, 1.0, 12.0}, {1, 0, 0}, along);
  // The slope's noise in closed form: each point errs off the plane by k Z d (Z the points'
  // RMS depth, d the plane's distance from the camera), shared over a 9 px window (450 points:
  // 450 / 81 windows), over a spread along the fall line (the incline) of 0.02^2 (15^2 - 1) / 12.
  const Eigen::Vector3d normal(0.0, std::cos(incline), std::sin(incline));  // up's side (up is -y)
  const double d = std::abs(normal.dot(Eigen::Vector3d(0.0, 1.0, 12.0)));
  double sum_z2 = 0.0;
  for (int j = 0; j < 15; ++j) sum_z2 += 30 * std::pow(12.0 + 0.02 * j * std::cos(incline), 2);
  const double z_rms = std::sqrt(sum_z2 / 450.0);
  const double spread = 0.02 * 0.02 * (15 * 15 - 1) / 12.0;
  const auto sigma_deg = [&](double k) { return RadToDeg(k * z_rms * d / std::sqrt(450.0 / 81.0 * spread)); };
  const AnalysisOptions options = PlanesOnly();  // inliers_min 2 % of the image: 800 points
  for (const auto& [k, within] : std::vector<std::pair<double, bool>>{
           {0.0, false},     // no noise model: the slope stands
           {1e-4, false},    // 30 - 2 x 2.3 deg: still beyond 25 deg
           {5e-4, true}}) {  // 30 - 2 x 11.7 deg: the noise explains it
    const AnalysisResult r = w.Analyze({}, options, DepthNoise{k, 9});
    ASSERT_TRUE(r.quality.passed) << r.quality.reason;
    const SegmentResult& patch = r.segments[1];
    ASSERT_TRUE(patch.small);
    EXPECT_NEAR(patch.slope_deg, 30.0, 1e-3);
    EXPECT_NEAR(patch.slope_sigma_deg, sigma_deg(k), 0.01 * sigma_deg(k) + 1e-9) << k;
    // sqrt(12) x the standard deviation of 15 heights 0.02 sin(30 deg) apart: 0.15 m.
    EXPECT_NEAR(patch.rise_m, std::sqrt(12.0) * 0.02 * std::sin(incline) * std::sqrt((15.0 * 15.0 - 1.0) / 12.0), 1e-6);
    EXPECT_EQ(patch.slope_within_noise, within) << k;
    EXPECT_EQ(patch.verdict, TravClass::kNonTraversable) << k;  // the frame's own verdict stands
  }
  // A face 0.3 m tall at the same range rises more than max_step_m: a step, whatever its slope's
  // noise (here more than 90 deg).
  AnalyticWorld face(200, 200);
  PaintFloor(face, 0, 100, 200, 0, 200);
  face.Paint(1, 0, 15, 0, 30, {0.0, 1.0, 12.0}, {1, 0, 0}, {0, -1, 0});
  const SegmentResult wall = face.Analyze({}, options, DepthNoise{5e-3, 9}).segments[1];
  EXPECT_DOUBLE_EQ(wall.slope_sigma_deg, 90.0);
  EXPECT_GT(wall.rise_m, 0.2);
  EXPECT_FALSE(wall.slope_within_noise);
}

TEST(SurfaceAnalyzer, GroundAboveTheCameraIsRejected) {
  AnalyticWorld w(100, 100);
  PaintFloor(w, 0, 0, 100, 0, 100, -0.5);  // a ceiling-like plane 0.5 m above the camera
  const AnalysisResult r = w.Analyze();
  EXPECT_FALSE(r.ground.found);
  EXPECT_FALSE(r.quality.passed);
  EXPECT_NE(r.quality.reason.find("no dominant ground plane"), std::string::npos);
  EXPECT_EQ(r.labels(50, 50), static_cast<std::uint8_t>(TravClass::kUndecided));
}

TEST(SurfaceAnalyzer, OnASlopeWithoutLevelGroundTheSlopeIsTheGround) {
  // A vehicle climbing a 20 deg slope sees no traversable segment: the semi-traversable slope
  // it stands on is the ground, and the frame is judged, not dropped.
  AnalyticWorld w(100, 100);
  PaintRamp(w, 0, 0, 100, 0, 100, 20.0);
  const AnalysisResult r = w.Analyze();
  ASSERT_TRUE(r.ground.found);
  EXPECT_TRUE(r.quality.passed) << r.quality.reason;
  EXPECT_EQ(r.ground.segment_id, 0);
  EXPECT_EQ(r.ground.surface_class, TravClass::kSemiTraversable);
  const double s = 20.0 * M_PI / 180.0;
  EXPECT_NEAR(r.ground.camera_height_m, std::cos(s) * 1.0 + std::sin(s) * 2.0, 1e-6);  // |n . p0|
  EXPECT_EQ(r.labels(50, 50), static_cast<std::uint8_t>(TravClass::kSemiTraversable));

  // Level ground in view, however small beside the slope, stays the ground.
  AnalyticWorld both(100, 100);
  PaintFloor(both, 0, 0, 30, 0, 100);
  PaintRamp(both, 1, 30, 100, 0, 100, 20.0);
  const AnalysisResult b = both.Analyze();
  ASSERT_TRUE(b.ground.found);
  EXPECT_EQ(b.ground.segment_id, 0);
  EXPECT_EQ(b.ground.surface_class, TravClass::kTraversable);
}

TEST(SurfaceAnalyzer, QualityCheckRejectsImplausibleCameraHeight) {
  AnalyticWorld w(100, 100);
  PaintFloor(w, 0, 0, 100, 0, 100, 5.0);
  VehicleOptions vehicle;
  vehicle.max_camera_height_m = 2.0;
  const AnalysisResult r = w.Analyze(vehicle);
  EXPECT_TRUE(r.ground.found);
  EXPECT_FALSE(r.quality.passed);
  EXPECT_NE(r.quality.reason.find("implausible camera height"), std::string::npos) << r.quality.reason;
  EXPECT_EQ(r.labels(10, 10), static_cast<std::uint8_t>(TravClass::kUndecided));
}

TEST(SurfaceAnalyzer, QualityCheckRejectsARoughGround) {
  AnalyticWorld w(100, 100);
  PaintFloor(w, 0, 0, 100, 0, 100);
  for (int v = 0; v < 100; ++v) {
    for (int u = 0; u < 100; ++u) w.cloud_(v, u).y() += ((u + v) % 2 ? 0.25f : -0.25f);
  }
  const AnalysisResult r = w.Analyze();
  EXPECT_FALSE(r.quality.passed);
  EXPECT_NE(r.quality.reason.find("too rough"), std::string::npos) << r.quality.reason;
}

// Rolling ground: a floor that sags 0.6 m in the middle of its 10 m depth (never steeper than 14
// degrees) misses its best plane by 0.18 m RMS, yet its points lie on a smooth surface: the check
// takes the bend out.
TEST(SurfaceAnalyzer, QualityCheckPassesASmoothlyBendingGround) {
  AnalyticWorld w(100, 100);
  w.Paint(0, 0, 100, 0, 100, {-5.0, 1.0, 2.0}, {1, 0, 0}, {0, 0, 1}, 0.1);
  for (int v = 0; v < 100; ++v) {
    const float t = v / 100.0f;
    for (int u = 0; u < 100; ++u) w.cloud_(v, u).y() -= 2.4f * (t * t - t);
  }
  const AnalysisResult r = w.Analyze();
  EXPECT_GT(r.ground.rms_m, PlanesOnly().max_ground_rms_m);
  EXPECT_TRUE(r.quality.passed) << r.quality.reason;
  EXPECT_LT(r.ground.smooth_rms_m, 0.005);
}

// Far ground scattered by stereo noise alone: the depth noise expected at its range explains its
// RMS, so the frame passes; without a noise model the same scatter fails.
TEST(SurfaceAnalyzer, QualityCheckJudgesRoughnessBeyondTheStereoNoiseAtItsRange) {
  AnalyticWorld w(100, 100);
  w.Paint(0, 0, 100, 0, 100, {-5.0, 1.0, 10.0}, {1, 0, 0}, {0, 0, 1}, 0.1);  // 10 to 20 m ahead
  std::mt19937 rng(3);
  std::normal_distribution<float> unit(0.0f, 1.0f);
  const DepthNoise noise{0.01};  // 1 cm at 1 m: 1 m of depth at 10 m
  for (int v = 0; v < 100; ++v) {
    for (int u = 0; u < 100; ++u) {
      Eigen::Vector3f& p = w.cloud_(v, u);
      p *= 1.0f + static_cast<float>(noise.SigmaAt(p.z())) / p.z() * unit(rng);  // along the ray
    }
  }
  AnalysisOptions options = PlanesOnly();
  options.max_ground_rms_m = 0.08;  // below the scatter the noise gives these points
  const AnalysisResult with = w.Analyze({}, options, noise);
  EXPECT_GT(with.ground.noise_rms_m, options.max_ground_rms_m);
  EXPECT_TRUE(with.quality.passed) << with.quality.reason;
  const AnalysisResult without = w.Analyze({}, options);
  EXPECT_FALSE(without.quality.passed);
  EXPECT_NE(without.quality.reason.find("too rough"), std::string::npos) << without.quality.reason;
}

TEST(SurfaceAnalyzer, PixelsWithoutDepthAreUnknownAndUnsegmentedAreUndecided) {
  AnalyticWorld w(100, 100);
  PaintFloor(w, 0, 0, 100, 0, 100);
  w.cloud_(0, 0) = NanVector3f();
  w.ids_(0, 0) = -1;
  w.ids_(1, 1) = -1;  // valid point, no segment
  const AnalysisResult r = w.Analyze();
  EXPECT_EQ(r.labels(0, 0), static_cast<std::uint8_t>(TravClass::kUnknown));
  EXPECT_EQ(r.labels(1, 1), static_cast<std::uint8_t>(TravClass::kUndecided));
  EXPECT_EQ(r.depth_pixels, 100 * 100 - 1);
}

TEST(SurfaceAnalyzer, ReachableStepsLetARampUpButNotOntoABox) {
  // Floor in columns 0..59; from column 60 a 12-degree ramp rises away to the right, 6 cm per
  // column: its centroid stands 0.24 m above the floor plane, a non-traversable "step" by eq. 5,
  // yet its foot meets the floor without a jump and a vehicle drives up it.
  AnalyticWorld w(100, 100);
  PaintFloor(w, 0, 0, 100, 0, 60);
  const double s = 12.0 * M_PI / 180.0;
  for (int v = 0; v < 100; ++v) {
    for (int u = 60; u < 100; ++u) {
      const double along = (u - 60) * 0.06;
      w.cloud_(v, u) = Eigen::Vector3f(static_cast<float>(0.2 + along * std::cos(s)),
                                       static_cast<float>(1.0 - along * std::sin(s)), static_cast<float>(2.0 + 0.02 * v));
      w.ids_(v, u) = 1;
    }
  }
  // A box top 0.3 m above the floor inside it, reached only across a 0.3 m jump.
  w.Paint(2, 40, 60, 20, 30, {-0.5, 0.7, 2.5}, {1, 0, 0}, {0, 0, 1});
  AnalysisOptions options = PlanesOnly();
  options.inliers_min_ratio = 0.01;
  const AnalysisResult paper = w.Analyze({}, options);
  ASSERT_TRUE(paper.quality.passed);
  ASSERT_EQ(paper.ground.segment_id, 0);
  EXPECT_NEAR(paper.segments[1].slope_deg, 12.0, 1e-3);
  EXPECT_GT(paper.segments[1].step_m, 0.2);
  EXPECT_EQ(paper.segments[1].verdict, TravClass::kNonTraversable);
  options.step_reference = StepReference::kReachable;
  const AnalysisResult reach = w.Analyze({}, options);
  EXPECT_EQ(reach.segments[1].step_class, TravClass::kTraversable);
  EXPECT_EQ(reach.segments[1].verdict, TravClass::kTraversable);
  EXPECT_EQ(reach.segments[2].verdict, TravClass::kNonTraversable);
  EXPECT_NEAR(reach.segments[2].step_m, 0.3, 0.02);
}

// The floor of the test above, and from column 60 a ramp rising away at `slope_deg` (6 cm per
// column along it) whose last 4 columns in rows 0..19 are a segment of their own (80 points).
AnalyticWorld FloorAndRamp(double slope_deg) {
  AnalyticWorld w(100, 100);
  PaintFloor(w, 0, 0, 100, 0, 60);
  const double s = slope_deg * M_PI / 180.0;
  for (int v = 0; v < 100; ++v) {
    for (int u = 60; u < 100; ++u) {
      const double along = (u - 60) * 0.06;
      w.cloud_(v, u) = Eigen::Vector3f(static_cast<float>(0.2 + along * std::cos(s)),
                                       static_cast<float>(1.0 - along * std::sin(s)), static_cast<float>(2.0 + 0.02 * v));
      w.ids_(v, u) = (u >= 96 && v < 20) ? 2 : 1;
    }
  }
  w.num_segments_ = 3;
  return w;
}

TEST(SurfaceAnalyzer, ReachableLargeLiftsOnlyLargeSegmentsThatEq5CallsAStep) {
  AnalysisOptions options = PlanesOnly();
  options.inliers_min_ratio = 0.01;  // inliers_min = 100: the ramp is large, its 80-point end small
  options.small_segments = SmallSegmentPolicy::kAll;

  // 12 deg: the ramp's centroid stands 1.17 sin(12 deg) = 0.24 m over the floor, a step by eq. 5,
  // and its end 2.25 sin(12 deg) = 0.47 m. Both are reached without a jump.
  const AnalyticWorld steep = FloorAndRamp(12.0);
  options.step_reference = StepReference::kReachable;
  const AnalysisResult reach = steep.Analyze({}, options);
  ASSERT_TRUE(reach.quality.passed);
  ASSERT_FALSE(reach.segments[1].small);
  ASSERT_TRUE(reach.segments[2].small);
  EXPECT_EQ(reach.segments[1].verdict, TravClass::kTraversable);
  EXPECT_EQ(reach.segments[2].verdict, TravClass::kTraversable);
  EXPECT_LT(reach.segments[2].step_m, 0.05);

  options.step_reference = StepReference::kReachableLarge;
  const AnalysisResult large = steep.Analyze({}, options);
  EXPECT_EQ(large.segments[1].step_class, TravClass::kTraversable);  // large: reached
  EXPECT_EQ(large.segments[1].verdict, TravClass::kTraversable);
  EXPECT_EQ(large.segments[2].step_class, TravClass::kNonTraversable);  // small: eq. 5
  EXPECT_EQ(large.segments[2].verdict, TravClass::kNonTraversable);
  EXPECT_NEAR(large.segments[2].step_m, 2.25 * std::sin(12.0 * M_PI / 180.0), 0.02);

  // 6 deg: the ramp's centroid stands 1.17 sin(6 deg) = 0.12 m over the floor, semi-traversable by
  // eq. 5. "reachable" makes it traversable; "reachable_large" keeps eq. 5's semi-traversable.
  const AnalyticWorld gentle = FloorAndRamp(6.0);
  options.step_reference = StepReference::kReachable;
  EXPECT_EQ(gentle.Analyze({}, options).segments[1].verdict, TravClass::kTraversable);
  options.step_reference = StepReference::kReachableLarge;
  const AnalysisResult kept = gentle.Analyze({}, options);
  EXPECT_NEAR(kept.segments[1].step_m, 1.17 * std::sin(6.0 * M_PI / 180.0), 0.01);
  EXPECT_EQ(kept.segments[1].verdict, TravClass::kSemiTraversable);
}

TEST(AnalysisOptions, RejectsBadFaceFragmentAndFillSettingsNamingTheKey) {
  const AnalysisOptions valid;  // every refinement on
  std::string error;
  ASSERT_TRUE(valid.IsValid(&error)) << error;
  // One bad value at a time, on top of valid options: rejected, and the message names the key.
  auto expect_rejected = [&](const std::string& key, const std::function<void(AnalysisOptions*)>& spoil) {
    AnalysisOptions o = valid;
    spoil(&o);
    std::string message;
    EXPECT_FALSE(o.IsValid(&message)) << key;
    EXPECT_NE(message.find(key), std::string::npos) << message;
  };
  expect_rejected("face_window_px", [](AnalysisOptions* o) { o->face_window_px = 4; });
  expect_rejected("face_min_slope_deg", [](AnalysisOptions* o) { o->face_min_slope_deg = 90; });
  expect_rejected("face_grow_tolerance_px", [](AnalysisOptions* o) { o->face_grow_tolerance_px = -0.1; });
  expect_rejected("face_columns_px", [](AnalysisOptions* o) { o->face_columns_px = 16; });
  expect_rejected("fragment_tolerance_px", [](AnalysisOptions* o) { o->fragment_tolerance_px = -1; });
  expect_rejected("fragment_consistent_share", [](AnalysisOptions* o) { o->fragment_consistent_share = 0; });
  expect_rejected("fragment_host_min_points", [](AnalysisOptions* o) { o->fragment_host_min_points = 2; });
  // A share of 0.5 could pick either class of a tie.
  expect_rejected("undecided_fill_share", [](AnalysisOptions* o) { o->undecided_fill_share = 0.5; });
  expect_rejected("undecided_fill_radius_px", [](AnalysisOptions* o) { o->undecided_fill_radius_px = -1; });
  expect_rejected("label_min_texture", [](AnalysisOptions* o) { o->label_min_texture = -0.5; });
  expect_rejected("label_min_texture", [](AnalysisOptions* o) { o->label_min_texture = 128; });
}

TEST(PlaneAccumulator, FitsATiltedPlaneInClosedForm) {
  PlaneAccumulator acc;
  const Eigen::Vector3d n = Eigen::Vector3d(0.2, -0.9, 0.3).normalized();
  const Eigen::Vector3d a = n.unitOrthogonal();
  const Eigen::Vector3d b = n.cross(a);
  for (int i = -10; i <= 10; ++i) {
    for (int j = -10; j <= 10; ++j) acc.Add(Eigen::Vector3d(1, 2, 3) + 0.1 * i * a + 0.1 * j * b);
  }
  const PlaneFit fit = acc.Fit();
  EXPECT_NEAR(std::abs(fit.normal.dot(n)), 1.0, 1e-9);
  EXPECT_TRUE(fit.centroid.isApprox(Eigen::Vector3d(1, 2, 3), 1e-9));
  EXPECT_NEAR(fit.rms_m, 0.0, 1e-6);
}

}  // namespace
}  // namespace ssta
