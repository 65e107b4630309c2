#include "ssta/geometry/normal_estimator.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <random>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "geometry/smallest_eigenvector.h"
#include "geometry/synthetic_scene.h"

namespace ssta {
namespace {

using test::AngleDeg;
using test::PinholeCamera;
using test::Scene;

constexpr NormalMethod kAllMethods[] = {NormalMethod::kCovarianceMatrix,
                                        NormalMethod::kAverage3dGradient,
                                        NormalMethod::kAverageDepthChange};

// Angular error statistics over the pixels selected by `use` that have a true normal.
struct ErrorStats {
  int selected = 0;     // selected pixels with a true normal
  int estimated = 0;    // ... of which have an estimated normal
  double mean_deg = 0;  // over the estimated ones
  double max_deg = 0;
  double Coverage() const { return selected ? static_cast<double>(estimated) / selected : 0.0; }
};

ErrorStats Compare(const Image3f& estimated, const Image3f& truth,
                   const std::function<bool(int v, int u)>& use) {
  ErrorStats stats;
  double sum = 0.0;
  for (int v = 0; v < truth.height(); ++v) {
    for (int u = 0; u < truth.width(); ++u) {
      if (!IsFinite(truth(v, u)) || !use(v, u)) continue;
      ++stats.selected;
      if (!IsFinite(estimated(v, u))) continue;
      ++stats.estimated;
      const double e = AngleDeg(estimated(v, u), truth(v, u));
      sum += e;
      stats.max_deg = std::max(stats.max_deg, e);
    }
  }
  if (stats.estimated) stats.mean_deg = sum / stats.estimated;
  return stats;
}

// A plane facing the camera at an angle, through (0, 0, 5) m.
Scene TiltedPlaneScene() {
  Scene scene;
  const Eigen::Vector3d n = Eigen::Vector3d(0.3, -0.5, -0.8).normalized();
  scene.AddPlane(n, -n.dot(Eigen::Vector3d(0, 0, 5)));
  return scene;
}

NormalOptions OptionsFor(NormalMethod method) {
  NormalOptions options = test::FixedWindow13();
  options.method = method;
  return options;
}

TEST(NormalEstimator, EachMethodRecoversATiltedPlane) {
  const PinholeCamera camera;
  Image3f truth;
  const Image3f cloud = TiltedPlaneScene().Render(camera, &truth);
  for (const NormalMethod method : kAllMethods) {
    SCOPED_TRACE(NormalMethodName(method));
    NormalEstimator estimator(OptionsFor(method));
    const Image3f& normals = estimator.Compute(cloud);
    const int r = estimator.options().smoothing_size_px / 2;
    // Interior: full windows fit inside the image.
    const ErrorStats interior = Compare(normals, truth, [&](int v, int u) {
      return v >= r && u >= r && v < camera.height - r && u < camera.width - r;
    });
    EXPECT_GT(interior.selected, 250000);
    EXPECT_EQ(interior.estimated, interior.selected);
    EXPECT_LT(interior.max_deg, 0.05);
    // Near the border the window shrinks but the normal stays right.
    const ErrorStats all = Compare(normals, truth, [](int, int) { return true; });
    EXPECT_LT(all.max_deg, 0.05);
    RecordProperty(std::string(NormalMethodName(method)) + "_max_deg", std::to_string(all.max_deg));
    // Oriented towards the camera.
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      if (IsFinite(normals[i])) {
        ASSERT_LT(normals[i].dot(cloud[i]), 0.0f);
        ASSERT_NEAR(normals[i].norm(), 1.0f, 1e-5f);
      }
    }
  }
}

TEST(NormalEstimator, GroundAtGrazingAnglesUpTo20mIsExact) {
  const PinholeCamera camera;
  Image3f truth;
  const Image3f cloud = test::GroundScene(1.0).Render(camera, &truth, 20.0);
  for (const NormalMethod method : kAllMethods) {
    SCOPED_TRACE(NormalMethodName(method));
    const Image3f normals = EstimateNormals(cloud, OptionsFor(method));
    const ErrorStats stats = Compare(normals, truth, [](int, int) { return true; });
    // Only the far edge of the ground (Z = 20 m, cut by the range limit) and the image
    // border lose their normals.
    EXPECT_GT(stats.Coverage(), 0.95);
    EXPECT_LT(stats.max_deg, 0.05);
    RecordProperty(std::string(NormalMethodName(method)) + "_ground_max_deg",
                   std::to_string(stats.max_deg));
  }
}

TEST(NormalEstimator, FarOutliersDoNotCostNearWindowsTheirPrecision) {
  // A plane 1.5 m away (windows ~4 cm wide) plus a few stereo outliers at 500 m, which set the
  // fixed-point quantum of the frame.
  const PinholeCamera camera;
  Scene scene;
  const Eigen::Vector3d n = Eigen::Vector3d(0.3, -0.5, -0.8).normalized();
  scene.AddPlane(n, -n.dot(Eigen::Vector3d(0, 0, 1.5)));
  Image3f truth;
  Image3f cloud = scene.Render(camera, &truth);
  for (const auto& [v, u] : {std::pair{100, 100}, std::pair{300, 500}, std::pair{400, 50}}) {
    cloud(v, u) = (500.0 * camera.Ray(v, u)).cast<float>();
    truth(v, u) = NanVector3f();
  }
  for (const NormalMethod method : kAllMethods) {
    SCOPED_TRACE(NormalMethodName(method));
    const ErrorStats stats =
        Compare(EstimateNormals(cloud, OptionsFor(method)), truth, [](int, int) { return true; });
    EXPECT_GT(stats.Coverage(), 0.97);
    EXPECT_LT(stats.max_deg, 0.1);
    RecordProperty(std::string(NormalMethodName(method)) + "_outlier_frame_max_deg",
                   std::to_string(stats.max_deg));
  }
}

TEST(NormalEstimator, InvalidPointsGiveNanAndBarelyDisturbNeighbours) {
  const PinholeCamera camera;
  Image3f truth;
  Image3f cloud = TiltedPlaneScene().Render(camera, &truth);
  // A 9 x 9 hole and a scatter of single invalid pixels.
  Image<std::uint8_t> invalid(camera.width, camera.height, 0);
  for (int v = 200; v < 209; ++v) {
    for (int u = 300; u < 309; ++u) invalid(v, u) = 1;
  }
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> pick_v(0, camera.height - 1), pick_u(0, camera.width - 1);
  for (int i = 0; i < 3000; ++i) invalid(pick_v(rng), pick_u(rng)) = 1;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (invalid[i]) cloud[i] = NanVector3f();
  }
  for (const NormalMethod method : kAllMethods) {
    SCOPED_TRACE(NormalMethodName(method));
    const Image3f normals = EstimateNormals(cloud, OptionsFor(method));
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      if (invalid[i]) {
        ASSERT_FALSE(IsFinite(normals[i]));
      }
    }
    const ErrorStats stats = Compare(normals, truth, [&](int v, int u) { return !invalid(v, u); });
    EXPECT_GT(stats.Coverage(), 0.97);
    // Exact for all: the gradient methods locate each half by its valid points.
    EXPECT_LT(stats.max_deg, 0.05);
    RecordProperty(std::string(NormalMethodName(method)) + "_max_deg",
                   std::to_string(stats.max_deg));
  }
}

