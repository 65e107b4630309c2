#include <cmath>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "ssta/stereo/triangulator.h"

namespace ssta {
namespace {

RectifiedGeometry MakeGeometry(int width, int height) {
  RectifiedGeometry g;
  g.full_width = g.crop_width = width;
  g.full_height = g.crop_height = height;
  g.f = 500.0;
  g.cu = 31.5;
  g.cv = 20.25;
  g.baseline_m = 0.12;
  return g;
}

TEST(Triangulate, ConstantDisparityMatchesTheClosedForm) {
  const RectifiedGeometry g = MakeGeometry(64, 40);
  const ImageF disparity(64, 40, 12.0f);  // Z = 500 * 0.12 / 12 = 5 m
  const Image3f points = Triangulate(disparity, g, TriangulationOptions{});
  ASSERT_EQ(points.width(), 64);
  ASSERT_EQ(points.height(), 40);
  for (int v = 0; v < 40; ++v) {
    for (int u = 0; u < 64; ++u) {
      const Eigen::Vector3f& p = points(v, u);
      ASSERT_TRUE(IsFinite(p)) << v << "," << u;
      EXPECT_NEAR(p.z(), 5.0f, 1e-5f);
      EXPECT_NEAR(p.x(), (u - 31.5f) * 5.0f / 500.0f, 1e-5f);
      EXPECT_NEAR(p.y(), (v - 20.25f) * 5.0f / 500.0f, 1e-5f);
    }
  }
}

TEST(Triangulate, InvalidDisparitiesAndRangeLimitsGiveNaN) {
  const RectifiedGeometry g = MakeGeometry(6, 1);
  ImageF disparity(6, 1);
  disparity[0] = 0.0f;                                       // invalid
  disparity[1] = -3.0f;                                      // invalid
  disparity[2] = std::numeric_limits<float>::quiet_NaN();    // invalid
  disparity[3] = 60.0f / 0.25f;                              // Z = 0.25 m < min 0.3
  disparity[4] = 60.0f / 30.0f;                              // Z = 30 m > max 25
  disparity[5] = 60.0f / 24.0f;                              // Z = 24 m: kept
  const Image3f points = Triangulate(disparity, g, TriangulationOptions{});
  for (int u = 0; u < 5; ++u) EXPECT_TRUE(std::isnan(points[u].z())) << u;
  ASSERT_TRUE(IsFinite(points[5]));
  EXPECT_NEAR(points[5].z(), 24.0f, 1e-4f);

  TriangulationOptions near_only;
  near_only.min_range_m = 0.1;
  near_only.max_range_m = 1.0;
  const Image3f near_points = Triangulate(disparity, g, near_only);
  EXPECT_NEAR(near_points[3].z(), 0.25f, 1e-6f);
  EXPECT_TRUE(std::isnan(near_points[5].z()));
}

TEST(Triangulate, WrongSizeIsAProgrammerError) {
  const RectifiedGeometry g = MakeGeometry(8, 8);
  EXPECT_THROW(Triangulate(ImageF(7, 8, 1.0f), g, TriangulationOptions{}), InternalError);
}

TEST(TriangulationOptions, InvalidValuesNameTheKey) {
  std::string error;
  TriangulationOptions o;
  EXPECT_TRUE(o.IsValid(&error));
  o.min_range_m = -1.0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error.rfind("min_range_m:", 0), 0u) << error;
  o = TriangulationOptions{};
  o.max_range_m = 0.2;  // below min_range_m = 0.3
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error.rfind("max_range_m:", 0), 0u) << error;
}

}  // namespace
}  // namespace ssta
