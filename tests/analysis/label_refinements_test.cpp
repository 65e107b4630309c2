#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include <Eigen/Geometry>

#include "analytic_world.h"
#include "ssta/analysis/label_refinements.h"
#include "ssta/analysis/frame_analysis.h"
#include "ssta/analysis/surface_analyzer.h"
#include "ssta/core/error.h"

namespace ssta {
namespace {

using testing::AnalyticWorld;
using testing::PaintFloor;
using testing::PaintRamp;
using testing::PlanesOnly;

// Disparities of the analytic world's points for a rig with f * b = 50 px m (f 420 px, b 0.12 m).
constexpr double kFocalTimesBaseline = 50.0;

TEST(RefineByGroundDisparity, SmallSegmentsOnTheGroundWithinNoiseBecomeTraversable) {
  AnalyticWorld w(100, 100);
  PaintFloor(w, 0, 0, 100, 0, 100);
  // A small patch 8 m ahead, tilted 40 degrees about x through a floor point: a noisy far
  // fragment of the floor. Its farthest point stands 0.13 m above the floor: d = 50 / 8 px
  // differs from the floor's along the same ray by less than 0.1 px.
  const double s = 40.0 * M_PI / 180.0;
  w.Paint(1, 0, 8, 0, 8, {0.0, 1.0, 8.0}, {1, 0, 0}, {0, -std::sin(s), std::cos(s)}, 0.025);
  // A small patch 0.5 m above the floor 3 m ahead: 50 / 3 px against 50 / 6 px on the floor.
  w.Paint(2, 8, 16, 0, 8, {0.0, 0.5, 3.0}, {1, 0, 0}, {0, 0, 1}, 0.02);
  AnalysisOptions options = PlanesOnly();
  options.small_segments = SmallSegmentPolicy::kAll;
  options.min_plane_points = 30;
  AnalysisResult r = w.Analyze({}, options);
  ASSERT_TRUE(r.quality.passed) << r.quality.reason;
  ASSERT_TRUE(r.segments[1].small);
  ASSERT_EQ(r.segments[1].verdict, TravClass::kNonTraversable);  // 40 degrees by its own plane
  ASSERT_EQ(r.segments[2].verdict, TravClass::kNonTraversable);  // 0.5 m step

  AnalysisResult off = r;
  RefineByGroundDisparity(w.cloud_, w.ids_, kFocalTimesBaseline, options, &off);  // tolerance 0: off
  EXPECT_EQ(off.segments[1].verdict, TravClass::kNonTraversable);

  options.ground_tolerance_px = 1.0;
  RefineByGroundDisparity(w.cloud_, w.ids_, kFocalTimesBaseline, options, &r);
  EXPECT_EQ(r.segments[1].verdict, TravClass::kTraversable) << r.segments[1].reason;
  EXPECT_EQ(r.labels(3, 3), static_cast<std::uint8_t>(TravClass::kTraversable));
  EXPECT_EQ(r.segments[2].verdict, TravClass::kNonTraversable);
  EXPECT_EQ(r.labels(10, 3), static_cast<std::uint8_t>(TravClass::kNonTraversable));
  EXPECT_EQ(r.segments[0].verdict, TravClass::kTraversable);

  // The same far patch with a tolerance below its largest offset (~0.08 px) only partly agrees.
  options.ground_tolerance_px = 0.01;
  AnalysisResult tight = w.Analyze({}, options);
  RefineByGroundDisparity(w.cloud_, w.ids_, kFocalTimesBaseline, options, &tight);
  EXPECT_EQ(tight.segments[1].verdict, TravClass::kNonTraversable);
}

TEST(RefineByFragmentPlanes, FragmentsOnAnAdjacentPlaneTakeItsVerdict) {
  AnalyticWorld w(100, 100);
  PaintFloor(w, 0, 0, 100, 0, 60);
  // An 18 deg ramp, 0.6 m long from its foot: 1200 px (large), semi-traversable by slope, its
  // centroid 0.09 m above the floor.
  PaintRamp(w, 1, 0, 30, 60, 100, 18.0);
  const double s18 = 18.0 * M_PI / 180.0, s40 = 40.0 * M_PI / 180.0;
  const Eigen::Vector3d along18(0, -std::sin(s18), std::cos(s18));
  const Eigen::Vector3d ramp_point = Eigen::Vector3d(0.5, 1.0, 2.0) + 10 * 0.02 * along18 + Eigen::Vector3d(0.2, 0, 0);
  // A fragment of the ramp 4 cm across whose own plane tilts at 40 deg (noise): its points stay
  // within 1.5 cm of the ramp's plane, ~0.3 px of disparity here.
  w.Paint(2, 10, 18, 70, 78, ramp_point, {1, 0, 0}, {0, -std::sin(s40), std::cos(s40)}, 0.005);
  // A box top 0.3 m above the ramp's plane beside it: ~5 px off in disparity.
  const Eigen::Vector3d ramp_up(0, -std::cos(s18), -std::sin(s18));
  w.Paint(3, 20, 28, 88, 96, ramp_point + 0.3 * ramp_up + Eigen::Vector3d(0.36, 0.2 * -along18.y(), 0),
          {1, 0, 0}, along18, 0.02);
  // A tilted floor fragment cut off from every large segment by a ring without depth.
  for (int v = 79; v < 90; ++v) {
    for (int u = 19; u < 30; ++u) {
      w.cloud_(v, u) = NanVector3f();
      w.ids_(v, u) = -1;
    }
  }
  w.Paint(4, 80, 88, 20, 28, {-0.4, 1.0, 3.6}, {1, 0, 0}, {0, -std::sin(s40), std::cos(s40)}, 0.005);
  AnalysisOptions options = PlanesOnly();
  options.small_segments = SmallSegmentPolicy::kAll;
  options.min_plane_points = 30;
  AnalysisResult r = w.Analyze({}, options);
  ASSERT_TRUE(r.quality.passed) << r.quality.reason;
  ASSERT_FALSE(r.segments[1].small);
  ASSERT_EQ(r.segments[1].verdict, TravClass::kSemiTraversable) << r.segments[1].reason;
  for (const int id : {2, 3, 4}) {
    ASSERT_TRUE(r.segments[id].small) << id;
    ASSERT_EQ(r.segments[id].verdict, TravClass::kNonTraversable) << id << ": " << r.segments[id].reason;
  }

  AnalysisResult off = r;
  RefineByFragmentPlanes(w.cloud_, w.ids_, kFocalTimesBaseline, options, &off);  // tolerance 0: off
  EXPECT_EQ(off.segments[2].verdict, TravClass::kNonTraversable);

  options.fragment_tolerance_px = 1.5;
  RefineByFragmentPlanes(w.cloud_, w.ids_, kFocalTimesBaseline, options, &r);
  EXPECT_EQ(r.segments[2].verdict, TravClass::kSemiTraversable) << r.segments[2].reason;
  EXPECT_NE(r.segments[2].reason.find("segment 1"), std::string::npos) << r.segments[2].reason;
  EXPECT_EQ(r.labels(14, 74), static_cast<std::uint8_t>(TravClass::kSemiTraversable));
  EXPECT_EQ(r.segments[3].verdict, TravClass::kNonTraversable) << r.segments[3].reason;
  EXPECT_EQ(r.labels(24, 92), static_cast<std::uint8_t>(TravClass::kNonTraversable));
  EXPECT_EQ(r.segments[4].verdict, TravClass::kNonTraversable) << r.segments[4].reason;
  EXPECT_EQ(r.segments[0].verdict, TravClass::kTraversable);

  // Too tight a tolerance for the tilted fragment's spread: it keeps its own verdict.
  options.fragment_tolerance_px = 0.05;
  AnalysisResult tight = w.Analyze({}, options);
  RefineByFragmentPlanes(w.cloud_, w.ids_, kFocalTimesBaseline, options, &tight);
  EXPECT_EQ(tight.segments[2].verdict, TravClass::kNonTraversable);

  // A host may itself be below inliers_min (a ramp seen from afar), not below
  // fragment_host_min_points.
  options.fragment_tolerance_px = 1.5;
  options.inliers_min_ratio = 0.2;  // 2000 px: the 1200 px ramp is small now
  for (const int host_min : {1000, 1500}) {
    options.fragment_host_min_points = host_min;
    AnalysisResult small_host = w.Analyze({}, options);
    ASSERT_TRUE(small_host.segments[1].small);
    const TravClass ramp = small_host.segments[1].verdict;
    ASSERT_NE(ramp, TravClass::kNonTraversable) << small_host.segments[1].reason;
    RefineByFragmentPlanes(w.cloud_, w.ids_, kFocalTimesBaseline, options, &small_host);
    EXPECT_EQ(small_host.segments[2].verdict, host_min <= 1200 ? ramp : TravClass::kNonTraversable) << host_min;
  }
}

TEST(RefineByGroundDisparity, OnSemiTraversableGroundSmallSegmentsTakeItsClass) {
  // The ground is a 20 deg slope (no level ground in view): a small noisy fragment of it is
  // semi-traversable like the slope, not traversable.
  AnalyticWorld w(100, 100);
  PaintRamp(w, 0, 0, 100, 0, 100, 20.0);
  const double s = 20.0 * M_PI / 180.0, tilted = 60.0 * M_PI / 180.0;
  // Through the ramp's point 3 m up its slope, tilted 40 deg more: its far edge 0.13 m off it.
  w.Paint(1, 0, 8, 0, 8, {0.0, 1.0 - 3.0 * std::sin(s), 2.0 + 3.0 * std::cos(s)}, {1, 0, 0},
          {0, -std::sin(tilted), std::cos(tilted)}, 0.025);
  AnalysisOptions options = PlanesOnly();
  options.small_segments = SmallSegmentPolicy::kAll;
  options.min_plane_points = 30;
  AnalysisResult r = w.Analyze({}, options);
  ASSERT_TRUE(r.quality.passed) << r.quality.reason;
  ASSERT_EQ(r.ground.surface_class, TravClass::kSemiTraversable);
  ASSERT_TRUE(r.segments[1].small);
  ASSERT_EQ(r.segments[1].verdict, TravClass::kNonTraversable);  // 60 degrees by its own plane
  options.ground_tolerance_px = 1.0;
  RefineByGroundDisparity(w.cloud_, w.ids_, kFocalTimesBaseline, options, &r);
  EXPECT_EQ(r.segments[1].verdict, TravClass::kSemiTraversable) << r.segments[1].reason;
  EXPECT_EQ(r.labels(3, 3), static_cast<std::uint8_t>(TravClass::kSemiTraversable));
}

TEST(RefineByGroundDisparity, LargeSegmentsKeepTheirVerdicts) {
  AnalyticWorld w(100, 100);
  PaintFloor(w, 0, 0, 100, 0, 80);
  PaintRamp(w, 1, 0, 100, 80, 100, 40.0);  // 2000 px: large, steep, starting on the floor
  AnalysisOptions options = PlanesOnly();
  options.ground_tolerance_px = 16.0;  // everything near the floor would pass
  AnalysisResult r = w.Analyze({}, options);
  ASSERT_FALSE(r.segments[1].small);
  ASSERT_EQ(r.segments[1].verdict, TravClass::kNonTraversable);
  RefineByGroundDisparity(w.cloud_, w.ids_, kFocalTimesBaseline, options, &r);
  EXPECT_EQ(r.segments[1].verdict, TravClass::kNonTraversable);
}

TEST(RefineByPixelSlope, SteepPixelsOfATraversableSegmentTakeTheirSlopeClass) {
  const Eigen::Vector3d up(0, -1, 0);
  auto normal_at = [&](double deg) {
    const double r = deg * M_PI / 180.0;
    return Eigen::Vector3f(0, -std::cos(r), -std::sin(r));
  };
  Image3f normals(5, 1, NanVector3f());
  ImageU8 labels(5, 1, 1);
  normals[0] = normal_at(5);   // stays traversable
  normals[1] = normal_at(20);  // semi by slope
  normals[2] = normal_at(40);  // non-traversable by slope
  labels[3] = 3;               // already an obstacle: never improved
  normals[3] = normal_at(0);
  labels[4] = 2;               // NaN normal: left as is
  RefineByPixelSlope(normals, up, VehicleOptions{}, &labels);
  EXPECT_EQ(labels[0], 1);
  EXPECT_EQ(labels[1], 2);
  EXPECT_EQ(labels[2], 3);
  EXPECT_EQ(labels[3], 3);
  EXPECT_EQ(labels[4], 2);
}

TEST(ApplyPixelSlopeClasses, UnderTheLocalRuleAGentlerPixelRelaxesItsSemiTraversableSegment) {
  // One segment averaging a hillside from 10 to 20 deg reads 16 deg (semi-traversable); the
  // pixels' own slopes say which part is gentler than 15 deg.
  const Eigen::Vector3d up(0, -1, 0);
  auto normal_at = [](double deg) {
    const double r = deg * M_PI / 180.0;
    return Eigen::Vector3f(0, -static_cast<float>(std::cos(r)), -static_cast<float>(std::sin(r)));
  };
  Image3f normals(6, 1, NanVector3f());
  const double slopes[] = {10, 14, 16, 20, 30, 0};
  for (int u = 0; u < 5; ++u) normals[u] = normal_at(slopes[u]);  // pixel 5: no normal
  ImageU8 slope_classes;
  PixelSlopeClasses(normals, up, VehicleOptions{}, nullptr, 1, &slope_classes);
  EXPECT_EQ(slope_classes[0], 1);
  EXPECT_EQ(slope_classes[2], 2);
  EXPECT_EQ(slope_classes[4], 3);
  EXPECT_EQ(slope_classes[5], 0);

  ImageU8 relaxed(6, 1, 2);
  ApplyPixelSlopeClasses(slope_classes, &relaxed, true);
  const std::vector<int> expected_relaxed = {1, 1, 2, 2, 3, 2};
  ImageU8 worse_only(6, 1, 2);
  ApplyPixelSlopeClasses(slope_classes, &worse_only);  // the other step rules: semi may be a step
  const std::vector<int> expected_worse_only = {2, 2, 2, 2, 3, 2};
  for (int u = 0; u < 6; ++u) {
    EXPECT_EQ(relaxed[u], expected_relaxed[u]) << u;
    EXPECT_EQ(worse_only[u], expected_worse_only[u]) << u;
  }
  // Obstacles and undecided pixels are never relaxed.
  ImageU8 other(6, 1, 3);
  other[1] = 4;
  ApplyPixelSlopeClasses(slope_classes, &other, true);
  EXPECT_EQ(other[0], 3);
  EXPECT_EQ(other[1], 4);
}

TEST(RefineByPixelSlope, AveragingInsideTheSegmentStopsTheFlicker) {
  // A 13 deg slope (traversable, semi from 15 deg) whose pixel normals alternate 13 +- 4 deg in
  // a checkerboard, as stereo noise does: one pixel in two reads 17 deg. Beside it, in another
  // segment, a 40 deg ramp that must not leak into the averages.
  const Eigen::Vector3d up(0, -1, 0);
  auto normal_at = [](double deg) {
    const double r = deg * M_PI / 180.0;
    return Eigen::Vector3f(0, -static_cast<float>(std::cos(r)), -static_cast<float>(std::sin(r)));
  };
  const int w = 40, h = 20;
  Image3f normals(w, h, NanVector3f());
  ImageI32 ids(w, h, 0);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      if (u >= 30) {
        ids(v, u) = 1;
        normals(v, u) = normal_at(40);
      } else {
        normals(v, u) = normal_at((u + v) % 2 ? 17.0 : 9.0);
      }
    }
  }
  auto count_semi = [&](const ImageU8& labels) {
    int semi = 0;
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < 30; ++u) semi += labels(v, u) == 2;
    }
    return semi;
  };
  ImageU8 own(w, h, 1);
  RefineByPixelSlope(normals, up, VehicleOptions{}, &own);
  EXPECT_EQ(count_semi(own), 30 * h / 2);  // every other pixel flips

  ImageU8 averaged(w, h, 1);
  RefineByPixelSlope(normals, up, VehicleOptions{}, &averaged, &ids, 7);
  EXPECT_EQ(count_semi(averaged), 0);
  for (int v = 0; v < h; ++v) {
    EXPECT_EQ(averaged(v, 29), 1) << "row " << v;   // next to the ramp: the ramp did not leak in
    EXPECT_EQ(averaged(v, 30), 3) << "row " << v;   // the ramp keeps its own slope
  }
}