// A 1 m box whose front face is 3 m away, in front of a wall at 10 m.
Scene BoxBeforeWallScene() {
  Scene scene;
  scene.AddPlane({0, 0, -1}, 10.0);
  scene.AddBox({-0.5, -0.5, 3.0}, {0.5, 0.5, 3.5});
  return scene;
}

TEST(NormalEstimator, WindowsDoNotStraddleDepthEdges) {
  const PinholeCamera camera;
  Image3f truth;
  const Image3f cloud = BoxBeforeWallScene().Render(camera, &truth);
  // Front-face pixels within 6 px of its silhouette (the face spans 150 x 150 px).
  auto near_silhouette = [&](int v, int u) {
    if (!IsFinite(cloud(v, u)) || cloud(v, u).z() > 3.01f) return false;
    for (int dv = -6; dv <= 6; ++dv) {
      for (int du = -6; du <= 6; ++du) {
        if (!cloud.Contains(v + dv, u + du) || cloud(v + dv, u + du).z() > 3.01f) return true;
      }
    }
    return false;
  };
  auto on_face = [&](int v, int u) { return cloud(v, u).z() < 3.01f; };
  for (const NormalMethod method : kAllMethods) {
    SCOPED_TRACE(NormalMethodName(method));
    NormalEstimator estimator(OptionsFor(method));
    const Image3f& normals = estimator.Compute(cloud);
    const ErrorStats edge = Compare(normals, truth, near_silhouette);
    EXPECT_GT(edge.selected, 3000);
    EXPECT_LT(edge.max_deg, 0.05);
    RecordProperty(std::string(NormalMethodName(method)) + "_silhouette_max_deg",
                   std::to_string(edge.max_deg));
    EXPECT_GT(Compare(normals, truth, on_face).Coverage(), 0.94);  // only 2 px lost per side
    // The wall around the box is right too.
    const ErrorStats wall =
        Compare(normals, truth, [&](int v, int u) { return cloud(v, u).z() > 9.9f; });
    EXPECT_LT(wall.max_deg, 0.05);
  }
  // Without edge handling the same pixels are badly off: the check above can fail.
  NormalOptions blind = test::FixedWindow13();
  blind.max_depth_change_factor = 100.0;
  const ErrorStats straddled = Compare(EstimateNormals(cloud, blind), truth, near_silhouette);
  RecordProperty("straddled_max_deg", std::to_string(straddled.max_deg));
  EXPECT_GT(straddled.max_deg, 20.0);
}

