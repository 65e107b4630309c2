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

/// The columns of a 0.1 m map whose centres lie within `radius` of (0, 0), on the surface
/// `height`, each with height sigma 0.02 m and horizontal sigma `xy_sigma`.
std::vector<SurfaceSample> Within(double radius, const std::function<double(double, double)>& height,
                                  double xy_sigma) {
  std::vector<SurfaceSample> s;
  const int reach = static_cast<int>(std::floor(radius / 0.1 + 1e-9));
  for (int j = -reach; j <= reach; ++j) {
    for (int i = -reach; i <= reach; ++i) {
      const Eigen::Vector2d xy(0.1 * i, 0.1 * j);
      if (xy.norm() > radius + 1e-9) continue;
      s.push_back({xy, height(xy.x(), xy.y()), 0.02, xy_sigma});
    }
  }
  return s;
}

TEST(JudgeSmearedSurface, AFarJumpCountsWithinTheSmearAlongItsRayAndStrayColumnsDoNot) {
  const VehicleOptions vehicle;  // step radius 0.2 m
  // Along the ray the step radius widens by the horizontal sigma, at most to twice the radius;
  // across it, it does not; both add half a cell.
  const SurfaceRegion region = SmearedRegion(0.2, 0.1, 0.15, {2.0, 0.0});
  EXPECT_NEAR(region.along_m, 0.40, 1e-12);
  EXPECT_NEAR(region.across_m, 0.25, 1e-12);
  EXPECT_NEAR(region.axis.x(), 1.0, 1e-12);
  EXPECT_NEAR(SmearedRegion(0.2, 0.1, 0.5, {0.0, -1.0}).along_m, 0.45, 1e-12);
  const SurfaceRegion around = SmearedRegion(0.2, 0.1, 0.15, Eigen::Vector2d::Zero());
  EXPECT_NEAR(around.across_m, 0.40, 1e-12);  // no direction: widened every way
  EXPECT_TRUE(region.Contains({0.4, 0.0}));
  EXPECT_FALSE(region.Contains({0.0, 0.3}));
  EXPECT_FALSE(region.Contains({0.3, 0.2}));

  // A 0.5 m jump 0.25 m from the cell along the ray, beyond its step radius's disc (0.25 m),
  // seen from far (horizontal sigma 0.2 m): the step radius's disc shows nothing and cannot
  // judge. The smear's region (0.45 m along the ray, 37 columns) holds 6 columns beyond the
  // jump, more than an eighth, and shows it: 0.5 m less one sigma of each side.
  const auto ahead = [](double x, double) { return x > 0.25 ? 0.5 : 0.0; };
  const std::vector<SurfaceSample> near = Within(SurfaceDiscRadius(0.2, 0.1), ahead, 0.2);
  const SurfaceVerdict own = JudgeSurface({0, 0}, near, 0.1, vehicle);
  EXPECT_TRUE(own.smeared);
  EXPECT_FALSE(own.determined);
  EXPECT_NEAR(own.xy_sigma_m, 0.2, 1e-12);
  const SurfaceRegion smear = SmearedRegion(0.2, 0.1, 0.2, {2.0, 0.0});
  const std::vector<SurfaceSample> wide = Within(0.45, ahead, 0.2);
  const SurfaceVerdict along = JudgeSmearedSurface({0, 0}, wide, 0.1, smear, vehicle);
  EXPECT_TRUE(along.determined && along.smeared);
  EXPECT_NEAR(along.step_m, 0.5 - 2 * 0.02, 1e-6);
  EXPECT_GT(along.probability[2], 0.999);
  // The same jump beside the ray: the ray's direction is known to a pixel, and it is open.
  const SurfaceVerdict beside = JudgeSmearedSurface({0, 0}, wide, 0.1, SmearedRegion(0.2, 0.1, 0.2, {0, 1}), vehicle);
  EXPECT_TRUE(beside.determined);
  EXPECT_GT(beside.probability[0], 0.99);
  // Nearer, four columns beyond it are under an eighth of the region's 33 (0.15 m of smear).
  EXPECT_GT(JudgeSmearedSurface({0, 0}, wide, 0.1, region, vehicle).probability[0], 0.99);

  // Level ground with three stray columns 0.6 m up (far noise): a side needs an eighth of the
  // region's columns.
  std::vector<SurfaceSample> level = Within(0.45, [](double, double) { return 0.0; }, 0.2);
  for (const Eigen::Vector2d& stray : {Eigen::Vector2d(0.3, 0.0), Eigen::Vector2d(-0.1, 0.1), Eigen::Vector2d(0.0, -0.2)}) {
    for (SurfaceSample& s : level) {
      if ((s.xy - stray).norm() < 1e-9) s.height_m = 0.6;
    }
  }
  const SurfaceVerdict strays = JudgeSmearedSurface({0, 0}, level, 0.1, smear, vehicle);
  EXPECT_TRUE(strays.determined);
  EXPECT_GT(strays.probability[0], 0.99);
  // The step radius's disc, as JudgeSurface judges it, takes two strays for a side.
  std::vector<SurfaceSample> two = Within(SurfaceDiscRadius(0.2, 0.1), [](double, double) { return 0.0; }, 0.01);
  for (SurfaceSample& s : two) {
    if (std::abs(std::abs(s.xy.x()) - 0.1) < 1e-9 && std::abs(s.xy.y()) < 1e-9) s.height_m = 0.6;
  }
  EXPECT_GT(JudgeSurface({0, 0}, two, 0.1, vehicle).probability[2], 0.99);
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
