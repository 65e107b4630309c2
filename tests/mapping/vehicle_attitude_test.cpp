// Costs that depend on the heading: the attitude on a fitted plane in closed form, a footprint
// on an analytic 20 deg hillside, and the per-heading cost layers.

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include <Eigen/Geometry>

#include "map_test_util.h"
#include "ssta/core/error.h"
#include "ssta/core/units.h"
#include "ssta/mapping/map_export.h"
#include "ssta/mapping/vehicle_attitude.h"

namespace ssta {
namespace {

/// Points of the plane z = 0.3 + b x + c y on a 1 m x 0.6 m grid around (1, 2).
std::vector<Eigen::Vector3d> PlanePoints(double b, double c) {
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 10; ++i) {
    for (int j = 0; j < 6; ++j) {
      const double x = 0.5 + 0.1 * i, y = 1.7 + 0.1 * j;
      points.emplace_back(x, y, 0.3 + b * x + c * y);
    }
  }
  return points;
}

TEST(VehicleAttitude, BodyFrameOfThePitchAndRollStandsOnThePlane) {
  // Independent of the formula: a body frame turned by yaw, then pitched (nose up) and rolled
  // (left side up), ZYX, must have its z axis along the plane's normal, for any heading.
  const double b = 0.31, c = -0.17;
  const Eigen::Vector3d normal = Eigen::Vector3d(-b, -c, 1.0).normalized();
  VehicleOptions vehicle;
  for (double yaw_deg = -180.0; yaw_deg < 180.0; yaw_deg += 22.5) {
    const double yaw = DegToRad(yaw_deg);
    const VehicleAttitude a = AttitudeOnGround(PlanePoints(b, c), yaw, vehicle);
    ASSERT_TRUE(std::isfinite(a.pitch_deg) && std::isfinite(a.roll_deg)) << yaw_deg;
    EXPECT_EQ(a.heights, 60);
    const Eigen::Matrix3d world_R_body =
        (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(-DegToRad(a.pitch_deg), Eigen::Vector3d::UnitY()) *
         Eigen::AngleAxisd(DegToRad(a.roll_deg), Eigen::Vector3d::UnitX()))
            .toRotationMatrix();
    EXPECT_NEAR((world_R_body.col(2) - normal).norm(), 0.0, 1e-9) << yaw_deg;
    // Its forward axis points along the heading when seen from above.
    const Eigen::Vector2d forward = world_R_body.col(0).head<2>().normalized();
    EXPECT_NEAR(forward.x(), std::cos(yaw), 1e-9) << yaw_deg;
    EXPECT_NEAR(forward.y(), std::sin(yaw), 1e-9) << yaw_deg;
  }
}

TEST(VehicleAttitude, VerdictBandsAndTooFewHeights) {
  VehicleOptions v;
  v.max_pitch_deg = 20.0;
  v.max_descent_deg = 10.0;
  v.max_roll_deg = 15.0;
  auto judged = [&](double pitch, double roll) {
    VehicleAttitude a;
    a.pitch_deg = pitch;
    a.roll_deg = roll;
    JudgeAttitude(v, &a);
    return a;
  };
  EXPECT_EQ(judged(15.0, 0.0).verdict, TravClass::kTraversable);  // 0.75 of the climb limit
  EXPECT_EQ(judged(15.0, 0.0).cost, 0.0);
  EXPECT_EQ(judged(-9.0, 0.0).verdict, TravClass::kSemiTraversable);  // 0.9 of the descent limit
  EXPECT_NEAR(judged(-9.0, 0.0).cost, 0.5, 1e-12);
  EXPECT_EQ(judged(0.0, -15.5).verdict, TravClass::kNonTraversable);  // right side down, too far
  EXPECT_EQ(judged(0.0, -15.5).cost, 1.0);
  EXPECT_EQ(HeadingCost(0.6, judged(-9.0, 0.0)), 0.6);  // the class cost when it is higher
  EXPECT_EQ(HeadingCost(0.1, judged(0.0, 16.0)), 1.0);
  EXPECT_TRUE(std::isnan(HeadingCost(std::nan(""), judged(0.0, 16.0))));

  // Two points, or points in a line: no plane.
  const std::vector<Eigen::Vector3d> line = {{0, 0, 0}, {1, 1, 0.5}, {2, 2, 1.0}, {3, 3, 1.5}};
  const VehicleAttitude none = AttitudeOnGround(line, 0.0, v);
  EXPECT_TRUE(std::isnan(none.pitch_deg));
  EXPECT_EQ(none.verdict, TravClass::kUnknown);
  EXPECT_FALSE(none.WithinLimits());
}

TEST(VehicleAttitude, HillsideAllowsDrivingStraightUpAndRefusesDrivingAcross) {
  // The world: a 20 deg hillside, a vehicle that climbs 25 deg and rolls 15 deg. The
  // fused heights lie on the plane (one point per column at its centre, 1 cm sigma), so the
  // fitted plane is the hillside up to float rounding of the heights: 0.05 deg.
  const TraversabilityMap map = testing::HillsideMap(20.0, testing::HillsideVehicle());
  const FootprintQuery up{2.0, 2.0, 0.0, 1.0, 0.6};
  const FootprintResult climbing = map.QueryFootprint(up);
  EXPECT_EQ(climbing.attitude_heights, climbing.cells);
  EXPECT_NEAR(climbing.pitch_deg, 20.0, 0.05);
  EXPECT_NEAR(climbing.roll_deg, 0.0, 0.05);
  EXPECT_NE(climbing.attitude, TravClass::kNonTraversable);
  EXPECT_NE(climbing.attitude, TravClass::kUnknown);

  FootprintQuery down = up;
  down.yaw = kPi;
  EXPECT_NEAR(map.QueryFootprint(down).pitch_deg, -20.0, 0.05);

  FootprintQuery across = up;
  across.yaw = 0.5 * kPi;  // facing +y: the hillside rises to the right (+x), falls to the left
  const FootprintResult traversing = map.QueryFootprint(across);
  EXPECT_NEAR(traversing.pitch_deg, 0.0, 0.05);
  EXPECT_NEAR(traversing.roll_deg, -20.0, 0.05);  // the left side (-x) is the lower one
  EXPECT_EQ(traversing.attitude, TravClass::kNonTraversable);
  // The class under the footprint is the slope's, whatever the heading.
  EXPECT_EQ(traversing.worst, climbing.worst);
}

TEST(VehicleAttitude, HeadingLayersMatchTheFootprintQueryAtEachCell) {
  const TraversabilityMap map = testing::HillsideMap(20.0, testing::HillsideVehicle());
  const GridProjection grid =
      map.Project(Eigen::AlignedBox2d(Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(4.0, 4.0)), 0.1);
  HeadingCostOptions options;
  options.headings = 8;
  const std::vector<ImageF> layers = HeadingCosts(grid, map.metadata().vehicle, options);
  ASSERT_EQ(layers.size(), 8u);
  EXPECT_EQ(HeadingName(1, 8), "45");
  EXPECT_EQ(HeadingName(1, 16), "22.5");
  int compared = 0;
  for (int v = 5; v < 35; v += 6) {
    for (int u = 5; u < 35; u += 6) {
      const Eigen::Vector2d c = grid.PixelCenter(v, u);
      for (int k = 0; k < 8; ++k) {
        const FootprintResult f = map.QueryFootprint({c.x(), c.y(), 2.0 * kPi * k / 8, 1.0, 0.6});
        VehicleAttitude a;
        a.pitch_deg = f.pitch_deg;
        a.roll_deg = f.roll_deg;
        JudgeAttitude(map.metadata().vehicle, &a);
        EXPECT_NEAR(layers[k](v, u), HeadingCost(grid.cost(v, u), a), 1e-4) << v << "," << u << " heading " << k;
        ++compared;
      }
      // Across the slope (90 and 270 deg) the 15 deg roll limit refuses it: cost 1; up and
      // down it keeps the class cost (20 deg is 0.8 of the 25 deg limits: the band's edge).
      EXPECT_EQ(layers[2](v, u), 1.0f);
      EXPECT_EQ(layers[6](v, u), 1.0f);
      EXPECT_NEAR(layers[0](v, u), grid.cost(v, u), 1e-3);
      EXPECT_NEAR(layers[4](v, u), grid.cost(v, u), 1e-3);
    }
  }
  EXPECT_EQ(compared, 5 * 5 * 8);

  options.footprint_width_m = 0.0;
  EXPECT_THROW(HeadingCosts(grid, map.metadata().vehicle, options), Error);
}

}  // namespace
}  // namespace ssta