TEST(NormalEstimator, CovarianceNormalsOfNoisyStereoGroundStayClose) {
  const PinholeCamera camera;
  Image3f truth;
  Image3f cloud = test::GroundScene(1.0).Render(camera, &truth, 20.0);
  // 0.15 px disparity noise: sigma_Z = 0.15 / (f b) * Z^2 (0.28 m at 10 m).
  const double k = 0.15 / (camera.f_px * camera.baseline_m);
  test::AddDepthNoise(k, 42, &cloud);
  const Image3f normals = EstimateNormals(cloud, test::FixedWindow13());
  auto in_range = [&](double z_min, double z_max) {
    return [&, z_min, z_max](int v, int u) {
      return IsFinite(cloud(v, u)) && cloud(v, u).z() >= z_min && cloud(v, u).z() < z_max;
    };
  };
  const ErrorStats all = Compare(normals, truth, [](int, int) { return true; });
  const ErrorStats near = Compare(normals, truth, in_range(0.0, 5.0));
  const ErrorStats far = Compare(normals, truth, in_range(10.0, 20.0));
  RecordProperty("mean_deg", std::to_string(all.mean_deg));
  RecordProperty("near_mean_deg", std::to_string(near.mean_deg));
  RecordProperty("far_mean_deg", std::to_string(far.mean_deg));
  EXPECT_GT(all.Coverage(), 0.9);  // noise must not fake depth edges everywhere
  // Near the camera the noise along the rays is large against the window's metric size and
  // tilts the total-least-squares fit most; far away the window spans metres of ground.
  EXPECT_LT(all.mean_deg, 3.5);
  EXPECT_LT(near.mean_deg, 4.5);
  EXPECT_LT(far.mean_deg, 2.5);

  // Depth-dependent smoothing trades near detail for far accuracy.
  NormalOptions adaptive = test::FixedWindow13();
  adaptive.depth_dependent_smoothing = true;
  const Image3f adaptive_normals = EstimateNormals(cloud, adaptive);
  const ErrorStats adaptive_far = Compare(adaptive_normals, truth, in_range(10.0, 20.0));
  RecordProperty("adaptive_far_mean_deg", std::to_string(adaptive_far.mean_deg));
  EXPECT_LT(adaptive_far.mean_deg, 0.8 * far.mean_deg);
}