// Disparity of a camera 0.8 m above level ground, pitched 15 deg down (f 420 px, b 0.12 m,
// 640 x 480): ground up to `face_m` ahead, then a vertical face `height_m` tall towards the
// camera and the level top of the step behind it; or, with `ramp_deg` > 0, a ramp rising away at
// that angle from `face_m` on. Ray cast in closed form: d = b / t for the hit at t * (u-cu, v-cv, f).
struct StepScene {
  static constexpr double kF = 420, kB = 0.12, kH = 0.8, kCu = 320, kCv = 240;
  double pitch = 15 * M_PI / 180;
  double face_m = 3.0, height_m = 0.15, ramp_deg = 0.0;
  Eigen::Vector3d Up() const { return {0, -std::cos(pitch), -std::sin(pitch)}; }
  Eigen::Vector3d Forward() const { return {0, -std::sin(pitch), std::cos(pitch)}; }
  /// 0: ground, 1: face (or ramp), 2: top, -1: sky.
  int Hit(int u, int v, double* t) const {
    const Eigen::Vector3d r(u - kCu, v - kCv, kF);
    const double ru = Up().dot(r), rf = Forward().dot(r);
    if (ramp_deg > 0) {
      // Ramp plane through the ground line at face_m, normal tilted towards the camera.
      const double a = ramp_deg * M_PI / 180;
      const Eigen::Vector3d n = std::cos(a) * Up() - std::sin(a) * Forward();
      const Eigen::Vector3d p0 = -kH * Up() + face_m * Forward();
      if (ru < 0 && -kH / ru * rf < face_m) {
        *t = -kH / ru;
        return 0;
      }
      const double nr = n.dot(r);
      if (nr >= 0) return -1;
      *t = n.dot(p0) / nr;
      return 1;
    }
    if (ru < 0 && -kH / ru * rf < face_m) {
      *t = -kH / ru;
      return 0;
    }
    if (rf > 0) {
      const double tf = face_m / rf;
      const double above = tf * ru + kH;  // height of the hit above the ground
      if (above >= 0 && above <= height_m) {
        *t = tf;
        return 1;
      }
    }
    if (Up().dot(r) < 0) {
      *t = -(kH - height_m) / ru;
      return 2;
    }
    return -1;
  }
  void Render(ImageF* disparity, ImageI32* part) const {
    *disparity = ImageF(640, 480, std::numeric_limits<float>::quiet_NaN());
    *part = ImageI32(640, 480, -1);
    for (int v = 0; v < 480; ++v) {
      for (int u = 0; u < 640; ++u) {
        double t = 0;
        const int hit = Hit(u, v, &t);
        (*part)(v, u) = hit;
        if (hit >= 0) (*disparity)(v, u) = static_cast<float>(kB / t);
      }
    }
  }
};

