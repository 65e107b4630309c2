#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include <gtest/gtest.h>

#include "map_test_util.h"

namespace ssta {
namespace {

using testing::OctoMapCarving;

using testing::NodeAt;
using testing::Pt;
using testing::Softmax;

// One axis-aligned ray: the sensor in voxel (0, 0, 0), target voxel A two metres along x and B
// behind it on the same ray.
const Eigen::Vector3d kOrigin(0.05, 0.05, 0.05);
const Eigen::Vector3d kA(2.05, 0.05, 0.05);
const Eigen::Vector3d kB(4.05, 0.05, 0.05);

std::vector<ClassifiedPoint> At(const Eigen::Vector3d& p, TravClass c, float slope = 0.0f, float step = 0.0f) {
  return {Pt(p.x(), p.y(), p.z(), c, slope, step)};
}

/// The class log-odds after the given verdicts (index 0..2), by the documented update.
std::array<float, 3> ExpectedLogOdds(const std::vector<int>& verdicts, const MapOptions& o) {
  std::array<float, 3> l{};
  for (const int v : verdicts) {
    for (int k = 0; k < 3; ++k) {
      const double delta = k == v ? o.class_hit_log_odds : o.class_miss_log_odds;
      l[k] = static_cast<float>(std::min(o.class_clamp_max, std::max(o.class_clamp_min, l[k] + delta)));
    }
  }
  return l;
}

TEST(Fusion, RepeatedObservationsRaiseTheClassProbabilityMonotonicallyToTheClamp) {
  TraversabilityMap map(OctoMapCarving());
  const MapOptions& o = map.options();
  double previous = 0.0;
  int strictly_rising = 0;
  for (int frame = 0; frame < 12; ++frame) {
    map.InsertFrame(At(kA, TravClass::kTraversable), kOrigin, frame);
    const CellInfo cell = map.CellAt(kA);
    ASSERT_EQ(cell.cls, TravClass::kTraversable);
    ASSERT_GE(cell.probability, previous);
    if (cell.probability > previous) ++strictly_rising;
    previous = cell.probability;
    EXPECT_EQ(cell.observations, static_cast<std::uint32_t>(frame + 1));
    EXPECT_EQ(cell.last_seen_ns, frame);
  }
  // L1: 0.85, 1.7, 2.55, 3.4, then the 3.5 clamp; L2 = L3 reach -2.0 at the fifth frame.
  EXPECT_EQ(strictly_rising, 5);
  const double at_clamp = std::exp(3.5) / (std::exp(3.5) + 2.0 * std::exp(-2.0));
  EXPECT_NEAR(previous, at_clamp, 1e-7);
  EXPECT_NEAR(previous, 0.991893, 1e-6);
  const CellInfo cell = map.CellAt(kA);
  EXPECT_NEAR(cell.occupancy, o.occupancy_clamp_max_prob, 1e-4);
  EXPECT_NEAR(cell.cost, 0.25 * 1.5 * (1.0 - at_clamp), 1e-9);  // traversable, nearly certain
}

TEST(Fusion, AVoxelSeenThroughLosesOccupancyAndItsClass) {
  TraversabilityMap map(OctoMapCarving());
  map.InsertFrame(At(kA, TravClass::kTraversable), kOrigin, 1);
  ASSERT_TRUE(map.CellAt(kA).occupied);
  // The surface is gone: now the rays run through A to B. Log-odds after one hit and n misses:
  // logodds(0.7) + n logodds(0.4) = 0.847 - 0.405 n: occupied for n <= 2, free from n = 3.
  for (int n = 1; n <= 3; ++n) {
    map.InsertFrame(At(kB, TravClass::kTraversable), kOrigin, 1 + n);
    const double expected = std::log(0.7 / 0.3) + n * std::log(0.4 / 0.6);
    EXPECT_NEAR(NodeAt(map, kA)->getLogOdds(), expected, 1e-6) << n;
    EXPECT_EQ(map.CellAt(kA).occupied, n <= 2) << n;
  }
  const CellInfo a = map.CellAt(kA);
  EXPECT_TRUE(a.observed);
  EXPECT_EQ(a.cls, TravClass::kUnknown);  // free space has no class
  EXPECT_TRUE(std::isnan(a.cost));
  EXPECT_LT(a.occupancy, 0.5);
  // The class evidence decayed to exactly zero: 0.85 -> 0.45 -> 0.05 -> 0, -0.4 -> 0.
  for (const float l : NodeAt(map, kA)->class_log_odds) EXPECT_EQ(l, 0.0f);
  EXPECT_EQ(a.observations, 1u);   // history is kept
  EXPECT_EQ(a.last_seen_ns, 1);
  // Many more misses: occupancy settles at the lower clamp.
  for (int n = 0; n < 10; ++n) map.InsertFrame(At(kB, TravClass::kTraversable), kOrigin, 10 + n);
  EXPECT_NEAR(map.CellAt(kA).occupancy, map.options().occupancy_clamp_min_prob, 1e-4);
  // B itself is now confidently traversable and the column top at A's x is empty.
  EXPECT_EQ(map.CellAt(kB).cls, TravClass::kTraversable);
  EXPECT_FALSE(map.TopSurfaceAt(kA.x(), kA.y()).observed);
}

TEST(Fusion, RaysLeaveVoxelsHeldAsTraversableAsTheyAreWhenAskedTo) {
  // A is seen one to three times, then eight frames see B through it. With
  // free_space_keeps_traversable only a voxel whose verdict is traversable keeps its occupancy
  // and class evidence bit for bit; obstacles, slopes, voxels outvoted and undecided voxels are
  // cleared as without it.
  struct Case {
    std::vector<TravClass> views;
    bool kept;
  };
  const std::vector<Case> cases = {
      {{TravClass::kTraversable}, true},
      {{TravClass::kTraversable, TravClass::kTraversable}, true},
      {{TravClass::kNonTraversable}, false},
      {{TravClass::kSemiTraversable}, false},
      {{TravClass::kTraversable, TravClass::kNonTraversable, TravClass::kNonTraversable}, false},
      {{TravClass::kUndecided}, false},
  };
  for (const bool keep : {false, true}) {
    for (std::size_t i = 0; i < cases.size(); ++i) {
      MapOptions options = OctoMapCarving();
      options.free_space_keeps_traversable = keep;
      TraversabilityMap map(options);
      std::int64_t t = 0;
      for (const TravClass c : cases[i].views) map.InsertFrame(At(kA, c), kOrigin, ++t);
      ASSERT_TRUE(map.CellAt(kA).occupied) << i;
      const float occupancy_before = NodeAt(map, kA)->getLogOdds();
      const std::array<float, 3> classes_before = NodeAt(map, kA)->class_log_odds;
      for (int n = 0; n < 8; ++n) map.InsertFrame(At(kB, TravClass::kTraversable), kOrigin, ++t);
      const bool kept = keep && cases[i].kept;
      EXPECT_EQ(map.CellAt(kA).occupied, kept) << keep << " case " << i;
      if (kept) {
        EXPECT_EQ(NodeAt(map, kA)->getLogOdds(), occupancy_before) << i;
        EXPECT_EQ(NodeAt(map, kA)->class_log_odds, classes_before) << i;
        EXPECT_EQ(map.CellAt(kA).cls, TravClass::kTraversable) << i;
      }
      // The free space in front of A is carved either way.
      EXPECT_LT(map.CellAt({1.05, 0.05, 0.05}).occupancy, 0.5) << keep << " case " << i;
    }
  }
}

TEST(Fusion, GrazingRaysKeepTheGroundTheyPassOverWithClearance) {
  // A camera 0.8 m above flat ground at z = 0 sees a ground voxel at 9.5 m, then one at 10 m: the
  // ray to the far point runs within one voxel (0.1 m) of the ground over its last 1.25 m, so it
  // passes through the voxel seen first (at x = 9.55 the ray is 0.09 m up). Without clearance
  // that ground voxel is cleared; with 0.1 m the ray stops 1.25 m short and keeps it.
  const Eigen::Vector3d camera(0.05, 0.05, 0.85);
  const Eigen::Vector3d near(9.55, 0.05, 0.05), far(10.05, 0.05, 0.05);
  for (const double clearance : {0.0, 0.1}) {
    MapOptions options = OctoMapCarving();
    options.free_space_clearance_m = clearance;
    TraversabilityMap map(options);
    map.InsertFrame(At(near, TravClass::kTraversable), camera, 1);
    ASSERT_TRUE(map.CellAt(near).occupied);
    for (int n = 0; n < 4; ++n) map.InsertFrame(At(far, TravClass::kTraversable), camera, 2 + n);
    EXPECT_EQ(map.CellAt(near).occupied, clearance > 0) << clearance;
    // Free space well above the ground is carved either way.
    EXPECT_TRUE(map.CellAt({5.05, 0.05, 0.45}).observed) << clearance;
  }
}

TEST(Fusion, RaysToObstaclesClearTheSmearInFrontOfThemUnlessTheyEndBelowTheGround) {
  // A camera 0.85 m up sees a point 0.45 m up at 10 m, once 1 m nearer (the smear of stereo's
  // depth noise, voxel S) and then four times where it is (E). The ray to E runs through S
  // (0.49 m up at x = 9.05) within 2 m of its end, where the 0.1 m clearance stops it
  // (0.1 / sin(elevation) = 2.5 m, capped at 2). With the obstacle shortening k r^2 (r = 10.01 m)
  // instead, the ray runs on to 0.80 m short of E for k = 0.008 and S is free after three misses
  // (0.85 - 3 x 0.41 < 0); k = 0.012 stops it 1.20 m short, before S. Only when E's points are
  // non-traversable and not below the ground: traversable points, and points below the ground
  // (a pit's wall), keep the clearance, as does the option off.
  const Eigen::Vector3d camera(0.05, 0.05, 0.85);
  const Eigen::Vector3d smear(9.05, 0.05, 0.45), end(10.05, 0.05, 0.45);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  struct Case {
    double k;
    TravClass cls;
    float height_m;
    bool cleared;
  };
  for (const Case& c : {Case{-1.0, TravClass::kNonTraversable, 0.45f, false},
                        Case{0.008, TravClass::kNonTraversable, 0.45f, true},
                        Case{0.0, TravClass::kNonTraversable, 0.45f, true},
                        Case{0.012, TravClass::kNonTraversable, 0.45f, false},
                        Case{0.008, TravClass::kNonTraversable, nan, true},
                        Case{0.008, TravClass::kNonTraversable, -0.04f, true},
                        Case{0.008, TravClass::kNonTraversable, -0.5f, false},
                        Case{0.008, TravClass::kSemiTraversable, 0.45f, false},
                        Case{0.008, TravClass::kTraversable, 0.45f, false}}) {
    SCOPED_TRACE(::testing::Message() << "k " << c.k << ", class " << static_cast<int>(c.cls) << ", height "
                                      << c.height_m);
    MapOptions options = OctoMapCarving();
    options.free_space_clearance_m = 0.1;
    options.free_space_obstacle_shortening_per_m2 = c.k;
    TraversabilityMap map(options);
    map.InsertFrame(At(smear, TravClass::kNonTraversable), camera, 1);
    ASSERT_TRUE(map.CellAt(smear).occupied);
    for (int n = 0; n < 4; ++n) {
      std::vector<ClassifiedPoint> points = At(end, c.cls);
      points[0].height_m = c.height_m;
      map.InsertFrame(points, camera, 2 + n);
    }
    EXPECT_EQ(map.CellAt(smear).occupied, !c.cleared);
    EXPECT_TRUE(map.CellAt(end).occupied);
    EXPECT_EQ(map.CellAt(end).cls, c.cls);
  }
  MapOptions bad = OctoMapCarving();
  bad.free_space_obstacle_shortening_per_m2 = std::nan("");
  std::string error;
  EXPECT_FALSE(bad.IsValid(&error));
  EXPECT_EQ(error.rfind("free_space_obstacle_shortening_per_m2:", 0), 0u) << error;
}

TEST(Fusion, ThreeNonTraversableViewsOutvoteOneTraversable) {
  TraversabilityMap map(OctoMapCarving());
  for (int i = 0; i < 3; ++i) map.InsertFrame(At(kA, TravClass::kNonTraversable), kOrigin, i);
  map.InsertFrame(At(kA, TravClass::kTraversable), kOrigin, 3);
  const CellInfo cell = map.CellAt(kA);
  EXPECT_EQ(cell.cls, TravClass::kNonTraversable);
  const auto expected = ExpectedLogOdds({2, 2, 2, 0}, map.options());  // 2.15, -0.35, -1.6
  EXPECT_EQ(NodeAt(map, kA)->class_log_odds, expected);
  EXPECT_NEAR(expected[2], 2.15f, 1e-5);
  EXPECT_NEAR(cell.probability, Softmax(expected, 2), 1e-12);
  EXPECT_NEAR(cell.probability, 0.904484, 1e-6);
  EXPECT_EQ(cell.cost, 1.0);
  EXPECT_EQ(cell.observations, 4u);
}

TEST(Fusion, OneUpdatePerVoxelPerFrameByMajority) {
  TraversabilityMap map(OctoMapCarving());
  std::vector<ClassifiedPoint> points;
  // Seven traversable and three non-traversable points inside voxel A, off-centre.
  for (int i = 0; i < 7; ++i) points.push_back(Pt(2.01 + 0.01 * i, 0.02, 0.03, TravClass::kTraversable, 10.0f, 0.02f));
  for (int i = 0; i < 3; ++i) points.push_back(Pt(2.02, 0.08, 0.07, TravClass::kNonTraversable, 40.0f, -0.3f));
  const InsertStats stats = map.InsertFrame(points, kOrigin, 5);
  EXPECT_EQ(stats.points_in, 10u);
  EXPECT_EQ(stats.points_hit, 10u);
  EXPECT_EQ(stats.voxels_hit, 1u);
  EXPECT_EQ(stats.voxels_with_class, 1u);
  EXPECT_EQ(stats.voxels_freed, 20u);  // the 20 voxels from the origin up to A
  const CellInfo cell = map.CellAt(kA);
  EXPECT_EQ(cell.cls, TravClass::kTraversable);
  EXPECT_EQ(cell.observations, 1u);
  EXPECT_NEAR(cell.probability, Softmax(ExpectedLogOdds({0}, map.options()), 0), 1e-12);
  EXPECT_NEAR(cell.frame_mean_slope_deg, (7 * 10.0 + 3 * 40.0) / 10.0, 1e-4);
  EXPECT_NEAR(cell.frame_mean_step_m, (7 * 0.02 - 3 * 0.3) / 10.0, 1e-6);
  EXPECT_NEAR(cell.max_step_m, 0.3, 1e-6);
  // A tie goes to the worse class.
  TraversabilityMap tie(OctoMapCarving());
  tie.InsertFrame({Pt(kA.x(), 0.05, 0.05, TravClass::kTraversable), Pt(kA.x(), 0.05, 0.05, TravClass::kSemiTraversable)},
                  kOrigin, 1);
  EXPECT_EQ(tie.CellAt(kA).cls, TravClass::kSemiTraversable);
  // With class_worst_share (shipped 0.25) three non-traversable points of ten make the voxel's
  // vote non-traversable; two of ten do not.
  for (const int red : {3, 2}) {
    MapOptions options = OctoMapCarving();
    options.class_worst_share = 0.25;
    TraversabilityMap share(options);
    std::vector<ClassifiedPoint> mixed;
    for (int i = 0; i < 10; ++i) {
      mixed.push_back(Pt(2.01 + 0.005 * i, 0.02, 0.03, i < red ? TravClass::kNonTraversable : TravClass::kTraversable));
    }
    share.InsertFrame(mixed, kOrigin, 1);
    EXPECT_EQ(share.CellAt(kA).cls, red == 3 ? TravClass::kNonTraversable : TravClass::kTraversable) << red;
  }
}

TEST(Fusion, SlopeAndStepAreRunningMeansOverFrames) {
  TraversabilityMap map(OctoMapCarving());
  map.InsertFrame(At(kA, TravClass::kSemiTraversable, 10.0f, 0.05f), kOrigin, 1);
  map.InsertFrame(At(kA, TravClass::kSemiTraversable, 20.0f, 0.15f), kOrigin, 2);
  map.InsertFrame(At(kA, TravClass::kSemiTraversable, NAN, NAN), kOrigin, 3);  // not averaged
  const CellInfo cell = map.CellAt(kA);
  EXPECT_EQ(cell.observations, 3u);
  EXPECT_NEAR(cell.frame_mean_slope_deg, 15.0, 1e-5);
  EXPECT_NEAR(cell.frame_mean_step_m, 0.10, 1e-6);
  EXPECT_NEAR(cell.max_step_m, 0.15, 1e-6);
  // The frames' votes decided the voxel's class, not a slope or step: the semi band's middle.
  EXPECT_TRUE(std::isnan(cell.slope_deg) && std::isnan(cell.step_m));
  EXPECT_NEAR(cell.cost, 0.5, 1e-12);
}

TEST(Fusion, UndecidedPointsUpdateOccupancyButNotClasses) {
  TraversabilityMap map(OctoMapCarving());
  map.InsertFrame(At(kA, TravClass::kUndecided), kOrigin, 7);
  map.InsertFrame(At(kB, TravClass::kUnknown), {4.05, 2.05, 0.05}, 8);
  for (const auto& p : {kA, kB}) {
    const CellInfo cell = map.CellAt(p);
    EXPECT_TRUE(cell.occupied);
    EXPECT_EQ(cell.cls, TravClass::kUndecided);
    EXPECT_EQ(cell.observations, 0u);
    EXPECT_TRUE(std::isnan(cell.cost));
    EXPECT_TRUE(std::isnan(cell.probability));
    EXPECT_TRUE(std::isnan(cell.slope_deg));
    for (const float l : NodeAt(map, p)->class_log_odds) EXPECT_EQ(l, 0.0f);
  }
  EXPECT_EQ(map.CellAt(kA).last_seen_ns, 7);
  EXPECT_EQ(map.TopSurfaceAt(kA.x(), kA.y()).cls, TravClass::kUndecided);
}

TEST(Fusion, PointsBeyondRangeClearSpaceOnlyUpToTheRange) {
  TraversabilityMap map(OctoMapCarving());  // max_range_m 15
  const Eigen::Vector3d far(20.05, 0.05, 0.05);
  const InsertStats stats = map.InsertFrame(At(far, TravClass::kTraversable), kOrigin, 1);
  EXPECT_EQ(stats.points_beyond_range, 1u);
  EXPECT_EQ(stats.voxels_hit, 0u);
  EXPECT_FALSE(map.CellAt(far).observed);
  const CellInfo mid = map.CellAt({10.05, 0.05, 0.05});
  EXPECT_TRUE(mid.observed);
  EXPECT_FALSE(mid.occupied);
  EXPECT_TRUE(map.CellAt({14.85, 0.05, 0.05}).observed);
  EXPECT_FALSE(map.CellAt({15.25, 0.05, 0.05}).observed);
}

TEST(Fusion, AFrameFromAnInvalidOriginIsSkippedWithAReason) {
  TraversabilityMap map(OctoMapCarving());
  const InsertStats stats = map.InsertFrame(At(kA, TravClass::kTraversable), {NAN, 0.0, 0.0}, 1);
  EXPECT_FALSE(stats.inserted);
  EXPECT_FALSE(stats.reason.empty());
  EXPECT_EQ(map.NumNodes(), 0u);
  EXPECT_EQ(map.frames_inserted(), 0u);
  const InsertStats bad_points = map.InsertFrame({Pt(NAN, 0, 0, TravClass::kTraversable), Pt(1e9, 0, 0, TravClass::kTraversable)},
                                                 kOrigin, 2);
  EXPECT_TRUE(bad_points.inserted);
  EXPECT_EQ(bad_points.points_rejected, 2u);
}

TEST(Fusion, OptionsAreValidatedNamingTheKey) {
  MapOptions options = OctoMapCarving();
  std::string error;
  EXPECT_TRUE(options.IsValid(&error));
  options.resolution_m = 0.0;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_EQ(error.rfind("resolution_m:", 0), 0u) << error;
  options = OctoMapCarving();
  options.occupancy_hit_prob = 0.4;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_EQ(error.rfind("occupancy_hit_prob:", 0), 0u) << error;
  options = OctoMapCarving();
  options.class_clamp_max = -1.0;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_EQ(error.rfind("class_clamp_max:", 0), 0u) << error;
  EXPECT_THROW(TraversabilityMap{options}, Error);
  options = OctoMapCarving();
  options.free_space_ray_cell = 3;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_EQ(error.rfind("free_space_ray_cell:", 0), 0u) << error;
  options = OctoMapCarving();
  options.free_space_no_return_stop_prob = options.occupancy_clamp_max_prob;  // no voxel would stop a ray
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_EQ(error.rfind("free_space_no_return_stop_prob:", 0), 0u) << error;
}


/// Hash of an OcTreeKey for the reference sets below.
struct KeyHash {
  std::size_t operator()(const octomap::OcTreeKey& k) const {
    return (static_cast<std::size_t>(k[0]) << 32) ^ (static_cast<std::size_t>(k[1]) << 16) ^ k[2];
  }
};

/// One frame of `count` points (one per voxel) uniform in [-extent, extent]^2 x [-1, 2] m about
/// `origin`, into a fresh map with `options`; then every voxel must be what OctoMap's own ray
/// walk (computeRayKeys) says: the union of the rays' keys minus the hit voxels is free after
/// one miss, the hit voxels occupied after one hit, and nothing else is in the tree.
void ExpectFreeSpaceIsComputeRayKeys(const MapOptions& options, const Eigen::Vector3d& origin, double extent,
                                     int count, unsigned seed) {
  TraversabilityMap map(options);
  const internal::TravOcTree& tree = testing::Tree(map);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> xy(-extent, extent), z(-1.0, 2.0);
  std::vector<ClassifiedPoint> points;
  std::unordered_set<octomap::OcTreeKey, KeyHash> used;
  while (static_cast<int>(points.size()) < count) {
    const ClassifiedPoint p = Pt(origin.x() + xy(rng), origin.y() + xy(rng), origin.z() + z(rng),
                                 TravClass::kTraversable);
    if (used.insert(tree.coordToKey(p.world_p.x(), p.world_p.y(), p.world_p.z())).second) points.push_back(p);
  }
  const InsertStats stats = map.InsertFrame(points, origin, 1);

  const octomap::point3d o(static_cast<float>(origin.x()), static_cast<float>(origin.y()),
                           static_cast<float>(origin.z()));
  std::unordered_set<octomap::OcTreeKey, KeyHash> hit, free;
  octomap::KeyRay ray;
  for (const ClassifiedPoint& p : points) {
    const Eigen::Vector3d w = p.world_p.cast<double>();
    Eigen::Vector3d end = w;
    if ((w - origin).norm() > options.max_range_m) {
      end = origin + (w - origin).normalized() * options.max_range_m;  // as InsertFrame clips it
    } else {
      hit.insert(tree.coordToKey(w.x(), w.y(), w.z()));
    }
    const octomap::point3d e(static_cast<float>(end.x()), static_cast<float>(end.y()), static_cast<float>(end.z()));
    ASSERT_TRUE(tree.computeRayKeys(o, e, ray));
    free.insert(ray.begin(), ray.end());
  }
  for (const auto& k : hit) free.erase(k);
  ASSERT_EQ(stats.voxels_hit, hit.size());
  ASSERT_EQ(stats.voxels_freed, free.size());

  const float miss = octomap::logodds(options.occupancy_miss_prob);
  const float hit_l = octomap::logodds(options.occupancy_hit_prob);
  for (const auto& k : free) {
    const internal::TravNode* node = tree.search(k);
    ASSERT_NE(node, nullptr);
    ASSERT_EQ(node->getLogOdds(), miss);
  }
  for (const auto& k : hit) {
    const internal::TravNode* node = tree.search(k);
    ASSERT_NE(node, nullptr);
    ASSERT_EQ(node->getLogOdds(), hit_l);
  }
  // Nothing else: the leaves (pruned free blocks counted voxel by voxel) add up to both sets.
  std::size_t free_voxels = 0, hit_voxels = 0;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const std::size_t n = std::size_t{1} << (3 * (tree.getTreeDepth() - it.getDepth()));
    (it->getLogOdds() < 0.0f ? free_voxels : hit_voxels) += n;
  }
  EXPECT_EQ(free_voxels, free.size());
  EXPECT_EQ(hit_voxels, hit.size());
}

TEST(Fusion, FreeSpaceIsExactlyOctoMapsRayWalkInsideTheRayBox) {
  MapOptions options = OctoMapCarving();  // free_space_clearance_m 0: rays run to the points
  // Points out to 17 m, so some lie beyond max_range_m (15 m) and clear space only.
  ExpectFreeSpaceIsComputeRayKeys(options, {0.37, -1.21, 1.53}, 12.0, 3000, 11);
}

TEST(Fusion, FreeSpaceIsExactlyOctoMapsRayWalkWhenTheRayBoxIsTooLargeForABitmap) {
  MapOptions options = OctoMapCarving();
  options.resolution_m = 1.0;
  options.max_range_m = 1000.0;
  // +-600 voxels in x and y: over 2^26 voxels in the rays' box, so the free voxels go to a set.
  ExpectFreeSpaceIsComputeRayKeys(options, {-3.3, 7.9, 0.4}, 600.0, 300, 12);
}

/// A ray that ranged nothing, from `origin` towards `towards`.
ClassifiedPoint NoReturn(const Eigen::Vector3d& towards) {
  ClassifiedPoint p = Pt(towards.x(), towards.y(), towards.z(), TravClass::kUnknown);
  p.no_return = true;
  return p;
}

TEST(Fusion, NoReturnRaysClearWeakVoxelsAndStopBeforeASurfaceTheMapIsSureOf) {
  MapOptions options = OctoMapCarving();  // hit 0.847, miss -0.405; stop at P 0.95 = 2.944
  TraversabilityMap map(options);
  const float hit = octomap::logodds(options.occupancy_hit_prob);
  const float miss = octomap::logodds(options.occupancy_miss_prob);
  // Seen from the side, so that no ray of theirs runs along the x axis: a phantom at kA hit
  // once, a wall at kB hit four times, and a weak voxel behind the wall, hit once.
  const Eigen::Vector3d side(4.05, 3.05, 0.05), behind(6.05, 0.05, 0.05);
  map.InsertFrame(At(kA, TravClass::kNonTraversable), {2.05, 3.05, 0.05}, 1);
  for (int i = 0; i < 4; ++i) map.InsertFrame(At(kB, TravClass::kNonTraversable), side, 2 + i);
  map.InsertFrame(At(behind, TravClass::kNonTraversable), {6.05, 3.05, 0.05}, 6);
  ASSERT_FLOAT_EQ(NodeAt(map, kA)->getLogOdds(), hit);
  ASSERT_FLOAT_EQ(NodeAt(map, kB)->getLogOdds(), 4 * hit);

  const InsertStats stats = map.InsertFrame({NoReturn({1.05, 0.05, 0.05})}, kOrigin, 7);
  EXPECT_EQ(stats.rays_without_return, 1u);
  EXPECT_EQ(stats.voxels_hit, 0u);
  // Of the 40 voxels up to the wall the map holds one, the phantom: it takes a miss, and the
  // space it never observed stays unobserved.
  EXPECT_EQ(stats.voxels_freed, 1u);
  EXPECT_FLOAT_EQ(NodeAt(map, kA)->getLogOdds(), hit + miss);
  EXPECT_FALSE(map.CellAt({1.05, 0.05, 0.05}).observed);
  EXPECT_FALSE(map.CellAt({3.95, 0.05, 0.05}).observed);
  // The wall and what lies behind it keep their evidence.
  EXPECT_FLOAT_EQ(NodeAt(map, kB)->getLogOdds(), 4 * hit);
  EXPECT_FLOAT_EQ(NodeAt(map, behind)->getLogOdds(), hit);
  EXPECT_EQ(map.CellAt(kB).cls, TravClass::kNonTraversable);

  // Two more such frames and the phantom is free space.
  map.InsertFrame({NoReturn({1.05, 0.05, 0.05})}, kOrigin, 8);
  map.InsertFrame({NoReturn({1.05, 0.05, 0.05})}, kOrigin, 9);
  EXPECT_FALSE(map.CellAt(kA).occupied);
  EXPECT_TRUE(map.CellAt(kA).observed);

  // Without a wall the ray runs to the range and no farther: of two phantoms on it, at 14.1 m
  // and at 15.6 m, it clears the first only.
  TraversabilityMap open(options);
  const Eigen::Vector3d near(10.05, 10.05, 0.05), far(11.05, 11.05, 0.05);
  open.InsertFrame(At(near, TravClass::kNonTraversable), {10.05, 10.05, 3.05}, 1);  // seen from above
  open.InsertFrame(At(far, TravClass::kNonTraversable), {11.05, 11.05, 3.05}, 2);
  const InsertStats open_stats = open.InsertFrame({NoReturn({1.05, 1.05, 0.05})}, kOrigin, 3);
  EXPECT_EQ(open_stats.voxels_freed, 1u);
  EXPECT_FLOAT_EQ(NodeAt(open, near)->getLogOdds(), hit + miss);
  EXPECT_FLOAT_EQ(NodeAt(open, far)->getLogOdds(), hit);
}

TEST(Fusion, NoReturnRaysStopExactlyWhereALookupOfEachVoxelWould) {
  // A tree of sure and weak voxels (1 to 6 hits each, seen from above all around), then one
  // frame of open rays in every direction: each must free exactly the voxels the tree held on
  // OctoMap's walk up to (not including) the first one that held P >= 0.95 before the frame, as
  // a search of the tree voxel by voxel finds them.
  MapOptions options = OctoMapCarving();
  options.max_range_m = 8.0;
  TraversabilityMap map(options);
  const internal::TravOcTree& tree = testing::Tree(map);
  const Eigen::Vector3d origin(0.37, -0.21, 0.53);
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> coord(-2.5, 2.5);
  std::uniform_int_distribution<int> hits(1, 6);
  for (int i = 0; i < 3000; ++i) {
    const Eigen::Vector3d p(origin.x() + coord(rng), origin.y() + coord(rng), origin.z() + coord(rng) / 3.0);
    const Eigen::Vector3d from(origin.x() + 7.0 * std::cos(i * 0.7), origin.y() + 7.0 * std::sin(i * 0.7), 6.0);
    const int n = hits(rng);
    for (int k = 0; k < n; ++k) map.InsertFrame(At(p, TravClass::kNonTraversable), from, i);
  }
  const float stop = octomap::logodds(options.free_space_no_return_stop_prob);
  const float miss = octomap::logodds(options.occupancy_miss_prob);
  const float clamp_min = tree.getClampingThresMinLog();
  auto before = [&](const octomap::OcTreeKey& k) {
    const internal::TravNode* node = tree.search(k);
    return node == nullptr ? std::numeric_limits<float>::quiet_NaN() : node->getLogOdds();
  };
  std::vector<ClassifiedPoint> rays;
  std::unordered_map<octomap::OcTreeKey, float, KeyHash> expected;  // freed voxel -> log-odds after
  std::unordered_set<octomap::OcTreeKey, KeyHash> stops;
  const octomap::point3d o(static_cast<float>(origin.x()), static_cast<float>(origin.y()),
                           static_cast<float>(origin.z()));
  std::normal_distribution<double> gauss;
  octomap::KeyRay ray;
  for (int r = 0; r < 400; ++r) {
    const Eigen::Vector3d d = Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized();
    rays.push_back(NoReturn(origin + d));
    const Eigen::Vector3d end = origin + d * options.max_range_m;
    const octomap::point3d e(static_cast<float>(end.x()), static_cast<float>(end.y()), static_cast<float>(end.z()));
    ASSERT_TRUE(tree.computeRayKeys(o, e, ray));
    for (const octomap::OcTreeKey& k : ray) {
      const float l = before(k);
      if (l >= stop) {
        stops.insert(k);
        break;
      }
      if (!std::isnan(l)) expected[k] = std::max(clamp_min, l + miss);
    }
  }
  ASSERT_GT(stops.size(), 20u);  // the rays met sure voxels as well as weak ones
  std::unordered_map<octomap::OcTreeKey, float, KeyHash> stop_before;
  for (const auto& k : stops) stop_before[k] = before(k);
  const InsertStats stats = map.InsertFrame(rays, origin, 9999);
  EXPECT_EQ(stats.voxels_freed, expected.size());
  for (const auto& [k, l] : expected) {
    const internal::TravNode* node = tree.search(k);
    ASSERT_NE(node, nullptr);
    ASSERT_FLOAT_EQ(node->getLogOdds(), l);
  }
  for (const auto& [k, l] : stop_before) EXPECT_FLOAT_EQ(tree.search(k)->getLogOdds(), l);
  EXPECT_GT(stats.voxels_freed, 1000u);
}


/// The full-resolution voxels of the tree's leaves, split by occupancy log-odds sign.
void LeafVoxels(const internal::TravOcTree& tree, std::unordered_set<octomap::OcTreeKey, KeyHash>* free,
                std::unordered_set<octomap::OcTreeKey, KeyHash>* occupied) {
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    internal::ForEachVoxelOfLeaf(it.getIndexKey(), tree.getTreeDepth(), it.getDepth(), [&](const octomap::OcTreeKey& key) {
      (it->getLogOdds() < 0.0f ? free : occupied)->insert(key);
    });
  }
}