TEST(NormalEstimator, ReusesBuffersAcrossFrameSizes) {
  PinholeCamera big;
  PinholeCamera small;
  small.width = 160;
  small.height = 120;
  small.cu_px = 79.5;
  small.cv_px = 59.5;
  small.f_px = 112.5;
  Image3f truth_big, truth_small;
  const Image3f cloud_big = TiltedPlaneScene().Render(big, &truth_big);
  const Image3f cloud_small = TiltedPlaneScene().Render(small, &truth_small);
  NormalEstimator estimator(test::FixedWindow13());
  for (int i = 0; i < 2; ++i) {
    const ErrorStats a =
        Compare(estimator.Compute(cloud_big), truth_big, [](int, int) { return true; });
    const ErrorStats b =
        Compare(estimator.Compute(cloud_small), truth_small, [](int, int) { return true; });
    EXPECT_LT(a.max_deg, 0.5);
    EXPECT_LT(b.max_deg, 0.5);
    EXPECT_GT(b.Coverage(), 0.9);
  }
  const Image3f all_invalid(8, 8, NanVector3f());
  const Image3f& none = estimator.Compute(all_invalid);
  EXPECT_EQ(none.width(), 8);
  for (std::size_t i = 0; i < none.size(); ++i) EXPECT_FALSE(IsFinite(none[i]));
}

TEST(NormalEstimator, WindowRadiusIsReportedAndCutAtEdges) {
  const PinholeCamera camera;
  const Image3f cloud = BoxBeforeWallScene().Render(camera);
  NormalEstimator estimator(test::FixedWindow13());
  estimator.Compute(cloud);
  const ImageU8& radius = estimator.window_radius_px();
  EXPECT_EQ(radius(240, 320), 6);  // box centre: full 13 x 13 window
  EXPECT_EQ(radius(0, 0), 0);      // image corner
  // Walking left from the box centre, the radius shrinks to 0 at the silhouette.
  int u = 320;
  while (cloud(240, u - 1).z() < 3.01f) --u;  // u: leftmost box pixel in row 240
  EXPECT_EQ(radius(240, u), 0);
  EXPECT_EQ(radius(240, u + 1), 0);
  EXPECT_EQ(radius(240, u + 2), 1);
  EXPECT_EQ(radius(240, u + 7), 6);
  EXPECT_EQ(radius(240, u - 1), 0);
}

// subsample 2: normals from the even points with half the window, shared by 2 x 2 blocks.
// On planes (a tilted plane; ground at grazing angles up to 20 m; a box before a wall) they
// equal the per-pixel normals within 0.05 degrees wherever both exist, lose few pixels, and
// stay NaN where the point is invalid.
TEST(NormalEstimator, SubsampledNormalsEqualFullOnesOnPlanes) {
  const PinholeCamera camera;
  struct Case {
    const char* name;
    Scene scene;
    double max_range_m;
    double min_coverage;  // of the full estimator's normals
  };
  const Case cases[] = {{"tilted_plane", TiltedPlaneScene(), 30.0, 0.97},
                        {"ground", test::GroundScene(1.0), 20.0, 0.97},
                        {"box_before_wall", BoxBeforeWallScene(), 30.0, 0.97}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    Image3f truth;
    Image3f cloud = c.scene.Render(camera, &truth, c.max_range_m);
    // Some invalid points, away from the even grid and on it.
    for (int u = 100; u < 110; ++u) cloud(201, u) = NanVector3f();
    for (int u = 300; u < 310; ++u) cloud(260, u) = NanVector3f();
    for (const bool adaptive : {false, true}) {
      SCOPED_TRACE(adaptive ? "depth-dependent" : "fixed window");
      NormalOptions options = test::FixedWindow13();
      options.smoothing_size_px = 31;
      options.depth_dependent_smoothing = adaptive;
      const Image3f full = EstimateNormals(cloud, options);
      options.subsample = 2;
      NormalEstimator estimator(options);
      const Image3f& half = estimator.Compute(cloud);
      int both = 0, full_only = 0, half_only = 0;
      double max_deg = 0.0, max_truth_deg = 0.0;
      for (int v = 0; v < cloud.height(); ++v) {
        for (int u = 0; u < cloud.width(); ++u) {
          if (!IsFinite(cloud(v, u))) {
            EXPECT_FALSE(IsFinite(half(v, u)));
            EXPECT_EQ(estimator.window_radius_px()(v, u), 0);
            continue;
          }
          const bool f = IsFinite(full(v, u)), h = IsFinite(half(v, u));
          both += f && h;
          full_only += f && !h;
          half_only += h && !f;
          if (!h) continue;
          EXPECT_NEAR(half(v, u).norm(), 1.0f, 1e-5f);
          EXPECT_LT(half(v, u).dot(cloud(v, u)), 0.0f);  // towards the camera
          EXPECT_GT(estimator.window_radius_px()(v, u), 0);
          if (f) max_deg = std::max(max_deg, AngleDeg(half(v, u), full(v, u)));
          if (IsFinite(truth(v, u))) max_truth_deg = std::max(max_truth_deg, AngleDeg(half(v, u), truth(v, u)));
        }
      }
      RecordProperty(std::string(c.name) + (adaptive ? "_adaptive" : "") + "_subsampled_max_deg",
                     std::to_string(max_deg));
      EXPECT_LT(max_deg, 0.05);
      EXPECT_LT(max_truth_deg, 0.05);
      EXPECT_GT(both, c.min_coverage * (both + full_only));
      EXPECT_LT(half_only, 0.01 * both);
    }
  }
}