AnalysisOptions FaceOptions() {
  AnalysisOptions o = PlanesOnly();
  o.face_window_px = 11;
  o.face_min_slope_deg = 40;
  return o;
}

TEST(RefineByDisparityFaces, FindsTheFrontOfACurbAndLeavesGroundAndTopAlone) {
  StepScene scene;  // a 15 cm curb 3 m ahead: its face spans ~20 rows
  ImageF d;
  ImageI32 part;
  scene.Render(&d, &part);
  ImageU8 labels(640, 480, 1);
  RefineByDisparityFaces(d, StepScene::kF, StepScene::kCu, StepScene::kCv, scene.Up(), FaceOptions(), &labels);
  // Rows of the face in the centre column, and the counts per part away from its borders (the
  // 11-row windows of the 5 rows next to a border straddle it).
  int face_rows = 0, face_hits = 0, ground_hits = 0, top_hits = 0, ground_far = 0, top_far = 0;
  for (int v = 0; v < 480; ++v) {
    face_rows += part(v, 320) == 1;
    for (int u = 0; u < 640; ++u) {
      bool near_border = false;
      for (int j = -6; j <= 6 && !near_border; ++j) {
        near_border = v + j >= 0 && v + j < 480 && part(v + j, u) != part(v, u);
      }
      if (near_border) continue;
      const bool face = labels(v, u) == 3;
      face_hits += part(v, u) == 1 && face;
      ground_far += part(v, u) == 0;
      ground_hits += part(v, u) == 0 && face;
      top_far += part(v, u) == 2;
      top_hits += part(v, u) == 2 && face;
    }
  }
  EXPECT_GE(face_rows, 18);
  EXPECT_LE(face_rows, 24);
  int face_inner = 0;
  for (int v = 0; v < 480; ++v) {
    for (int u = 0; u < 640; ++u) {
      bool inner = part(v, u) == 1;
      for (int j = -6; j <= 6 && inner; ++j) inner = v + j >= 0 && v + j < 480 && part(v + j, u) == 1;
      face_inner += inner;
    }
  }
  ASSERT_GT(face_inner, 640 * 5);
  EXPECT_EQ(face_hits, face_inner);  // every face pixel whose window lies on the face
  EXPECT_GT(ground_far, 100000);
  EXPECT_EQ(ground_hits, 0);
  EXPECT_GT(top_far, 10000);
  EXPECT_EQ(top_hits, 0);
}

