// The verdict of a cell from the fused surface around it, on analytic worlds whose class is known
// in closed form (default vehicle: slope 15 / 25 deg, step 0.1 / 0.2 m, step radius 0.2 m).

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>

#include "ssta/core/units.h"
#include "ssta/mapping/surface_judgement.h"

namespace ssta {
namespace {

/// The columns of a 0.1 m map that judge the cell at (0, 0) (centres within SurfaceDiscRadius:
/// the step radius and half a cell), on the surface `height`, each with `sigma` of noise drawn
/// from `seed` (0: exact heights).
std::vector<SurfaceSample> Disc(const std::function<double(double, double)>& height, double sigma,
                                unsigned seed = 0) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  std::vector<SurfaceSample> s;
  for (int j = -2; j <= 2; ++j) {
    for (int i = -2; i <= 2; ++i) {
      const Eigen::Vector2d xy(0.1 * i, 0.1 * j);
      if (xy.norm() > SurfaceDiscRadius(0.2, 0.1) + 1e-9) continue;
      s.push_back({xy, height(xy.x(), xy.y()) + (seed ? noise(rng) : 0.0), sigma});
    }
  }
  return s;
}

int Verdict(const SurfaceVerdict& v) {
  return static_cast<int>(std::max_element(v.probability.begin(), v.probability.end()) - v.probability.begin()) + 1;
}

TEST(JudgeSurface, SmoothRampsAreJudgedByTheirSlopeAlone) {
  const VehicleOptions vehicle;
  for (const auto& [deg, expected] : {std::pair{5.0, 1}, {20.0, 2}, {32.0, 3}}) {
    SCOPED_TRACE(deg);
    const double g = std::tan(DegToRad(deg));
    const SurfaceVerdict v = JudgeSurface({0, 0}, Disc([g](double x, double) { return 3.0 + g * x; }, 0.01), 0.1, vehicle);
    ASSERT_TRUE(v.determined);
    EXPECT_NEAR(v.slope_deg, deg, 0.01);
    EXPECT_LT(v.step_m, 0.06);  // a ramp has no step
    EXPECT_EQ(Verdict(v), expected);
    EXPECT_GT(v.probability[expected - 1], 0.9);
  }
}

TEST(JudgeSurface, AJumpInTheDiscIsAStepOfItsHeightOnEitherSide) {
  const VehicleOptions vehicle;
  for (const auto& [jump, expected] : {std::pair{0.05, 1}, {0.15, 2}, {0.4, 3}}) {
    for (const double edge : {-0.05, 0.05}) {  // the cell below the jump and the cell on top
      SCOPED_TRACE(std::to_string(jump) + (edge < 0 ? " on top" : " below"));
      const auto box = [jump, edge](double x, double) { return x >= edge ? 0.0 : jump; };
      const SurfaceVerdict v = JudgeSurface({0, 0}, Disc(box, 0.005), 0.1, vehicle);
      ASSERT_TRUE(v.determined);
      EXPECT_NEAR(v.step_m, jump, 0.05);
      if (jump > 0.1) {
        EXPECT_LT(v.slope_deg, 1.0);  // the plane keeps to the cell's own side of the jump
      }
      EXPECT_EQ(Verdict(v), expected);
    }
  }
}

TEST(JudgeSurface, AJumpWithinTheStepRadiusOfTheCellsGroundMakesItNonTraversable) {
  // A 0.4 m jump along a straight edge `distance` from the cell's centre. The cell's ground
  // reaches half a cell (0.05 m) towards it, so the class rule calls the cell non-traversable
  // up to 0.25 m. The columns centred up to 0.2 m away see the edges at 0.12 and 0.18 m with
  // three columns beyond them; a disc of the step radius alone holds one there and takes it
  // for a stray. Beyond 0.3 m no column of the disc lies across the jump.
  const VehicleOptions vehicle;
  for (const auto& [distance, expected] : {std::pair{0.12, 3}, {0.18, 3}, {0.32, 1}}) {
    for (const double rise : {0.4, -0.4}) {  // the cell below the jump and the cell on top
      SCOPED_TRACE(std::to_string(distance) + (rise > 0 ? " below" : " on top"));
      const double edge = distance;
      const auto wall = [rise, edge](double x, double) { return x >= edge ? rise : 0.0; };
      const SurfaceVerdict v = JudgeSurface({0, 0}, Disc(wall, 0.005), 0.1, vehicle);
      ASSERT_TRUE(v.determined);
      EXPECT_EQ(Verdict(v), expected);
      if (expected == 3) {
        EXPECT_NEAR(v.step_m, 0.4, 0.02);
      }
    }
  }
}

TEST(JudgeSurface, LevelGroundIsTraversableAtAnyHeight) {
  const VehicleOptions vehicle;
  for (const double height : {-1.5, 0.0, 0.6, 4.0}) {
    const SurfaceVerdict v = JudgeSurface({0, 0}, Disc([height](double, double) { return height; }, 0.01), 0.1, vehicle);
    EXPECT_EQ(Verdict(v), 1) << height;
  }
}

TEST(JudgeSurface, NoisyFarHeightsGiveALevelSurfaceAnUnsureVerdict) {
  const VehicleOptions vehicle;
  const auto level = [](double, double) { return 0.0; };
  const SurfaceVerdict near = JudgeSurface({0, 0}, Disc(level, 0.01, 7), 0.1, vehicle);
  const SurfaceVerdict far = JudgeSurface({0, 0}, Disc(level, 0.15, 7), 0.1, vehicle);
  EXPECT_GT(near.probability[0], 0.95);
  EXPECT_LT(far.probability[0], near.probability[0] - 0.2);  // the noise leaves it open
  EXPECT_GT(far.slope_sigma_deg, 5 * near.slope_sigma_deg);
}

TEST(JudgeSurface, HeightsSmearedSidewaysJudgeNothing) {
  // A 0.5 m box edge through the disc: seen from near (heights where their columns are), a
  // non-traversable step; with horizontal sigmas above half the step radius the heights may
  // belong to columns beyond the disc, and the surface says so instead of judging.
  const VehicleOptions vehicle;
  std::vector<SurfaceSample> edge = Disc([](double x, double) { return x > 0.05 ? 0.5 : 0.0; }, 0.01);
  for (SurfaceSample& s : edge) s.xy_sigma_m = 0.02;
  const SurfaceVerdict near = JudgeSurface({0, 0}, edge, 0.1, vehicle);
  EXPECT_TRUE(near.determined && !near.smeared);
  EXPECT_GT(near.probability[2], 0.99);
  for (SurfaceSample& s : edge) s.xy_sigma_m = 0.6 * vehicle.step_radius_m;
  const SurfaceVerdict far = JudgeSurface({0, 0}, edge, 0.1, vehicle);
  EXPECT_TRUE(far.smeared);
  EXPECT_FALSE(far.determined);
}

TEST(JudgeSurface, TooFewColumnsLeaveTheCellUndetermined) {
  const VehicleOptions vehicle;
  std::vector<SurfaceSample> three = {{{0, 0}, 0, 0.01}, {{0.1, 0}, 0, 0.01}, {{0, 0.1}, 0, 0.01}};
  EXPECT_FALSE(JudgeSurface({0, 0}, three, 0.1, vehicle).determined);
  std::vector<SurfaceSample> line;
  for (int i = -2; i <= 2; ++i) line.push_back({{0.1 * i, 0}, 0, 0.01});
  EXPECT_FALSE(JudgeSurface({0, 0}, line, 0.1, vehicle).determined);
}

}  // namespace
}  // namespace ssta