// subsample 2 compares points two pixels apart, so its depth-edge threshold is the full image's
// at a gap of one pixel. A plane whose inverse depth changes by 0.012 / m per column is no edge
// at full resolution (0.012 < 0.02) and none at half resolution either (0.024 < 0.02 sqrt(2));
// with the one-pixel threshold every even point of it was an edge pixel and got no normal.
TEST(NormalEstimator, SubsampledDepthEdgesAreTheFullImagesAtTwoPixels) {
  const int width = 200, height = 120;
  const float f = 300.0f, cu = 100.0f, cv = 60.0f;
  for (const float slope : {0.012f, 0.016f}) {  // [1/m per column]; 0.016: an edge either way
    SCOPED_TRACE(slope);
    // 1/Z = 0.3 + slope u is the plane 1 = slope f X + (slope cu + 0.3) Z.
    Image3f cloud(width, height, NanVector3f());
    for (int v = 0; v < height; ++v) {
      for (int u = 0; u < width; ++u) {
        const float z = 1.0f / (0.3f + slope * u);
        cloud(v, u) = Eigen::Vector3f((u - cu) * z / f, (v - cv) * z / f, z);
      }
    }
    const Eigen::Vector3f truth = Eigen::Vector3f(slope * f, 0.0f, slope * cu + 0.3f).normalized();
    NormalOptions options = test::FixedWindow13();
    options.smoothing_size_px = 15;
    const bool edge_at_two_pixels = 2.0 * slope > options.max_depth_change_factor * std::sqrt(2.0);
    for (const int subsample : {1, 2}) {
      SCOPED_TRACE(subsample);
      options.subsample = subsample;
      NormalEstimator estimator(options);
      const Image3f& normals = estimator.Compute(cloud);
      int with_normal = 0, inside = 0;  // inside: 2 px or more from the border (whose windows
      double max_deg = 0.0;             // the border cuts to nothing)
      for (int v = 0; v < height; ++v) {
        for (int u = 0; u < width; ++u) {
          const bool is_inside = v >= 2 && u >= 2 && v < height - 2 && u < width - 2;
          inside += is_inside;
          if (!IsFinite(normals(v, u))) continue;
          with_normal += is_inside;
          max_deg = std::max(max_deg, AngleDeg(normals(v, u), normals(v, u).dot(truth) > 0 ? truth : -truth));
        }
      }
      const bool edges = subsample == 1 ? slope > options.max_depth_change_factor : edge_at_two_pixels;
      if (edges) {
        EXPECT_EQ(with_normal, 0);
      } else {
        EXPECT_EQ(with_normal, inside);
        EXPECT_LT(max_deg, 0.01);
      }
    }
  }
}