TEST(RefineByDisparityFaces, KeepsRampsGentlerThanTheThresholdAndOnlyTouchesDrivableOrUndecided) {
  for (const double ramp : {18.0, 30.0, 50.0}) {
    StepScene scene;
    scene.ramp_deg = ramp;
    scene.face_m = 4.0;
    ImageF d;
    ImageI32 part;
    scene.Render(&d, &part);
    ImageU8 labels(640, 480, 2);
    RefineByDisparityFaces(d, StepScene::kF, StepScene::kCu, StepScene::kCv, scene.Up(), FaceOptions(), &labels);
    int ramp_px = 0, flagged = 0;
    for (int v = 6; v < 474; ++v) {
      for (int u = 0; u < 640; ++u) {
        bool inner = part(v, u) == 1;
        for (int j = -6; j <= 6 && inner; ++j) inner = part(v + j, u) == 1;
        if (!inner) continue;
        ++ramp_px;
        flagged += labels(v, u) == 3;
      }
    }
    ASSERT_GT(ramp_px, 1000) << ramp;
    // The tangent along a column of a plane rising away lies in the plane: its slope along
    // the column is below the ramp's, and equal at the centre column.
    if (ramp < 40) {
      EXPECT_EQ(flagged, 0) << ramp;
    } else {
      EXPECT_GT(flagged, ramp_px * 9 / 10) << ramp;
    }
  }
  // Classes other than 1, 2 and 4 stay as they are; 4 (undecided) on a face becomes 3.
  StepScene scene;
  ImageF d;
  ImageI32 part;
  scene.Render(&d, &part);
  int v_face = -1;
  for (int v = 0; v < 480 && v_face < 0; ++v) {
    if (part(v, 320) == 1 && part(v - 6, 320) == 1 && part(v + 6, 320) == 1) v_face = v;
  }
  ASSERT_GE(v_face, 0);
  for (const std::uint8_t c : {0, 3, 4}) {
    ImageU8 labels(640, 480, c);
    RefineByDisparityFaces(d, StepScene::kF, StepScene::kCu, StepScene::kCv, scene.Up(), FaceOptions(), &labels);
    EXPECT_EQ(labels(v_face, 320), c == 4 ? 3 : c) << int(c);
  }
}

TEST(RefineByDisparityFaces, IgnoresBoundedNoiseOnGroundAndDepthEdges) {
  StepScene scene;
  scene.face_m = 100.0;  // no face in view: ground only
  ImageF d;
  ImageI32 part;
  scene.Render(&d, &part);
  // Uniform noise of +-0.17 px (about SGBM's spread, sigma 0.1 px), from a fixed LCG.
  std::uint32_t state = 12345;
  for (std::size_t i = 0; i < d.size(); ++i) {
    state = state * 1664525u + 1013904223u;
    if (std::isfinite(d[i])) d[i] += static_cast<float>(((state >> 8) / 16777216.0 - 0.5) * 0.34);
  }
  // A hole: columns 300..339 from row 300 down lie 3 px of disparity farther than the ground
  // (a window across its upper edge fits a falling disparity, which reads as a steep surface
  // unless the jump stops it). A near box: columns 400..439 from row 300 down at 1.5 m.
  for (int v = 300; v < 480; ++v) {
    for (int u = 300; u < 340; ++u) d(v, u) -= 3.0f;
    for (int u = 400; u < 440; ++u) d(v, u) = static_cast<float>(StepScene::kF * StepScene::kB / 1.5);
  }
  ImageU8 labels(640, 480, 1);
  RefineByDisparityFaces(d, StepScene::kF, StepScene::kCu, StepScene::kCv, scene.Up(), FaceOptions(), &labels);
  int flagged_ground = 0, valid = 0;
  for (int v = 0; v < 480; ++v) {
    for (int u = 0; u < 640; ++u) {
      if (u >= 400 && u < 440 && v >= 295) continue;  // the box and the windows touching its top
      valid += std::isfinite(d(v, u));
      flagged_ground += labels(v, u) == 3;
    }
  }
  ASSERT_GT(valid, 150000);
  EXPECT_EQ(flagged_ground, 0);
  // The box's face towards the camera (constant disparity) is a face.
  EXPECT_EQ(labels(400, 420), 3);
}

TEST(RefineByDisparityFaces, PoolingColumnsFindsALowCurbThatNoiseHidesFromOneColumn) {
  StepScene scene;  // a 5 cm curb 3 m ahead: its face spans ~7 rows, fewer than the window
  scene.height_m = 0.05;
  ImageF d;
  ImageI32 part;
  scene.Render(&d, &part);
  // SGBM's errors on ground are stripes along the rows (its pull of sub-pixel disparities to
  // whole pixels) that shift from column to column as the camera rolls: here a ripple of
  // AMP px and a 22-row period along each column, with a random phase per column (fixed
  // LCG). One column's fit reads the ripple's flanks as flat (face-like) or steep.
  std::uint32_t state = 777;
  auto uniform = [&state] {
    state = state * 1664525u + 1013904223u;
    return (state >> 8) / 16777216.0;
  };
  for (int u = 0; u < 640; ++u) {
    const double phase = 2 * M_PI * uniform();
    for (int v = 0; v < 480; ++v) {
      if (std::isfinite(d(v, u))) d(v, u) += static_cast<float>(0.4 * std::sin(2 * M_PI * v / 22.0 + phase));
    }
  }
  // A near box beside the curb, columns 560..599 from row 200 down at 0.5 m: its front (d' = 0,
  // d four times the ground's) must not leak into the pooled fits of the ground columns next
  // to it (pooled with 8 of its columns, the ground would read 44 deg).
  for (int v = 200; v < 480; ++v) {
    for (int u = 560; u < 600; ++u) d(v, u) = static_cast<float>(StepScene::kF * StepScene::kB / 0.5);
  }
  struct Counts {
    int face_px = 0, face_hits = 0, far_px = 0, far_hits = 0, beside_px = 0, beside_hits = 0;
  };
  auto run = [&](int columns) {
    AnalysisOptions o = FaceOptions();
    o.face_min_slope_deg = 35;
    o.face_columns_px = columns;
    ImageU8 labels(640, 480, 1);
    RefineByDisparityFaces(d, StepScene::kF, StepScene::kCu, StepScene::kCv, scene.Up(), o, &labels);
    Counts n;
    for (int v = 8; v < 472; ++v) {
      for (int u = 0; u < 560; ++u) {
        bool near_face = false;
        for (int j = -8; j <= 8 && !near_face; ++j) near_face = part(v + j, u) == 1;
        const bool flagged = labels(v, u) == 3;
        if (u >= 20 && u < 520 && part(v, u) == 1) {
          ++n.face_px;
          n.face_hits += flagged;
        } else if (u >= 20 && u < 520 && !near_face && part(v, u) >= 0) {
          ++n.far_px;
          n.far_hits += flagged;
        } else if (u >= 540 && v >= 210 && !near_face && part(v, u) >= 0) {
          ++n.beside_px;  // the 20 columns left of the box, below its top
          n.beside_hits += flagged;
        }
      }
    }
    return n;
  };
  const Counts alone = run(1), pooled = run(17);
  ASSERT_GT(alone.face_px, 640 * 5);
  ASSERT_GT(alone.far_px, 150000);
  ASSERT_GT(alone.beside_px, 3000);
  // One column alone reads the ripple as faces all over the ground; pooled, the ripples' random
  // phases cancel: no ground pixel is flagged (the box's ground neighbours included), and a
  // third of the curb's face still is (the 11-row windows straddle its 7 rows; noise-free 39 %).
  EXPECT_GT(alone.far_hits, alone.far_px / 100);
  EXPECT_EQ(pooled.far_hits, 0);
  EXPECT_EQ(pooled.beside_hits, 0);
  EXPECT_GT(pooled.face_hits, pooled.face_px / 4);
}

