// The sensor path's nearest-point lookup against a walk over every point.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "mapping/sensor_path.h"

namespace ssta::internal {
namespace {

Eigen::Vector2d NearestByWalk(const std::vector<Eigen::Vector3d>& path, const Eigen::Vector2d& xy) {
  Eigen::Vector2d best = xy;
  double best_d2 = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3d& p : path) {
    const double d2 = (p.head<2>() - xy).squaredNorm();
    if (d2 < best_d2) best_d2 = d2, best = p.head<2>();
  }
  return best;
}

TEST(SensorPath, FindsTheNearestPointAsAWalkOverThePathDoes) {
  // A winding 600 m drive, a point every 0.1 m, asked about places near it, across it and far
  // off it (up to 5 km: the lookup walks the path there).
  std::mt19937 rng(7);
  std::vector<Eigen::Vector3d> drive;
  Eigen::Vector3d at(-40.0, 25.0, 0.5);
  double heading = 0.3;
  std::normal_distribution<double> turn(0.0, 0.05);
  for (int i = 0; i < 6000; ++i) {
    heading += turn(rng);
    at += 0.1 * Eigen::Vector3d(std::cos(heading), std::sin(heading), 0.0);
    drive.push_back(at);
  }
  SensorPath path;
  path.Assign(drive);
  ASSERT_EQ(path.points().size(), drive.size());
  std::uniform_real_distribution<double> near(-30.0, 30.0);
  std::uniform_int_distribution<int> pick(0, static_cast<int>(drive.size()) - 1);
  for (int k = 0; k < 2000; ++k) {
    const double reach = k % 10 == 0 ? 5000.0 : 1.0;
    const Eigen::Vector2d q = drive[static_cast<std::size_t>(pick(rng))].head<2>() +
                              reach * Eigen::Vector2d(near(rng), near(rng));
    const Eigen::Vector2d expected = NearestByWalk(drive, q);
    const Eigen::Vector2d found = path.NearestXy(q);
    ASSERT_NEAR((found - q).norm(), (expected - q).norm(), 1e-9) << "asked about " << q.transpose();
  }
  // Points appended one by one are indexed as those assigned.
  SensorPath grown;
  for (const Eigen::Vector3d& p : drive) grown.Append(p);
  EXPECT_EQ(grown.NearestXy({3.0, -7.0}), path.NearestXy({3.0, -7.0}));
  // No path: the place itself.
  EXPECT_EQ(SensorPath().NearestXy({1.5, 2.5}), Eigen::Vector2d(1.5, 2.5));
}

}  // namespace
}  // namespace ssta::internal