// Without depth edges the depth-dependent radius is min(side(Z) / 2, distance to the border)
// with side(Z) = floor(smoothing_size_px * clamp(sqrt(Z / 5 m), 0.5, 2)): every pixel of a
// tilted plane (depths of several metres, so radii from 5 to 13 px) gets exactly that.
TEST(NormalEstimator, DepthDependentRadiusFollowsTheFormulaExactly) {
  const PinholeCamera camera;
  const Image3f cloud = TiltedPlaneScene().Render(camera);
  NormalOptions options = test::FixedWindow13();
  options.smoothing_size_px = 17;
  options.depth_dependent_smoothing = true;
  NormalEstimator estimator(options);
  estimator.Compute(cloud);
  const ImageU8& radius = estimator.window_radius_px();
  int checked = 0, min_r = 255, max_r = 0;
  for (int v = 0; v < cloud.height(); ++v) {
    for (int u = 0; u < cloud.width(); ++u) {
      if (!IsFinite(cloud(v, u))) continue;
      const float rho = 1.0f / cloud(v, u).z();
      const double scale = std::clamp(std::sqrt(1.0 / (rho * 5.0)), 0.5, 2.0);
      const int r = std::min({static_cast<int>(17 * scale) / 2, v, u, cloud.height() - 1 - v,
                              cloud.width() - 1 - u});
      ASSERT_EQ(radius(v, u), r >= 1 ? r : 0) << "v " << v << " u " << u;
      ++checked;
      if (r == static_cast<int>(17 * scale) / 2) {
        min_r = std::min(min_r, r);
        max_r = std::max(max_r, r);
      }
    }
  }
  EXPECT_GT(checked, 300000);
  EXPECT_LT(min_r, max_r);  // the depths span several radii
}

// The sweep runs in bands of rows on several threads; each band starts its integral rows at
// the band, so the normals and radii must be those of one sweep, bit for bit, for every method,
// with depth edges, holes, noise and depth-dependent windows crossing the band boundaries.
TEST(NormalEstimator, BandsOnSeveralThreadsGiveExactlyTheSingleSweep) {
  const PinholeCamera camera;
  Scene scene = test::GroundScene(1.0);
  scene.AddBox({-0.6, -0.2, 3.0}, {0.4, 1.0, 3.6});  // a box standing on the ground
  Image3f cloud = scene.Render(camera, nullptr, 25.0);
  test::AddDepthNoise(0.15 / (camera.f_px * camera.baseline_m), 7, &cloud);
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> row(0, camera.height - 1), col(0, camera.width - 1);
  for (int i = 0; i < 3000; ++i) cloud(row(rng), col(rng)) = NanVector3f();  // holes
  auto same_bits = [](const auto& a, const auto& b) {
    return a.width() == b.width() && a.height() == b.height() &&
           std::memcmp(a.data(), b.data(), a.size() * sizeof(*a.data())) == 0;
  };
  for (const NormalMethod method : kAllMethods) {
    for (const bool adaptive : {false, true}) {
      SCOPED_TRACE(std::string(NormalMethodName(method)) + (adaptive ? " adaptive" : ""));
      NormalOptions options = OptionsFor(method);
      options.depth_dependent_smoothing = adaptive;
      options.threads = 1;
      NormalEstimator single(options);
      const Image3f& reference = single.Compute(cloud);
      int valid = 0;
      for (std::size_t i = 0; i < reference.size(); ++i) valid += IsFinite(reference[i]) ? 1 : 0;
      EXPECT_GT(valid, camera.width * camera.height / 3);  // not a vacuous comparison
      for (const int threads : {2, 3, 7}) {
        options.threads = threads;
        NormalEstimator banded(options);
        const Image3f& normals = banded.Compute(cloud);
        EXPECT_TRUE(same_bits(normals, reference)) << threads << " threads";
        EXPECT_TRUE(same_bits(banded.window_radius_px(), single.window_radius_px())) << threads << " threads";
      }
    }
  }
}

TEST(NormalOptions, ValidationNamesTheKey) {
  std::string error;
  EXPECT_TRUE(NormalOptions{}.IsValid(&error));
  NormalOptions options;
  options.smoothing_size_px = 1;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_EQ(error.rfind("smoothing_size_px:", 0), 0u) << error;
  options = NormalOptions{};
  options.max_depth_change_factor = 0.0;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_EQ(error.rfind("max_depth_change_factor:", 0), 0u) << error;
  options.max_depth_change_factor = std::nan("");
  EXPECT_FALSE(options.IsValid(nullptr));
  try {
    NormalEstimator estimator(options);
    FAIL() << "expected ssta::Error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("max_depth_change_factor:", 0), 0u);
  }
  options = NormalOptions{};
  options.subsample = 3;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_EQ(error.rfind("subsample:", 0), 0u) << error;
  options.subsample = 2;
  options.smoothing_size_px = 5;  // half of it: below the 3 x 3 minimum
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_EQ(error.rfind("smoothing_size_px:", 0), 0u) << error;
  options.smoothing_size_px = 6;
  EXPECT_TRUE(options.IsValid(&error)) << error;
  options = NormalOptions{};
  options.threads = -1;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_EQ(error.rfind("threads:", 0), 0u) << error;
}

