#include "ssta/geometry/segmenter.h"

#include <algorithm>
#include <cmath>
#include <map>

#include <gtest/gtest.h>

#include "geometry/synthetic_scene.h"
#include "ssta/geometry/normal_estimator.h"

namespace ssta {
namespace {

using test::PinholeCamera;
using test::Scene;

constexpr double kPi = 3.14159265358979323846;

// Floor 1 m below the camera up to z0 = 6 m, then a ramp rising at `ramp_deg` (sharp crease).
Scene FloorAndRampScene(double ramp_deg) {
  constexpr double kHeight = 1.0, kZ0 = 6.0;
  const double slope = std::tan(ramp_deg * kPi / 180.0);
  Scene scene;
  scene.AddPlane({0, 1, 0}, -kHeight, [](const Eigen::Vector3d& p) { return p.z() <= kZ0; });
  // y = kHeight - (z - kZ0) * slope  <=>  y + slope * z - (kHeight + slope * kZ0) = 0
  scene.AddPlane({0, 1, slope}, -(kHeight + slope * kZ0),
                 [](const Eigen::Vector3d& p) { return p.z() >= kZ0; });
  return scene;
}

// Floor 1 m below the camera with a 0.3 m tall box, front face at 3 m, top 1.2 x 1 m.
Scene BoxOnFloorScene() {
  Scene scene = test::GroundScene(1.0);
  scene.AddBox({-0.6, 0.7, 3.0}, {0.6, 1.0, 4.0});
  return scene;
}

// The segment holding most of the pixels selected by `use`, and how many of them it holds.
struct Mode {
  int label = -1;
  int count = 0;
  int selected = 0;
};
template <typename Use>
Mode ModeOf(const Segmentation& s, Use use) {
  std::map<int, int> counts;
  Mode mode;
  for (int v = 0; v < s.labels.height(); ++v) {
    for (int u = 0; u < s.labels.width(); ++u) {
      if (!use(v, u)) continue;
      ++mode.selected;
      if (s.labels(v, u) >= 0) ++counts[s.labels(v, u)];
    }
  }
  for (const auto& [label, count] : counts) {
    if (count > mode.count) mode = {label, count, mode.selected};
  }
  return mode;
}

// Pixels of `truth` normals within 1 degree of `n`, at least `margin` px from other normals.
auto Facing(const Image3f& truth, const Eigen::Vector3f& n) {
  return
      [&truth, n](int v, int u) { return IsFinite(truth(v, u)) && truth(v, u).dot(n) > 0.9998f; };
}

SegmenterOptions WithRoughness(double deg) { return test::NeighbourNormals(deg); }

TEST(Segmenter, SplitsRampFromFloorBelowCreaseRotationAndMergesAboveRampAngle) {
  const PinholeCamera camera;
  Image3f truth;
  const Image3f cloud = FloorAndRampScene(20.0).Render(camera, &truth, 20.0);
  const ImageF disparity = test::DisparityOf(cloud, camera);
  const Image3f normals = EstimateNormals(cloud, test::FixedWindow13());
  const auto floor = Facing(truth, {0, -1, 0});
  const Eigen::Vector3f ramp_n =
      Eigen::Vector3f(0, -std::cos(20 * kPi / 180), -std::sin(20 * kPi / 180));
  const auto ramp = Facing(truth, ramp_n);

  // The window spreads the 20-degree crease over ~13 rows; record its steepest per-pixel turn.
  double max_turn_deg = 0.0;
  for (int v = 1; v < camera.height; ++v) {
    const double turn = test::AngleDeg(normals(v, 320), normals(v - 1, 320));
    if (std::isfinite(turn)) max_turn_deg = std::max(max_turn_deg, turn);
  }
  RecordProperty("crease_max_turn_per_px_deg", std::to_string(max_turn_deg));
  EXPECT_GT(max_turn_deg, 2.0);
  EXPECT_LT(max_turn_deg, 5.0);

  for (const double roughness : {1.0, test::NeighbourNormals().roughness_deg}) {
    SCOPED_TRACE(roughness);
    const Segmentation split = SegmentNormals(normals, &disparity, WithRoughness(roughness));
    const Mode f = ModeOf(split, floor), r = ModeOf(split, ramp);
    EXPECT_NE(f.label, r.label);
    EXPECT_GT(f.count, 0.95 * f.selected);
    EXPECT_GT(r.count, 0.95 * r.selected);
  }
  const Segmentation merged = SegmentNormals(normals, &disparity, WithRoughness(25.0));
  const Mode f = ModeOf(merged, floor), r = ModeOf(merged, ramp);
  EXPECT_EQ(f.label, r.label);
  EXPECT_GT(f.count, 0.99 * f.selected);
  EXPECT_GT(r.count, 0.99 * r.selected);
}

TEST(Segmenter, SegmentAngleStopsAGradualCreaseFromChaining) {
  // At roughness 5 degrees the 20-degree crease (steepest turn ~3.4 deg/px) is crossed in
  // sub-threshold steps and floor and ramp merge; comparing the segments' mean normals stops it.
  const PinholeCamera camera;
  Image3f truth;
  const Image3f cloud = FloorAndRampScene(20.0).Render(camera, &truth, 20.0);
  const ImageF disparity = test::DisparityOf(cloud, camera);
  const Image3f normals = EstimateNormals(cloud, test::FixedWindow13());
  const auto floor = Facing(truth, {0, -1, 0});
  const auto ramp = Facing(truth, Eigen::Vector3f(0, -std::cos(20 * kPi / 180), -std::sin(20 * kPi / 180)));

  SegmenterOptions neighbours_only = WithRoughness(5.0);
  const Segmentation chained = SegmentNormals(normals, &disparity, neighbours_only);
  EXPECT_EQ(ModeOf(chained, floor).label, ModeOf(chained, ramp).label);

  SegmenterOptions with_segments = neighbours_only;
  with_segments.max_segment_angle_deg = 8.0;
  const Segmentation split = SegmentNormals(normals, &disparity, with_segments);
  const Mode f = ModeOf(split, floor), r = ModeOf(split, ramp);
  EXPECT_NE(f.label, r.label);
  EXPECT_GT(f.count, 0.95 * f.selected);
  EXPECT_GT(r.count, 0.9 * r.selected);
}

TEST(Segmenter, BoxTopAndFrontAreSeparateSegments) {
  const PinholeCamera camera;
  Image3f truth;
  const Image3f cloud = BoxOnFloorScene().Render(camera, &truth, 20.0);
  const ImageF disparity = test::DisparityOf(cloud, camera);
  const Image3f normals = EstimateNormals(cloud, test::FixedWindow13());
  const Segmentation s = SegmentNormals(normals, &disparity, test::NeighbourNormals());
  auto top = [&](int v, int u) {
    return Facing(truth, {0, -1, 0})(v, u) && std::abs(cloud(v, u).y() - 0.7f) < 1e-3f;
  };
  const auto front = Facing(truth, {0, 0, -1});
  const Mode t = ModeOf(s, top), fr = ModeOf(s, front);
  ASSERT_GT(t.selected, 3000);
  ASSERT_GT(fr.selected, 5000);
  EXPECT_NE(t.label, fr.label);
  // The window blurs the normals over ~6 rows on each side of a crease: those rows form their
  // own small segments (the front face is only 45 rows tall).
  EXPECT_GT(t.count, 0.6 * t.selected);
  EXPECT_GT(fr.count, 0.6 * fr.selected);
  // The top's segment holds no front pixels and vice versa.
  EXPECT_EQ(
      ModeOf(s, [&](int v, int u) { return front(v, u) && s.labels(v, u) == t.label; }).selected,
      0);
  EXPECT_EQ(
      ModeOf(s, [&](int v, int u) { return top(v, u) && s.labels(v, u) == fr.label; }).selected, 0);
  // The floor is one segment apart from both.
  const Mode floor = ModeOf(s, [&](int v, int u) {
    return Facing(truth, {0, -1, 0})(v, u) && !top(v, u);
  });
  EXPECT_NE(floor.label, t.label);
  EXPECT_NE(floor.label, fr.label);
  EXPECT_EQ(s.LargestSegment(), floor.label);
}

TEST(Segmenter, DisparityJumpSeparatesBoxTopFromFloorBehindIt) {
  // True normals: box top and floor are exactly parallel and touch along the top's silhouette,
  // so only the disparity test can tell them apart.
  const PinholeCamera camera;
  Image3f truth;
  const Image3f cloud = BoxOnFloorScene().Render(camera, &truth, 20.0);
  const ImageF disparity = test::DisparityOf(cloud, camera);
  auto top = [&](int v, int u) {
    return IsFinite(cloud(v, u)) && std::abs(cloud(v, u).y() - 0.7f) < 1e-3f;
  };
  auto floor = [&](int v, int u) {
    return IsFinite(cloud(v, u)) && std::abs(cloud(v, u).y() - 1.0f) < 1e-3f;
  };
  const Segmentation with = SegmentNormals(truth, &disparity, test::NeighbourNormals());
  EXPECT_NE(ModeOf(with, top).label, ModeOf(with, floor).label);
  EXPECT_EQ(ModeOf(with, top).count, ModeOf(with, top).selected);

  SegmenterOptions pure = test::NeighbourNormals();
  pure.max_disparity_jump_px = 0.0;
  const Segmentation without = SegmentNormals(truth, &disparity, pure);
  EXPECT_EQ(ModeOf(without, top).label, ModeOf(without, floor).label);
  // No disparity image: the pure normal criterion too.
  const Segmentation no_disparity = SegmentNormals(truth, nullptr, test::NeighbourNormals());
  EXPECT_EQ(ModeOf(no_disparity, top).label, ModeOf(no_disparity, floor).label);
}

TEST(Segmenter, NanNormalsAreUnlabelledAndSizesAddUp) {
  const PinholeCamera camera;
  Image3f cloud = BoxOnFloorScene().Render(camera, nullptr, 20.0);
  for (int v = 300; v < 320; ++v) {
    for (int u = 100; u < 140; ++u) cloud(v, u) = NanVector3f();
  }
  const ImageF disparity = test::DisparityOf(cloud, camera);
  const Image3f normals = EstimateNormals(cloud, test::FixedWindow13());
  Segmenter segmenter(test::NeighbourNormals());
  for (int repeat = 0; repeat < 2; ++repeat) {  // reused buffers give the same answer
    const Segmentation& s = segmenter.Compute(normals, &disparity);
    int labelled = 0;
    for (std::size_t i = 0; i < normals.size(); ++i) {
      if (!IsFinite(normals[i])) {
        ASSERT_EQ(s.labels[i], -1);
      } else {
        ASSERT_GE(s.labels[i], 0);
        ASSERT_LT(s.labels[i], s.num_segments());
        ++labelled;
      }
    }
    EXPECT_EQ(s.labels(310, 120), -1);
    int total = 0;
    for (const int size : s.sizes) {
      EXPECT_GT(size, 0);
      total += size;
    }
    EXPECT_EQ(total, labelled);
    ASSERT_EQ(static_cast<int>(s.offsets.size()), s.num_segments() + 1);
    EXPECT_EQ(s.offsets.back(), labelled);
    EXPECT_EQ(static_cast<int>(s.pixel_indices.size()), labelled);
    for (int k = 0; k < s.num_segments(); ++k) {
      ASSERT_EQ(s.offsets[k + 1] - s.offsets[k], s.sizes[k]);
      for (int j = s.offsets[k]; j < s.offsets[k + 1]; ++j) {
        ASSERT_EQ(s.labels[s.pixel_indices[j]], k);
        if (j > s.offsets[k]) {
          ASSERT_LT(s.pixel_indices[j - 1], s.pixel_indices[j]);
        }
      }
    }
    // Ids follow the raster order of each segment's first pixel.
    for (int k = 1; k < s.num_segments(); ++k) {
      ASSERT_LT(s.pixel_indices[s.offsets[k - 1]], s.pixel_indices[s.offsets[k]]);
    }
  }
}

TEST(Segmenter, NoisyStereoGroundStaysOneSegmentAtDefaults) {
  const PinholeCamera camera;
  Image3f cloud = test::GroundScene(1.0).Render(camera, nullptr, 20.0);
  test::AddDepthNoise(0.15 / (camera.f_px * camera.baseline_m), 11, &cloud);
  const ImageF disparity = test::DisparityOf(cloud, camera);
  const Image3f normals = EstimateNormals(cloud, test::FixedWindow13());
  const Segmentation s = SegmentNormals(normals, &disparity, test::NeighbourNormals());
  int with_normal = 0, near_with_normal = 0, near_in_largest = 0;
  const int largest = s.LargestSegment();
  for (std::size_t i = 0; i < normals.size(); ++i) {
    if (!IsFinite(normals[i])) continue;
    ++with_normal;
    if (cloud[i].z() < 10.0f) {
      ++near_with_normal;
      near_in_largest += s.labels[i] == largest;
    }
  }
  const double largest_fraction = static_cast<double>(s.sizes[largest]) / with_normal;
  const double near_fraction = static_cast<double>(near_in_largest) / near_with_normal;
  RecordProperty("largest_fraction", std::to_string(largest_fraction));
  RecordProperty("near_fraction", std::to_string(near_fraction));
  EXPECT_GT(near_fraction, 0.95);
  EXPECT_GT(largest_fraction, 0.9);
}

TEST(SegmenterOptions, ValidationNamesTheKey) {
  std::string error;
  EXPECT_TRUE(SegmenterOptions{}.IsValid(&error));
  SegmenterOptions options;
  options.roughness_deg = 0.0;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_EQ(error.rfind("roughness_deg:", 0), 0u) << error;
  options = SegmenterOptions{};
  options.max_disparity_jump_px = -1.0;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_EQ(error.rfind("max_disparity_jump_px:", 0), 0u) << error;
  EXPECT_THROW(Segmenter{options}, Error);
  const Image3f normals(2, 2, NanVector3f());
  EXPECT_THROW(SegmentNormals(normals, nullptr, options), Error);
}

TEST(Segmenter, DisparityOfAnotherSizeIsAProgrammerError) {
  const Image3f normals(4, 4, Eigen::Vector3f(0, 0, -1));
  const ImageF disparity(3, 4, 1.0f);
  EXPECT_THROW(SegmentNormals(normals, &disparity, test::NeighbourNormals()), InternalError);
}

}  // namespace
}  // namespace ssta