TEST(RefineByDisparityFaces, GrowsAFaceOverAllItsRowsAndNoFurther) {
  for (const double height : {0.08, 0.12}) {
    StepScene scene;  // a curb 3 m ahead whose face spans 11 (8 cm) or 16 (12 cm) rows
    scene.height_m = height;
    ImageF d;
    ImageI32 part;
    scene.Render(&d, &part);
    auto run = [&](double grow_px, int* face_hits, int* face_px, int* off_hits) {
      AnalysisOptions o = FaceOptions();
      o.face_grow_tolerance_px = grow_px;
      ImageU8 labels(640, 480, 1);
      RefineByDisparityFaces(d, StepScene::kF, StepScene::kCu, StepScene::kCv, scene.Up(), o, &labels);
      *face_hits = *face_px = *off_hits = 0;
      for (int v = 2; v < 478; ++v) {
        for (int u = 0; u < 640; ++u) {
          const bool flagged = labels(v, u) == 3;
          if (part(v, u) == 1) {
            ++*face_px;
            *face_hits += flagged;
          } else if (part(v - 2, u) != 1 && part(v + 2, u) != 1) {
            *off_hits += flagged;  // ground or top more than 2 rows from the face
          }
        }
      }
    };
    int before_hits, after_hits, face_px, before_off, after_off;
    run(0.0, &before_hits, &face_px, &before_off);
    run(0.25, &after_hits, &face_px, &after_off);
    ASSERT_GT(face_px, 640 * 6) << height;
    // The line fits over 11 rows flag the rows where the window lies mostly on the face (55 %
    // and 73 % of them here); grown from the rows steeper than 70 deg, every row of it. The ground at the face's foot and the top at its edge lie at the face's
    // depth: within 0.25 px of its disparity for 0.25 / (b / h) ~ 2 rows, no further.
    EXPECT_LT(before_hits, face_px * 4 / 5) << height;
    EXPECT_GT(after_hits, face_px * 97 / 100) << height;
    EXPECT_EQ(before_off, 0) << height;
    EXPECT_EQ(after_off, 0) << height;
  }
}

// The organized cloud of a StepScene disparity: X = (u - cu, v - cv, f) b / d.
Image3f StepSceneCloud(const ImageF& d) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  Image3f cloud(d.width(), d.height(), Eigen::Vector3f(nan, nan, nan));
  for (int v = 0; v < d.height(); ++v) {
    for (int u = 0; u < d.width(); ++u) {
      if (!(d(v, u) > 0)) continue;
      const double t = StepScene::kB / d(v, u);
      cloud(v, u) = Eigen::Vector3d((u - StepScene::kCu) * t, (v - StepScene::kCv) * t, StepScene::kF * t).cast<float>();
    }
  }
  return cloud;
}

TEST(JudgeFacesByHeight, AFaceIsAStepOfItsHeight) {
  // Curbs 3 m ahead, judged by the default vehicle (semi step 0.10 m, max step 0.20 m): the
  // face test flags them all; their height then decides, as the class rule decides a step.
  const VehicleOptions vehicle;
  struct Case {
    double height_m;
    int expected;
  };
  for (const Case c : {Case{0.30, 3}, Case{0.15, 2}, Case{0.07, 1}}) {
    StepScene scene;
    scene.height_m = c.height_m;
    ImageF d;
    ImageI32 part;
    scene.Render(&d, &part);
    AnalysisOptions o = FaceOptions();
    o.face_min_slope_deg = 35;
    const ImageU8 before(640, 480, 1);
    ImageU8 labels = before;
    RefineByDisparityFaces(d, StepScene::kF, StepScene::kCu, StepScene::kCv, scene.Up(), o, &labels);
    int face_px = 0, flagged = 0;
    for (int v = 0; v < 480; ++v) {
      face_px += part(v, 320) == 1;
      flagged += part(v, 320) == 1 && labels(v, 320) == 3;
    }
    ASSERT_GE(flagged, face_px / 2) << c.height_m;  // the test found the face first
    JudgeFacesByHeight(StepSceneCloud(d), scene.Up(), vehicle, before, &labels);
    int right = 0, face_inner = 0, off_face_changed = 0;
    for (int v = 1; v < 479; ++v) {
      for (int u = 0; u < 640; ++u) {
        if (part(v, u) == 1 && labels(v, u) != 1) right += labels(v, u) == c.expected;
        face_inner += part(v, u) == 1 && labels(v, u) != 1;
        // Ground and top more than 2 rows from the face are never the face's.
        if (part(v, u) != 1 && part(v - 1, u) != 1 && part(v + 1, u) != 1 && v > 2 && v < 477 &&
            part(v - 2, u) != 1 && part(v + 2, u) != 1) {
          off_face_changed += labels(v, u) != 1;
        }
      }
    }
    if (c.expected == 1) {
      EXPECT_EQ(face_inner, 0) << c.height_m;  // every flagged pixel went back to traversable
    } else {
      ASSERT_GT(face_inner, 640 * 5) << c.height_m;
      EXPECT_EQ(right, face_inner) << c.height_m;
    }
    EXPECT_EQ(off_face_changed, 0) << c.height_m;
  }
}

TEST(JudgeFacesByHeight, APlateauOfTheMatcherOnGroundIsNoHazardAndOtherRulesStand) {
  // Level ground; SGBM's smoothness holds one disparity over 17 rows of it (rows 300-316 take
  // row 308's), which the face test reads as a face: 17 rows about 2 m away are 8 cm of height.
  StepScene scene;
  scene.face_m = 100.0;
  ImageF d;
  ImageI32 part;
  scene.Render(&d, &part);
  for (int v = 300; v <= 316; ++v) {
    for (int u = 0; u < 640; ++u) d(v, u) = d(308, u);
  }
  AnalysisOptions o = FaceOptions();
  o.face_min_slope_deg = 35;
  ImageU8 before(640, 480, 1);
  // Another rule's obstacle in the plateau (columns 100-109) and undecided pixels (200-209).
  for (int v = 300; v <= 316; ++v) {
    for (int u = 100; u < 110; ++u) before(v, u) = 3;
    for (int u = 200; u < 210; ++u) before(v, u) = 4;
  }
  ImageU8 labels = before;
  RefineByDisparityFaces(d, StepScene::kF, StepScene::kCu, StepScene::kCv, scene.Up(), o, &labels);
  int flagged = 0;
  for (int v = 300; v <= 316; ++v) flagged += labels(v, 320) == 3;
  ASSERT_GE(flagged, 5);  // without its height the plateau is a face
  JudgeFacesByHeight(StepSceneCloud(d), scene.Up(), VehicleOptions(), before, &labels);
  int changed = 0;
  for (std::size_t i = 0; i < labels.size(); ++i) changed += labels[i] != before[i];
  EXPECT_EQ(changed, 0);
}