TEST(NormalMethod, NamesRoundTripAndUnknownNamesAreErrors) {
  for (const NormalMethod method : kAllMethods) {
    EXPECT_EQ(ParseNormalMethod(NormalMethodName(method)), method);
  }
  EXPECT_EQ(ParseNormalMethod("covariance"), NormalMethod::kCovarianceMatrix);
  try {
    ParseNormalMethod("pca");
    FAIL() << "expected ssta::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("'pca'"), std::string::npos);
    EXPECT_EQ(std::string(e.what()).rfind("method:", 0), 0u);
  }
}

// Smallest-eigenvector direction of a covariance with SmallestEigenvectorOfUnitTrace in T.
template <typename T>
Eigen::Vector3d SolveUnitTrace(const Eigen::Matrix3d& c, T min_rank2) {
  const Eigen::Matrix3d m = c / c.trace();
  T x, y, z;
  internal::SmallestEigenvectorOfUnitTrace<T>(T(m(0, 0)), T(m(0, 1)), T(m(0, 2)), T(m(1, 1)),
                                              T(m(1, 2)), T(m(2, 2)), min_rank2, &x, &y, &z);
  return Eigen::Vector3d(x, y, z);
}

TEST(SmallestEigenvector, AgreesWithEigenOnRandomFlatCovariances) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), ratio(0.0, 0.2), scale(1e-4, 1e2);
  double worst_float_deg = 0.0, worst_double_deg = 0.0;
  for (int i = 0; i < 10000; ++i) {
    const Eigen::Matrix3d rotation =
        Eigen::Quaterniond(Eigen::Vector4d(unit(rng), unit(rng), unit(rng), unit(rng)).normalized())
            .toRotationMatrix();
    // lambda3 >= lambda2 >= 0.02 lambda3 (windows up to 50 times longer than wide), lambda1 <=
    // 0.2 lambda2 (flat enough to call a surface).
    const double l3 = scale(rng), l2 = l3 * (0.02 + 0.98 * (unit(rng) + 1) / 2),
                 l1 = l2 * ratio(rng);
    const Eigen::Matrix3d c =
        rotation * Eigen::Vector3d(l1, l2, l3).asDiagonal() * rotation.transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
    solver.computeDirect(c);
    const Eigen::Vector3d truth = solver.eigenvectors().col(0);
    auto angle_deg = [&](const Eigen::Vector3d& n) {
      return std::acos(std::min(1.0, std::abs(n.normalized().dot(truth)))) * 180.0 / M_PI;
    };
    const Eigen::Vector3d nf = SolveUnitTrace<float>(c, 1e-6f);
    const Eigen::Vector3d nd = SolveUnitTrace<double>(c, 1e-10);
    ASSERT_GT(nf.norm(), 0.0);
    ASSERT_GT(nd.norm(), 0.0);
    worst_float_deg = std::max(worst_float_deg, angle_deg(nf));
    worst_double_deg = std::max(worst_double_deg, angle_deg(nd));
  }
  RecordProperty("worst_float_deg", std::to_string(worst_float_deg));
  RecordProperty("worst_double_deg", std::to_string(worst_double_deg));
  EXPECT_LT(worst_float_deg, 0.1);
  EXPECT_LT(worst_double_deg, 0.1);
  // Collinear points and a single point have no normal.
  Eigen::Matrix3d line = Eigen::Matrix3d::Constant(1.0);
  EXPECT_EQ(SolveUnitTrace<float>(line, 1e-6f).norm(), 0.0);
  Eigen::Matrix3d point = Eigen::Matrix3d::Zero();
  point(0, 0) = 1e-30;  // trace must be positive; the caller rejects trace 0 itself
  EXPECT_EQ(SolveUnitTrace<float>(point, 1e-6f).norm(), 0.0);
}

}  // namespace
}  // namespace ssta