TEST(Fusion, CoarseRaysCastOneRayPerCellToTheMeanOfItsEnds) {
  // Closed form by OctoMap's own walk: with free_space_ray_cell 2 the free voxels are the
  // computeRayKeys voxels of one ray per 2x2x2 cell of ray ends, to the mean of its ends.
  MapOptions options = OctoMapCarving();
  options.free_space_ray_cell = 2;
  TraversabilityMap map(options);
  const internal::TravOcTree& tree = testing::Tree(map);
  const Eigen::Vector3d origin(0.37, -1.21, 1.53);
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> xy(-8.0, 8.0), z(-1.0, 0.5);
  std::vector<ClassifiedPoint> points;
  std::unordered_set<octomap::OcTreeKey, KeyHash> used;
  while (points.size() < 2000) {
    const ClassifiedPoint p = Pt(origin.x() + xy(rng), origin.y() + xy(rng), origin.z() + z(rng), TravClass::kTraversable);
    if (used.insert(tree.coordToKey(p.world_p.x(), p.world_p.y(), p.world_p.z())).second) points.push_back(p);
  }
  const InsertStats stats = map.InsertFrame(points, origin, 1);
  ASSERT_EQ(stats.points_beyond_range, 0u);  // all within 15 m: one ray per point, in order

  std::vector<octomap::OcTreeKey> cells;  // in order of first end, as the sums are
  std::vector<std::pair<Eigen::Vector3d, int>> sums;
  std::unordered_set<octomap::OcTreeKey, KeyHash> hit, free;
  for (const ClassifiedPoint& p : points) {
    const octomap::OcTreeKey k = tree.coordToKey(p.world_p.x(), p.world_p.y(), p.world_p.z());
    hit.insert(k);
    const octomap::OcTreeKey cell(static_cast<octomap::key_type>(k[0] / 2), static_cast<octomap::key_type>(k[1] / 2),
                                  static_cast<octomap::key_type>(k[2] / 2));
    const auto found = std::find(cells.begin(), cells.end(), cell);
    if (found == cells.end()) {
      cells.push_back(cell);
      sums.emplace_back(p.world_p.cast<double>(), 1);
    } else {
      auto& s = sums[static_cast<std::size_t>(found - cells.begin())];
      s.first += p.world_p.cast<double>();
      ++s.second;
    }
  }
  ASSERT_LT(sums.size(), points.size());  // some cells do hold several ends
  const octomap::point3d o(static_cast<float>(origin.x()), static_cast<float>(origin.y()), static_cast<float>(origin.z()));
  octomap::KeyRay ray;
  for (const auto& [sum, n] : sums) {
    const Eigen::Vector3d mean = sum / n;
    ASSERT_TRUE(tree.computeRayKeys(o, octomap::point3d(static_cast<float>(mean.x()), static_cast<float>(mean.y()),
                                                        static_cast<float>(mean.z())), ray));
    free.insert(ray.begin(), ray.end());
  }
  for (const auto& k : hit) free.erase(k);
  std::unordered_set<octomap::OcTreeKey, KeyHash> map_free, map_hit;
  LeafVoxels(tree, &map_free, &map_hit);
  EXPECT_EQ(map_hit, hit);
  EXPECT_EQ(map_free, free);
  EXPECT_EQ(stats.voxels_freed, free.size());
}