TEST(FillUndecidedByConsensus, TakesTheClassOfAClearMajorityOnlyAndInOnePass) {
  AnalysisOptions options = PlanesOnly();
  options.undecided_fill_radius_px = 1;
  options.undecided_fill_share = 0.9;
  // Row 1: undecided amid 8 traversable -> traversable. Row 4: 7 traversable and 1
  // non-traversable around it (0.875 < 0.9) -> stays. Unknown (0) neighbours do not vote.
  ImageU8 labels(5, 9, 1);
  labels(1, 2) = 4;
  labels(4, 2) = 4;
  labels(3, 3) = 3;
  labels(7, 2) = 4;
  labels(6, 1) = labels(6, 2) = labels(6, 3) = labels(7, 1) = 0;  // unknown above and left
  ImageU8 before = labels;
  FillUndecidedByConsensus(options, &labels);
  EXPECT_EQ(labels(1, 2), 1);
  EXPECT_EQ(labels(4, 2), 4);
  EXPECT_EQ(labels(7, 2), 1);  // 4 traversable voters, 4 unknown
  EXPECT_EQ(labels(3, 3), 3);
  options.undecided_fill_share = 0.85;
  FillUndecidedByConsensus(options, &before);
  EXPECT_EQ(before(4, 2), 1);
  // Off: nothing changes.
  ImageU8 off(5, 5, 1);
  off(2, 2) = 4;
  options.undecided_fill_radius_px = 0;
  FillUndecidedByConsensus(options, &off);
  EXPECT_EQ(off(2, 2), 4);
}

TEST(FillUndecidedByConsensus, FillsAPointHeldBesideAJumpOnlyWithTheObstacle) {
  AnalysisOptions options = PlanesOnly();
  options.undecided_fill_radius_px = 1;
  options.undecided_fill_share = 0.9;
  // Left half traversable, right half non-traversable; in each, one undecided pixel that the
  // local steps held undecided beside a jump (step class 4) and one they did not (0).
  ImageU8 labels(12, 5, 1);
  for (int v = 0; v < 5; ++v) {
    for (int u = 6; u < 12; ++u) labels(v, u) = 3;
  }
  labels(1, 2) = labels(3, 2) = labels(1, 9) = labels(3, 9) = 4;
  ImageU8 step_classes(12, 5, 0);
  step_classes(1, 2) = step_classes(1, 9) = 4;
  step_classes(2, 2) = 4;  // a decided pixel the rule also flagged: untouched, still votes
  const ImageU8 before = labels;
  FillUndecidedByConsensus(options, &labels, &step_classes);
  EXPECT_EQ(labels(1, 2), 4);  // amid open ground the doubt stays
  EXPECT_EQ(labels(3, 2), 1);  // no jump beside it: filled as before
  EXPECT_EQ(labels(1, 9), 3);  // amid the obstacle it takes the obstacle's class
  EXPECT_EQ(labels(3, 9), 3);
  EXPECT_EQ(labels(2, 2), 1);
  // Without the step classes every one of them is filled.
  ImageU8 unheld = before;
  FillUndecidedByConsensus(options, &unheld);
  EXPECT_EQ(unheld(1, 2), 1);
  EXPECT_EQ(unheld(1, 9), 3);
  // Step classes of another size are refused.
  ImageU8 wrong(5, 5, 0);
  EXPECT_THROW(FillUndecidedByConsensus(options, &unheld, &wrong), InternalError);
}

TEST(FillUndecidedByConsensus, LeavesSplitWindowsAndWideGapsUndecided) {
  AnalysisOptions options = PlanesOnly();
  options.undecided_fill_radius_px = 4;
  // Traversable left of column 20, non-traversable from column 22, undecided in columns 20-21
  // (an obstacle's outline), and a 12 px wide band of undecided rows 30..41 across the image.
  ImageU8 labels(40, 60, 1);
  for (int v = 0; v < 60; ++v) {
    for (int u = 0; u < 40; ++u) {
      if (u >= 22) labels(v, u) = 3;
      if (u == 20 || u == 21 || (v >= 30 && v < 42)) labels(v, u) = 4;
    }
  }
  FillUndecidedByConsensus(options, &labels);
  EXPECT_EQ(labels(10, 20), 4);  // 4 columns of each class in its window: split
  EXPECT_EQ(labels(10, 21), 4);
  EXPECT_EQ(labels(31, 5), 1);   // the band's edge rows see traversable rows within 4 px
  EXPECT_EQ(labels(31, 35), 3);
  EXPECT_EQ(labels(35, 5), 4);   // its middle sees no decided pixel: one pass, no spreading
  EXPECT_EQ(labels(36, 35), 4);
}

