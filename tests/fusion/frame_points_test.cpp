// A classified frame as the map takes it: its labelled pixels as world points (ClassifiedPointsInWorld),
// and the texture mask that keeps matching noise out of the map (TexturedPixels).

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <set>
#include <utility>

#include "ssta/analysis/frame_analysis.h"
#include "ssta/analysis/label_rule.h"
#include "ssta/core/error.h"
#include "ssta/fusion/frame_points.h"

namespace ssta {
namespace {

TEST(ClassifiedPointsInWorld, TransformsEveryStrideThPointWithItsSegmentVerdict) {
  FrameResult f;
  f.cloud = Image3f(4, 2, NanVector3f());
  f.segment_ids = ImageI32(4, 2, -1);
  f.analysis.labels = ImageU8(4, 2, 0);
  f.analysis.segments.resize(1);
  f.analysis.segments[0].has_plane = true;
  f.analysis.segments[0].slope_deg = 12.0;
  f.analysis.segments[0].step_m = 0.05;
  f.cloud(0, 0) = Eigen::Vector3f(1, 2, 3);
  f.segment_ids(0, 0) = 0;
  f.analysis.labels(0, 0) = 1;
  f.cloud(0, 2) = Eigen::Vector3f(0, 0, 5);  // no segment: undecided, no slope
  f.analysis.labels(0, 2) = 4;
  f.cloud(0, 1) = Eigen::Vector3f(9, 9, 9);  // skipped by stride 2
  Eigen::Isometry3d world_T_rect = Eigen::Isometry3d::Identity();
  world_T_rect.translate(Eigen::Vector3d(10, 0, 0));
  world_T_rect.rotate(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()));
  const auto points = ClassifiedPointsInWorld(f, world_T_rect, 2);
  ASSERT_EQ(points.size(), 2u);
  EXPECT_TRUE(points[0].world_p.isApprox(Eigen::Vector3f(8, 1, 3), 1e-6f)) << points[0].world_p.transpose();
  EXPECT_EQ(points[0].cls, TravClass::kTraversable);
  EXPECT_FLOAT_EQ(points[0].slope_deg, 12.0f);
  EXPECT_EQ(points[1].cls, TravClass::kUndecided);
  EXPECT_TRUE(std::isnan(points[1].slope_deg));
}

TEST(ClassifiedPointsInWorld, DoesNotCountAnObstacleVoteOfASmallSegmentWhoseSlopeTheNoiseExplains) {
  // Three non-traversable pixels: a small segment whose slope the stereo noise explains
  // (SegmentResult::slope_within_noise), set by its own verdict (rule small_segment); the same
  // segment's pixel that the local step rule made non-traversable; and a small segment steep
  // beyond its noise. Only the first votes undecided: its obstacle is the noise's.
  FrameResult f;
  f.cloud = Image3f(3, 1, Eigen::Vector3f(0, 0, 5));
  f.segment_ids = ImageI32(3, 1, 0);
  f.segment_ids(0, 2) = 1;
  f.analysis.labels = ImageU8(3, 1, static_cast<std::uint8_t>(TravClass::kNonTraversable));
  f.analysis.rules = ImageU8(3, 1, static_cast<std::uint8_t>(LabelRule::kSmallSegment));
  f.analysis.rules(0, 1) = static_cast<std::uint8_t>(LabelRule::kLocalStep);
  f.analysis.segments.resize(2);
  for (SegmentResult& s : f.analysis.segments) {
    s.has_plane = s.small = true;
    s.slope_deg = 30.0;
  }
  f.analysis.segments[0].slope_within_noise = true;
  const auto points = ClassifiedPointsInWorld(f, Eigen::Isometry3d::Identity(), 1);
  ASSERT_EQ(points.size(), 3u);
  EXPECT_EQ(points[0].cls, TravClass::kUndecided);
  EXPECT_EQ(points[1].cls, TravClass::kNonTraversable);
  EXPECT_EQ(points[2].cls, TravClass::kNonTraversable);
  // Without the rules (a frame built by hand) every label counts as it is.
  f.analysis.rules = ImageU8();
  EXPECT_EQ(ClassifiedPointsInWorld(f, Eigen::Isometry3d::Identity(), 1)[0].cls, TravClass::kNonTraversable);
}

TEST(ClassifiedPointsInWorld, CountsAPixelBlockedForItsSmearBesideAJumpAsUndecided) {
  // Two non-traversable pixels beside a jump: one the frame blocked because its point is smeared
  // over the step radius (rule smeared_step), one whose step it placed (local_step). The map
  // takes the first as a surface seen without a class, and a lip over it as the lip's vote.
  FrameResult f;
  f.cloud = Image3f(3, 1, Eigen::Vector3f(0, 0, 12));
  f.segment_ids = ImageI32(3, 1, -1);
  f.analysis.labels = ImageU8(3, 1, static_cast<std::uint8_t>(TravClass::kNonTraversable));
  f.analysis.rules = ImageU8(3, 1, static_cast<std::uint8_t>(LabelRule::kSmearedStep));
  f.analysis.rules(0, 1) = static_cast<std::uint8_t>(LabelRule::kLocalStep);
  ImageU8 lip(3, 1, 0);
  lip(0, 2) = 128;
  const auto points = ClassifiedPointsInWorld(f, Eigen::Isometry3d::Identity(), 1, nullptr, nullptr, &lip);
  ASSERT_EQ(points.size(), 3u);
  EXPECT_EQ(points[0].cls, TravClass::kUndecided);
  EXPECT_EQ(points[1].cls, TravClass::kNonTraversable);
  EXPECT_EQ(points[2].cls, TravClass::kNonTraversable);
  EXPECT_NEAR(points[2].vote_weight, 128.0 / 255.0, 1e-6);
}

TEST(MapPointsOfFrame, TakesTheFramesOwnLipsWhenTheyWereSearchedWithinItsRange) {
  // One row of level ground, where the map's own search finds no lip, and lips the frame's
  // analysis found (AnalysisResult::lips): none, suspected, sure. Searched within the map's
  // range (sqrt(range_depth_sigma_m / depth noise)), they are the map's; within another, the map
  // searches for itself.
  FrameResult f;
  f.cloud = Image3f(3, 1, Eigen::Vector3f(0, 0.8f, 5));
  f.segment_ids = ImageI32(3, 1, 0);
  f.depth_noise_per_m2 = 0.001;
  f.analysis.labels = ImageU8(3, 1, static_cast<std::uint8_t>(TravClass::kTraversable));
  f.analysis.segments.resize(1);
  f.analysis.lips = ImageU8(3, 1, 0);
  f.analysis.lips(0, 1) = 100;
  f.analysis.lips(0, 2) = 255;
  MappingOptions options;
  options.min_texture = 0.0;
  options.no_return_stride_px = 0;
  f.analysis.lips_range_m = std::sqrt(options.range_depth_sigma_m / f.depth_noise_per_m2);
  const std::vector<ClassifiedPoint> taken =
      MapPointsOfFrame(f, Eigen::Isometry3d::Identity(), options, RectifiedGeometry{}, VehicleOptions{});
  ASSERT_EQ(taken.size(), 3u);
  EXPECT_EQ(taken[0].cls, TravClass::kTraversable);
  EXPECT_EQ(taken[1].cls, TravClass::kNonTraversable);
  EXPECT_FLOAT_EQ(taken[1].vote_weight, 100.0f / 255.0f);
  EXPECT_EQ(taken[2].cls, TravClass::kNonTraversable);
  EXPECT_FLOAT_EQ(taken[2].vote_weight, 1.0f);
  f.analysis.lips_range_m = 10.0;
  for (const ClassifiedPoint& p :
       MapPointsOfFrame(f, Eigen::Isometry3d::Identity(), options, RectifiedGeometry{}, VehicleOptions{})) {
    EXPECT_EQ(p.cls, TravClass::kTraversable);
  }
}

TEST(AppendNoReturnRays, CastsBlankPixelsAboveTheHorizonOnALatticeWhosePhaseFollowsTheFrame) {
  // A 40 x 30 common area, f 20 px, principal point (20, 15), camera level (up is -y): rows
  // 0-14 look up, rows 15-29 down. Every pixel is untextured (the texture rule) but for column 7.
  RectifiedGeometry g;
  g.f = 20.0;
  g.cu = 20.0;
  g.cv = 15.0;
  FrameResult f;
  f.up_rectified = Eigen::Vector3d(0, -1, 0);
  f.analysis.rules = ImageU8(40, 30, static_cast<std::uint8_t>(LabelRule::kTexture));
  for (int v = 0; v < 30; ++v) f.analysis.rules(v, 7) = static_cast<std::uint8_t>(LabelRule::kSegment);
  Eigen::Isometry3d world_T_rect = Eigen::Isometry3d::Identity();
  world_T_rect.translate(Eigen::Vector3d(1, 2, 3));
  std::set<std::pair<int, int>> phases;
  for (std::int64_t t = 0; t < 200; ++t) {
    f.timestamp_ns = 1600000000000000000 + t * 100000000;
    std::vector<ClassifiedPoint> points(1);  // appended to, not replaced
    AppendNoReturnRays(f, world_T_rect, g, 4, &points);
    ASSERT_GE(points.size(), 2u);
    // Every ray: a point 1 m deep in the camera, so its pixel is recovered from it.
    int u0 = -1, v0 = -1;
    for (std::size_t i = 1; i < points.size(); ++i) {
      ASSERT_TRUE(points[i].no_return);
      const Eigen::Vector3f q = points[i].world_p - Eigen::Vector3f(1, 2, 3);
      ASSERT_NEAR(q.z(), 1.0f, 1e-6f);
      const int u = static_cast<int>(std::lround(q.x() * 20.0f + 20.0f));
      const int v = static_cast<int>(std::lround(q.y() * 20.0f + 15.0f));
      ASSERT_LT(v, 15) << "below the horizon";
      ASSERT_NE(u, 7) << "a textured pixel";
      if (i == 1) {
        u0 = u;
        v0 = v;
      }
      ASSERT_EQ((u - u0) % 4, 0);
      ASSERT_EQ((v - v0) % 4, 0);
    }
    ASSERT_LT(u0, 4);
    ASSERT_LT(v0, 4);
    // All of the lattice: 10 columns (less column 7's if on it) times its rows above row 15.
    const int rows = (14 - v0) / 4 + 1, columns = 10 - (u0 == 3 ? 1 : 0);
    EXPECT_EQ(points.size(), static_cast<std::size_t>(1 + rows * columns));
    phases.insert({u0, v0});
  }
  EXPECT_EQ(phases.size(), 16u);  // over 200 frames, every one of the 16 phases
}

TEST(ClassifiedPointsInWorld, LeavesOutPixelsTheKeepMaskDrops) {
  FrameResult f;
  f.cloud = Image3f(3, 1, Eigen::Vector3f(1, 2, 3));
  f.segment_ids = ImageI32(3, 1, -1);
  f.analysis.labels = ImageU8(3, 1, 1);
  ImageU8 keep(3, 1, 1);
  keep(0, 1) = 0;
  EXPECT_EQ(ClassifiedPointsInWorld(f, Eigen::Isometry3d::Identity(), 1, &keep).size(), 2u);
  // A pixel labelled unknown (untextured, analysis.label_min_texture) is left out though it
  // has a point.
  f.analysis.labels(0, 2) = 0;
  const std::vector<ClassifiedPoint> points = ClassifiedPointsInWorld(f, Eigen::Isometry3d::Identity(), 1);
  ASSERT_EQ(points.size(), 2u);
  EXPECT_EQ(points[0].cls, TravClass::kTraversable);
  EXPECT_EQ(points[1].cls, TravClass::kTraversable);
}

TEST(ClassifiedPointsInWorld, PutsEachPointAtThePointDisparityAlongItsRay) {
  // Z' = f b / d' = Z d / d': half the disparity, twice the range, the same direction; where
  // either disparity is 0 the point keeps its own.
  FrameResult f;
  f.cloud = Image3f(3, 1, NanVector3f());
  f.disparity = ImageF(3, 1, 0.0f);
  f.segment_ids = ImageI32(3, 1, -1);
  f.analysis.labels = ImageU8(3, 1, 1);
  f.cloud(0, 0) = Eigen::Vector3f(1, 2, 4);
  f.disparity(0, 0) = 8.0f;
  f.cloud(0, 1) = Eigen::Vector3f(-1, 0.5f, 2);
  f.disparity(0, 1) = 16.0f;
  f.cloud(0, 2) = Eigen::Vector3f(0, 1, 5);
  f.disparity(0, 2) = 6.4f;
  ImageF refined(3, 1, 0.0f);
  refined(0, 0) = 4.0f;
  refined(0, 1) = 20.0f;
  Eigen::Isometry3d world_T_rect = Eigen::Isometry3d::Identity();
  world_T_rect.translate(Eigen::Vector3d(10, 0, 0));
  const auto points = ClassifiedPointsInWorld(f, world_T_rect, 1, nullptr, &refined);
  ASSERT_EQ(points.size(), 3u);
  EXPECT_TRUE(points[0].world_p.isApprox(Eigen::Vector3f(12, 4, 8), 1e-6f)) << points[0].world_p.transpose();
  EXPECT_TRUE(points[1].world_p.isApprox(Eigen::Vector3f(10 - 0.8f, 0.4f, 1.6f), 1e-6f)) << points[1].world_p.transpose();
  EXPECT_TRUE(points[2].world_p.isApprox(Eigen::Vector3f(10, 1, 5), 1e-6f)) << points[2].world_p.transpose();
  ImageF wrong_size(2, 1, 1.0f);
  EXPECT_THROW(ClassifiedPointsInWorld(f, world_T_rect, 1, nullptr, &wrong_size), InternalError);
}

TEST(ClassifiedPointsInWorld, GivesEachPointItsHeightAboveTheFramesGroundPlaneAtItsOwnRange) {
  // Camera frame, y down: the ground plane y = 1.5 (1.5 m below the camera) is n = (0, -1, 0),
  // D = 1.5. A point at y = 1.0 stands 0.5 m above it; at the point disparity twice the
  // matcher's, the same ray at half the range, y = 0.5, stands 1.0 m above it.
  FrameResult f;
  f.cloud = Image3f(3, 1, NanVector3f());
  f.disparity = ImageF(3, 1, 10.0f);
  f.segment_ids = ImageI32(3, 1, -1);
  f.analysis.labels = ImageU8(3, 1, 3);
  f.cloud(0, 0) = Eigen::Vector3f(0, 1.0f, 6);
  f.cloud(0, 1) = Eigen::Vector3f(1, 2.0f, 8);  // 0.5 m below the ground (a pit)
  f.cloud(0, 2) = Eigen::Vector3f(0, 1.0f, 6);
  f.analysis.ground.found = true;
  f.analysis.ground.plane = Eigen::Vector4d(0, -1, 0, 1.5);
  f.analysis.quality.passed = true;
  ImageF refined(3, 1, 10.0f);
  refined(0, 2) = 20.0f;
  std::vector<ClassifiedPoint> points = ClassifiedPointsInWorld(f, Eigen::Isometry3d::Identity(), 1, nullptr, &refined);
  ASSERT_EQ(points.size(), 3u);
  EXPECT_NEAR(points[0].height_m, 0.5f, 1e-6f);
  EXPECT_NEAR(points[1].height_m, -0.5f, 1e-6f);
  EXPECT_NEAR(points[2].height_m, 1.0f, 1e-6f);
  // No height from a plane that failed the quality check, or without a plane.
  f.analysis.quality.passed = false;
  points = ClassifiedPointsInWorld(f, Eigen::Isometry3d::Identity(), 1);
  ASSERT_EQ(points.size(), 3u);
  for (const ClassifiedPoint& p : points) EXPECT_TRUE(std::isnan(p.height_m));
  f.analysis.quality.passed = true;
  f.analysis.ground.found = false;
  points = ClassifiedPointsInWorld(f, Eigen::Isometry3d::Identity(), 1);
  for (const ClassifiedPoint& p : points) EXPECT_TRUE(std::isnan(p.height_m));
}

TEST(TexturedPixels, KeepsPixelsWhoseWindowStdReachesTheThreshold) {
  // A 12x8 image, blank (grey 100) except a 0/6 checker in columns 8..11: a window's std is
  // 3 where it lies on the checker only, less where it also covers the blank part.
  ImageU8 image(12, 8, 100);
  for (int v = 0; v < 8; ++v) {
    for (int u = 8; u < 12; ++u) image(v, u) = (u + v) % 2 == 0 ? 0 : 6;
  }
  RectifiedGeometry g;
  g.crop_u0 = 1;
  g.crop_v0 = 2;
  g.crop_width = 10;
  g.crop_height = 4;
  const ImageU8 keep = TexturedPixels(image, g, 3, 2.0);
  ASSERT_EQ(keep.width(), 10);
  ASSERT_EQ(keep.height(), 4);
  for (int v = 0; v < 4; ++v) {
    // Crop column u is image column u + 1; the 3x3 window at image column 8 covers one blank
    // column (3 of 9 pixels at 100: std ~ 46, kept); at 6 and before it is all blank (std 0).
    for (int u = 0; u <= 5; ++u) EXPECT_EQ(keep(v, u), 0) << v << "," << u;
    for (int u = 6; u < 10; ++u) EXPECT_EQ(keep(v, u), 1) << v << "," << u;
  }
  // On the checker alone the std of a 3x3 window is 6 * sqrt(4/9 * 5/9) = 2.98: dropped at 3.
  const ImageU8 strict = TexturedPixels(image, g, 3, 3.0);
  EXPECT_EQ(strict(1, 8), 0);
  EXPECT_EQ(strict(1, 7), 1);  // the window covers the blank column: a large std
}

TEST(ClassifiedPointsInWorld, IntoAReusedBufferGivesTheSamePointsAsAFreshVector) {
  FrameResult f;
  f.cloud = Image3f(3, 2, Eigen::Vector3f(1, 2, 3));
  f.cloud(1, 1) = NanVector3f();
  f.segment_ids = ImageI32(3, 2, -1);
  f.analysis.labels = ImageU8(3, 2, 2);
  f.analysis.segments.resize(2);
  f.analysis.segments[0].has_plane = false;  // slope NaN, step kept
  f.analysis.segments[0].step_m = 0.25;
  f.analysis.segments[1].has_plane = true;
  f.analysis.segments[1].slope_deg = 7.5;
  f.analysis.segments[1].step_m = -0.125;
  f.segment_ids(0, 1) = 0;
  f.segment_ids(1, 2) = 1;
  // The buffer holds more points of an earlier frame than this one yields.
  std::vector<ClassifiedPoint> buffer(9);
  ClassifiedPointsInWorld(f, Eigen::Isometry3d::Identity(), 1, nullptr, &buffer);
  ASSERT_EQ(buffer.size(), 5u);
  EXPECT_TRUE(std::isnan(buffer[0].slope_deg) && std::isnan(buffer[0].step_m));
  EXPECT_TRUE(std::isnan(buffer[1].slope_deg));
  EXPECT_EQ(buffer[1].step_m, 0.25f);
  EXPECT_EQ(buffer[4].slope_deg, 7.5f);
  EXPECT_EQ(buffer[4].step_m, -0.125f);
  const auto fresh = ClassifiedPointsInWorld(f, Eigen::Isometry3d::Identity(), 1);
  ASSERT_EQ(fresh.size(), buffer.size());
  for (std::size_t i = 0; i < fresh.size(); ++i) {
    EXPECT_EQ(fresh[i].world_p, buffer[i].world_p);
    EXPECT_EQ(fresh[i].cls, buffer[i].cls);
    EXPECT_EQ(std::isnan(fresh[i].slope_deg), std::isnan(buffer[i].slope_deg));
  }
}

TEST(TexturedPixels, EqualsTheWindowStdComputedDirectlyCallAfterCall) {
  // The integral tables are reused between calls (only their first row and column are
  // cleared): larger, smaller and odd-sized random images in turn must each give exactly the
  // direct count n * sum(g^2) - sum(g)^2 >= n^2 * min_std^2 over the clipped window.
  std::mt19937 rng(7);
  const int sizes[][2] = {{40, 30}, {13, 9}, {41, 31}, {12, 5}, {40, 30}};
  for (const auto& size : sizes) {
    const int w = size[0], h = size[1];
    ImageU8 image(w, h, 0);
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) image(v, u) = static_cast<std::uint8_t>(u < w / 2 ? 100 : rng() % 256);  // blank, then noise
    }
    RectifiedGeometry g;
    g.crop_u0 = 2;
    g.crop_v0 = 1;
    g.crop_width = w - 3;
    g.crop_height = h - 2;
    const int block = 5;
    const double min_std = 20.0;
    const ImageU8 keep = TexturedPixels(image, g, block, min_std);
    ASSERT_EQ(keep.width(), g.crop_width);
    ASSERT_EQ(keep.height(), g.crop_height);
    int kept = 0;
    for (int v = 0; v < g.crop_height; ++v) {
      for (int u = 0; u < g.crop_width; ++u) {
        std::int64_t n = 0, s = 0, s2 = 0;
        for (int y = std::max(0, v + 1 - 2); y <= std::min(h - 1, v + 1 + 2); ++y) {
          for (int x = std::max(0, u + 2 - 2); x <= std::min(w - 1, u + 2 + 2); ++x) {
            ++n;
            s += image(y, x);
            s2 += static_cast<std::int64_t>(image(y, x)) * image(y, x);
          }
        }
        const bool textured = static_cast<double>(n * s2 - s * s) >=
                              static_cast<double>(n) * static_cast<double>(n) * min_std * min_std;
        EXPECT_EQ(keep(v, u), textured ? 1 : 0) << w << "x" << h << " at " << u << "," << v;
        kept += textured ? 1 : 0;
      }
    }
    EXPECT_GT(kept, 0);
    EXPECT_LT(kept, g.crop_width * g.crop_height);
  }
}

}  // namespace
}  // namespace ssta