TEST(Fusion, CoarseRaysKeepTheOccupiedVoxelsAndFreeOnlyNearTheExactRays) {
  // The floor-and-box world seen from four sides: the same voxels end occupied with exact and
  // with coarse rays, and each voxel a coarse ray frees lies within `cell` voxels (Chebyshev)
  // of a voxel the exact rays free or hit (the mean ray runs inside the cone of the cell's rays).
  const std::vector<Eigen::Vector3d> origins = {{1.5, 1.25, 3.0}, {-2.0, 1.2, 1.5}, {4.9, 0.3, 1.2}, {1.4, 4.6, 2.2}};
  for (const int cell : {2, 4}) {
    MapOptions coarse_options = OctoMapCarving();
    coarse_options.free_space_ray_cell = cell;
    TraversabilityMap exact, coarse(coarse_options);
    for (std::size_t f = 0; f < origins.size(); ++f) {
      exact.InsertFrame(testing::FloorAndBox(), origins[f], static_cast<std::int64_t>(f));
      coarse.InsertFrame(testing::FloorAndBox(), origins[f], static_cast<std::int64_t>(f));
    }
    std::unordered_set<octomap::OcTreeKey, KeyHash> exact_free, exact_occupied, coarse_free, coarse_occupied;
    LeafVoxels(testing::Tree(exact), &exact_free, &exact_occupied);
    LeafVoxels(testing::Tree(coarse), &coarse_free, &coarse_occupied);
    EXPECT_EQ(coarse_occupied, exact_occupied) << "cell " << cell;
    ASSERT_GT(coarse_free.size(), 0u);
    for (const auto& k : coarse_free) {
      bool near = false;
      for (int dx = -cell; dx <= cell && !near; ++dx) {
        for (int dy = -cell; dy <= cell && !near; ++dy) {
          for (int dz = -cell; dz <= cell && !near; ++dz) {
            const octomap::OcTreeKey n(static_cast<octomap::key_type>(k[0] + dx), static_cast<octomap::key_type>(k[1] + dy),
                                       static_cast<octomap::key_type>(k[2] + dz));
            near = exact_free.count(n) > 0 || exact_occupied.count(n) > 0;
          }
        }
      }
      ASSERT_TRUE(near) << "cell " << cell << ": voxel " << k[0] << " " << k[1] << " " << k[2];
    }
    // Fewer rays, fewer voxels walked, but the carved volume stays comparable.
    EXPECT_GT(coarse_free.size(), exact_free.size() / 2) << "cell " << cell;
  }
}

}  // namespace
}  // namespace ssta