TEST(FillUndecidedByHeight, DrivableHeightsTakeTheirStepClassHigherPointsStayUndecided) {
  // Floor 1 m below the camera (segment 0); single unsegmented points (undecided) at known
  // heights above it. A point h above the floor at depth Z lies fb h / (Z D) px off the floor's
  // disparity on its ray (D = 1 m, fb = 50 px m).
  AnalyticWorld w(100, 100);
  PaintFloor(w, 0, 0, 100, 0, 100);
  auto point_at = [&](int v, int u, double height_m, double depth_m) {
    w.cloud_(v, u) = Eigen::Vector3f(0.0f, static_cast<float>(1.0 - height_m), static_cast<float>(depth_m));
    w.ids_(v, u) = -1;
  };
  point_at(10, 10, 0.05, 3.0);   // 0.83 px off: ground within stereo noise -> traversable
  point_at(20, 10, 0.15, 2.0);   // 3.75 px off, step 0.15 m -> semi-traversable
  point_at(30, 10, 0.15, 20.0);  // 0.375 px off: at 20 m stereo cannot tell it from the floor
  point_at(40, 10, 0.50, 3.0);   // step 0.5 m: not drivable, stays undecided
  point_at(50, 10, -0.25, 3.0);  // 0.25 m below the floor (a brink's smeared point): stays
  point_at(55, 10, -0.15, 2.0);  // 0.15 m below: a hole's far wall as likely as its floor: stays
  point_at(57, 10, -0.05, 3.0);  // 0.05 m below, 0.83 px off: ground within noise -> traversable
  w.cloud_(60, 10) = NanVector3f();  // no depth: stays unknown
  w.ids_(60, 10) = -1;
  AnalysisOptions options = PlanesOnly();
  options.ground_tolerance_px = 1.0;
  options.undecided_height_fill = true;
  const AnalysisResult analysed = w.Analyze({}, options);
  ASSERT_TRUE(analysed.quality.passed) << analysed.quality.reason;
  ASSERT_EQ(analysed.labels(10, 10), static_cast<std::uint8_t>(TravClass::kUndecided));
  const auto label = [](const AnalysisResult& r, int v, int u) { return static_cast<TravClass>(r.labels(v, u)); };

  AnalysisResult r = analysed;
  FillUndecidedByHeight(w.cloud_, kFocalTimesBaseline, VehicleOptions{}, options, &r);
  EXPECT_EQ(label(r, 10, 10), TravClass::kTraversable);
  EXPECT_EQ(label(r, 20, 10), TravClass::kSemiTraversable);
  EXPECT_EQ(label(r, 30, 10), TravClass::kTraversable);
  EXPECT_EQ(label(r, 40, 10), TravClass::kUndecided);
  EXPECT_EQ(label(r, 50, 10), TravClass::kUndecided);
  EXPECT_EQ(label(r, 55, 10), TravClass::kUndecided);
  EXPECT_EQ(label(r, 57, 10), TravClass::kTraversable);
  EXPECT_EQ(label(r, 60, 10), TravClass::kUnknown);
  EXPECT_EQ(label(r, 70, 70), TravClass::kTraversable);  // the floor keeps its verdict

  // Without the disparity tolerance the far point is judged by its height alone.
  AnalysisOptions no_tolerance = options;
  no_tolerance.ground_tolerance_px = 0.0;
  AnalysisResult by_height = analysed;
  FillUndecidedByHeight(w.cloud_, kFocalTimesBaseline, VehicleOptions{}, no_tolerance, &by_height);
  EXPECT_EQ(label(by_height, 30, 10), TravClass::kSemiTraversable);
  EXPECT_EQ(label(by_height, 10, 10), TravClass::kTraversable);  // 0.05 m < semi_step_m

  // Off, or in a frame that failed the quality check: nothing changes.
  AnalysisOptions off = options;
  off.undecided_height_fill = false;
  AnalysisResult unchanged = analysed;
  FillUndecidedByHeight(w.cloud_, kFocalTimesBaseline, VehicleOptions{}, off, &unchanged);
  EXPECT_EQ(label(unchanged, 20, 10), TravClass::kUndecided);
  AnalysisResult failed = analysed;
  failed.quality.passed = false;
  FillUndecidedByHeight(w.cloud_, kFocalTimesBaseline, VehicleOptions{}, options, &failed);
  EXPECT_EQ(label(failed, 20, 10), TravClass::kUndecided);
}


// Local steps on analytic worlds: a floor 1 m below the camera with a box on it, seen from above
// (the world is painted straight into the cloud; the normals are the surfaces' own).
struct StepWorld {
  StepWorld(int width, int height) : cloud(width, height, NanVector3f()), normals(width, height, NanVector3f()),
                                     labels(width, height, 1) {}
  /// A level patch at `height_m` below the camera over x in [x0, x1), z in [z0, z1), 1 cm spacing.
  void Level(double x0, double x1, double z0, double z1, double height_m) { Slope(x0, x1, z0, z1, height_m, 0.0); }
  /// Ground rising `rise` m per m ahead over x in [x0, x1), z in [z0, z1): `height_m` below the
  /// camera at z = 1, its normals the slope's own.
  void Slope(double x0, double x1, double z0, double z1, double height_m, double rise) {
    const Eigen::Vector3f n = Eigen::Vector3f(0, -1, static_cast<float>(-rise)).normalized();
    for (int v = 0; v < cloud.height(); ++v) {
      for (int u = 0; u < cloud.width(); ++u) {
        const double x = -1.0 + 0.01 * u, z = 1.0 + 0.01 * v;
        if (x < x0 || x >= x1 || z < z0 || z >= z1) continue;
        cloud(v, u) = Eigen::Vector3f(static_cast<float>(x), static_cast<float>(height_m - rise * (z - 1.0)),
                                      static_cast<float>(z));
        normals(v, u) = n;
      }
    }
  }
  Image3f cloud, normals;
  ImageU8 labels;
};

/// The pixel of a StepWorld-sized image at (x, z).
std::uint8_t PixelAt(const ImageU8& image, double x, double z) {
  return image(static_cast<int>(std::lround((z - 1.0) / 0.01)), static_cast<int>(std::lround((x + 1.0) / 0.01)));
}

std::uint8_t LabelAt(const StepWorld& w, double x, double z) { return PixelAt(w.labels, x, z); }

TEST(RefineByLocalSteps, LevelGroundStaysTraversableAtAnyHeight) {
  StepWorld w(200, 200);
  w.Level(-1, 1, 1, 3, 1.0);
  RefineByLocalSteps(w.cloud, w.normals, {0, -1, 0}, VehicleOptions{}, DepthNoise{}, &w.labels);
  for (std::size_t i = 0; i < w.labels.size(); ++i) ASSERT_EQ(w.labels[i], 1) << i;
  StepWorld low(200, 200);
  low.Level(-1, 1, 1, 3, 2.5);  // the floor of a drop-off, 1.5 m lower
  RefineByLocalSteps(low.cloud, low.normals, {0, -1, 0}, VehicleOptions{}, DepthNoise{}, &low.labels);
  for (std::size_t i = 0; i < low.labels.size(); ++i) ASSERT_EQ(low.labels[i], 1) << i;
}

TEST(RefineByLocalSteps, TheBandAroundAJumpTakesItsStepClassOnBothSides) {
  for (const auto& [jump, expected] : {std::pair{0.05, 1}, {0.15, 2}, {0.3, 3}}) {
    SCOPED_TRACE(jump);
    StepWorld w(200, 200);
    w.Level(-1, 1, 1, 2, 1.0);          // the floor up to z = 2
    w.Level(-1, 1, 2, 3, 1.0 - jump);   // a terrace beyond it, `jump` higher
    RefineByLocalSteps(w.cloud, w.normals, {0, -1, 0}, VehicleOptions{}, DepthNoise{}, &w.labels);
    EXPECT_EQ(LabelAt(w, 0.0, 1.95), expected);  // at the foot
    EXPECT_EQ(LabelAt(w, 0.0, 2.05), expected);  // on the edge
    EXPECT_EQ(LabelAt(w, 0.0, 1.5), 1);          // 0.5 m before it
    EXPECT_EQ(LabelAt(w, 0.0, 2.6), 1);          // the terrace's level top
  }
}

TEST(LocalStepClasses, UpASlopeAJumpAboveTheCameraLevelCountsButNotAboveItsGround) {
  // Ground rising 0.3 m per m (16.7 deg), `depth` below the camera 1 m ahead, and 3 m ahead a
  // terrace 0.3 m higher. At a depth of 0.8 m the terrace's top lies 0.1-0.25 m above the
  // camera's level but 0.8 m below the plane through the camera parallel to the ground.
  const double rise = 0.3;
  auto world = [&](double depth) {
    StepWorld w(200, 250);
    w.Slope(-1, 1, 1, 3, depth, rise);
    w.Slope(-1, 1, 3, 3.5, depth - 0.3, rise);
    return w;
  };
  const Eigen::Vector3d level_up(0, -1, 0);
  const Eigen::Vector3d ground_up = Eigen::Vector3d(0, -1, -rise).normalized();
  auto classes = [&](const StepWorld& w, const Eigen::Vector3d* ground) {
    ImageU8 out;
    LocalStepClasses(w.cloud, w.normals, level_up, VehicleOptions{}, DepthNoise{}, &out, nullptr, ground);
    return out;
  };
  const StepWorld w = world(0.8);
  const ImageU8 by_level = classes(w, nullptr), by_ground = classes(w, &ground_up);
  for (const double z : {2.95, 3.05}) {  // at the foot and on the edge
    EXPECT_EQ(PixelAt(by_ground, 0.0, z), 3) << z;
    EXPECT_EQ(PixelAt(by_level, 0.0, z), 1) << z;  // the terrace's top is above the camera's level
  }
  EXPECT_EQ(PixelAt(by_ground, 0.0, 2.3), 1);  // the slope is smooth: its gradient is no step
  EXPECT_EQ(PixelAt(by_ground, 0.0, 3.35), 1);  // the terrace's top

  // The plane counts only what lies more than max_step_m below it (a degree of error in the
  // fitted ground is 0.2 m at 12 m): at a depth of 0.15 m the terrace's top lies 0.15 m below
  // the plane and stays out, as it would by the camera's level alone.
  EXPECT_EQ(PixelAt(classes(world(0.15), &ground_up), 0.0, 2.95), 1);

  // A roof 1 m over the terrace's far half lies above the plane and stays out of the heights:
  // the terrace under it keeps its class.
  StepWorld roofed = w;
  for (int v = static_cast<int>(std::lround((3.25 - 1.0) / 0.01)); v < 250; v += 2) {
    for (int u = 0; u < 200; u += 2) roofed.cloud(v, u).y() -= 1.0f;
  }
  const ImageU8 roofed_classes = classes(roofed, &ground_up);
  EXPECT_EQ(PixelAt(roofed_classes, 0.01, 3.35), 1);  // a point of the terrace under the roof
  EXPECT_EQ(PixelAt(roofed_classes, 0.0, 2.95), 3);
}

TEST(RefineByLocalSteps, PointsSmearedOverTheRadiusBesideAJumpAreUndecidedNotTraversable) {
  // Depth noise of 0.06 Z^2: beyond Z = 1.8 m a point's error along its ray exceeds the step
  // radius (0.2 m), so it cannot tell which side of the jump at Z = 2 m it lies on.
  const DepthNoise noise{0.06};
  for (const auto& [jump, band] : {std::pair{0.8, 4}, {0.05, 1}}) {
    SCOPED_TRACE(jump);
    StepWorld w(200, 200);
    w.Level(-1, 1, 1, 2, 1.0);
    w.Level(-1, 1, 2, 3, 1.0 - jump);
    RefineByLocalSteps(w.cloud, w.normals, {0, -1, 0}, VehicleOptions{}, noise, &w.labels);
    EXPECT_EQ(LabelAt(w, 0.0, 1.95), band);  // at the foot: a jump far beyond the noise is near
    EXPECT_EQ(LabelAt(w, 0.0, 2.05), band);  // on the edge
    EXPECT_EQ(LabelAt(w, 0.0, 1.5), 1);      // 0.5 m before it, placed well enough to be judged
    EXPECT_EQ(LabelAt(w, 0.0, 2.9), 1);      // smeared over twice the radius: no step class at all
  }
  // A point already non-traversable stays so.
  StepWorld red(200, 200);
  red.Level(-1, 1, 1, 2, 1.0);
  red.Level(-1, 1, 2, 3, 0.2);
  red.labels.Fill(3);
  RefineByLocalSteps(red.cloud, red.normals, {0, -1, 0}, VehicleOptions{}, noise, &red.labels);
  EXPECT_EQ(LabelAt(red, 0.0, 1.95), 3);
}

TEST(ApplySmearedStepBand, BlocksTheUndecidedPixelsSmearedBesideAJumpAndNothingElse) {
  // The world of the test above: beyond Z = 1.8 m a point cannot tell which side of the jump at
  // Z = 2 m it lies on, and the local step rule leaves it undecided; the band then blocks it.
  // Placed points, points smeared beside no jump and points smeared past twice the radius keep
  // their labels.
  const DepthNoise noise{0.06};
  for (const auto& [jump, band] : {std::pair{0.8, 3}, {0.05, 1}}) {
    SCOPED_TRACE(jump);
    StepWorld w(200, 200);
    w.Level(-1, 1, 1, 2, 1.0);
    w.Level(-1, 1, 2, 3, 1.0 - jump);
    ImageU8 step_classes;
    LocalStepClasses(w.cloud, w.normals, {0, -1, 0}, VehicleOptions{}, noise, &step_classes);
    ApplyLocalStepClasses(step_classes, &w.labels);
    ApplySmearedStepBand(step_classes, &w.labels);
    EXPECT_EQ(LabelAt(w, 0.0, 1.95), band);
    EXPECT_EQ(LabelAt(w, 0.0, 2.05), band);
    EXPECT_EQ(LabelAt(w, 0.0, 1.5), 1);
    EXPECT_EQ(LabelAt(w, 0.0, 2.9), 1);
  }
  // Only undecided labels whose step class is undecided change.
  const ImageU8 step_classes = [] {
    ImageU8 s(5, 1, 4);
    s(0, 4) = 0;
    return s;
  }();
  ImageU8 labels(5, 1, 0);
  const std::uint8_t before[5] = {0, 1, 2, 4, 4};
  const std::uint8_t expected[5] = {0, 1, 2, 3, 4};
  for (int u = 0; u < 5; ++u) labels(0, u) = before[u];
  ApplySmearedStepBand(step_classes, &labels);
  for (int u = 0; u < 5; ++u) EXPECT_EQ(labels(0, u), expected[u]) << u;
  ImageU8 wrong(4, 1, 4);
  EXPECT_THROW(ApplySmearedStepBand(step_classes, &wrong), InternalError);
}

TEST(ApplyHiddenDrops, ASureLipBlocksASuspectedOneIsUndecidedAndNoLipChangesNothing) {
  // Labels: traversable, semi, undecided, non-traversable, unknown, then traversable pixels with
  // no lip, a weak suspicion (the least FindHiddenDrops gives) and one just short of sure.
  ImageU8 labels(9, 1, 0);
  const std::uint8_t before[9] = {1, 2, 4, 3, 0, 1, 1, 1, 4};
  const std::uint8_t lip[9] = {255, 255, 255, 255, 255, 0, 5, 254, 100};
  const std::uint8_t expected[9] = {3, 3, 3, 3, 0, 1, 4, 4, 4};
  ImageU8 mask(9, 1, 0);
  for (int u = 0; u < 9; ++u) {
    labels(0, u) = before[u];
    mask(0, u) = lip[u];
  }
  ApplyHiddenDrops(mask, &labels);
  for (int u = 0; u < 9; ++u) EXPECT_EQ(labels(0, u), expected[u]) << "pixel " << u;
  EXPECT_THROW(ApplyHiddenDrops(ImageU8(8, 1, 0), &labels), InternalError);
}
}  // namespace
}  // namespace ssta
