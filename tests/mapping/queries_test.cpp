#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "map_test_util.h"
#include "ssta/mapping/column_explanation.h"
#include "ssta/mapping/confidence_bar.h"
#include "ssta/mapping/map_export.h"

namespace ssta {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

using testing::OctoMapCarving;

using testing::FloorAndBoxMap;

constexpr double kPi = 3.14159265358979323846;

class FloorAndBoxQueries : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { map_ = new TraversabilityMap(FloorAndBoxMap()); }
  static void TearDownTestSuite() {
    delete map_;
    map_ = nullptr;
  }
  static const TraversabilityMap& map() { return *map_; }
  /// Probability after one observation: softmax(0.85, -0.4, -0.4).
  static double OneViewProbability() {
    return std::exp(0.85) / (std::exp(0.85) + 2.0 * std::exp(-0.4));
  }
  /// A traversable column's cost after one observation: 0.25 min(1, 1.5 (1 - confidence)).
  static double OneViewFloorCost() { return 0.25 * std::min(1.0, 1.5 * (1.0 - OneViewProbability())); }

 private:
  static TraversabilityMap* map_;
};
TraversabilityMap* FloorAndBoxQueries::map_ = nullptr;

TEST_F(FloorAndBoxQueries, TopSurfaceOverTheBoxIsTheBoxTop) {
  const CellInfo top = map().TopSurfaceAt(1.15, 1.12);
  ASSERT_TRUE(top.observed);
  EXPECT_EQ(top.cls, TravClass::kNonTraversable);
  EXPECT_EQ(top.cost, 1.0);
  EXPECT_NEAR(top.center.x(), 1.15, 1e-9);
  EXPECT_NEAR(top.center.y(), 1.15, 1e-9);
  EXPECT_NEAR(top.center.z(), 0.25, 1e-9);  // voxel [0.2, 0.3): the top of the 0.3 m box
  EXPECT_NEAR(top.frame_mean_slope_deg, 80.0, 1e-4);
  EXPECT_NEAR(top.probability, OneViewProbability(), 1e-6);
}

TEST_F(FloorAndBoxQueries, TopSurfaceOnTheFloorIsTheFloor) {
  const CellInfo floor = map().TopSurfaceAt(0.55, 2.31);
  ASSERT_TRUE(floor.observed);
  EXPECT_EQ(floor.cls, TravClass::kTraversable);
  EXPECT_NEAR(floor.cost, OneViewFloorCost(), 1e-8);  // one view: not yet certain (float log-odds)
  EXPECT_NEAR(floor.center.z(), 0.05, 1e-9);
  EXPECT_NEAR(floor.center.y(), 2.35, 1e-9);
  EXPECT_NEAR(floor.probability, OneViewProbability(), 1e-6);
  EXPECT_EQ(floor.observations, 1u);
  EXPECT_EQ(floor.last_seen_ns, 1000);
}

TEST_F(FloorAndBoxQueries, UnobservedIsClassZeroWithNaNCost) {
  for (const CellInfo& cell : {map().TopSurfaceAt(50.0, 50.0), map().CellAt({50.0, 50.0, 0.05}),
                               map().TopSurfaceAt(-0.05, 1.0)}) {
    EXPECT_FALSE(cell.observed);
    EXPECT_EQ(cell.cls, TravClass::kUnknown);
    EXPECT_TRUE(std::isnan(cell.cost));
    EXPECT_TRUE(std::isnan(cell.probability));
  }
  EXPECT_TRUE(std::isnan(map().TopSurfaceAt(50.0, 50.0).center.z()));
  // Far beyond the addressable cube (an int cast of the scaled coordinate would overflow):
  // unobserved, and a footprint there is an error.
  for (const double far : {1e12, -1e12, 1e300}) {
    EXPECT_FALSE(map().CellAt({far, 0.0, 0.0}).observed) << far;
    EXPECT_FALSE(map().TopSurfaceAt(0.0, far).observed) << far;
    EXPECT_THROW(map().QueryFootprint({far, 0.0, 0.0, 1.0, 1.0}), Error) << far;
  }
}

TEST_F(FloorAndBoxQueries, CellAtAnswersForEachVoxelOfTheBox) {
  for (int iz = 0; iz < 3; ++iz) {
    const CellInfo cell = map().CellAt({1.05, 1.25, 0.05 + 0.1 * iz});
    EXPECT_TRUE(cell.occupied);
    EXPECT_EQ(cell.cls, TravClass::kNonTraversable);
  }
  EXPECT_FALSE(map().CellAt({1.05, 1.25, 0.35}).occupied);
}

TEST_F(FloorAndBoxQueries, FootprintOverlappingTheBoxIsNonTraversable) {
  // x in [0.6, 1.2], y in [0.96, 1.34]: it touches 6 x 5 columns, 2 x 3 of them on the box.
  const FootprintResult r = map().QueryFootprint({0.9, 1.15, 0.0, 0.6, 0.38});
  EXPECT_EQ(r.cells, 30);
  EXPECT_EQ(r.observed_cells, 30);
  EXPECT_EQ(r.worst, TravClass::kNonTraversable);
  EXPECT_NEAR(r.mean_cost, (6.0 + 24.0 * OneViewFloorCost()) / 30.0, 1e-8);
  EXPECT_EQ(r.max_cost, 1.0);
  EXPECT_DOUBLE_EQ(r.fraction_observed, 1.0);
  // The same rectangle turned by 90 degrees (length along y now).
  const FootprintResult turned = map().QueryFootprint({0.9, 1.15, kPi / 2, 0.38, 0.6});
  EXPECT_EQ(turned.cells, 30);
  EXPECT_NEAR(turned.mean_cost, (6.0 + 24.0 * OneViewFloorCost()) / 30.0, 1e-8);
}

TEST_F(FloorAndBoxQueries, AFootprintThatOverlapsTheBoxByLessThanHalfAColumnIsBlocked) {
  // x in [0.6, 1.04]: the box's first column (x in [1.0, 1.1]) is under 4 cm of the footprint.
  const FootprintResult r = map().QueryFootprint({0.82, 1.15, 0.0, 0.44, 0.2});
  EXPECT_EQ(r.worst, TravClass::kNonTraversable);
  // Ending on the column's edge at x = 1.0, the footprint stands beside the box.
  const FootprintResult beside = map().QueryFootprint({0.8, 1.15, 0.0, 0.4, 0.2});
  EXPECT_EQ(beside.worst, TravClass::kTraversable);
  // Turned by 30 degrees with its corner reaching into the box's column.
  const FootprintResult corner = map().QueryFootprint({0.88, 0.87, kPi / 6, 0.44, 0.2});
  EXPECT_EQ(corner.worst, TravClass::kNonTraversable);
}

TEST_F(FloorAndBoxQueries, FootprintOnTheFloorAndOverTheEdge) {
  const FootprintResult floor = map().QueryFootprint({0.5, 0.5, 0.3, 0.5, 0.4});
  EXPECT_EQ(floor.worst, TravClass::kTraversable);
  EXPECT_NEAR(floor.mean_cost, OneViewFloorCost(), 1e-8);
  // Each floor column was seen once: the footprint is as sure of driving there as one view is.
  EXPECT_NEAR(floor.drivable_confidence, OneViewProbability(), 1e-6);
  // x in [2.7, 3.1]: centres 2.75 .. 3.05, the last off the floor; y centres 0.45, 0.55.
  const FootprintResult edge = map().QueryFootprint({2.9, 0.5, 0.0, 0.4, 0.18});
  EXPECT_EQ(edge.cells, 8);
  EXPECT_EQ(edge.observed_cells, 6);
  EXPECT_DOUBLE_EQ(edge.fraction_observed, 0.75);
  // Smaller than a voxel: the column under the centre.
  const FootprintResult tiny = map().QueryFootprint({1.12, 1.12, 0.0, 0.01, 0.01});
  EXPECT_EQ(tiny.cells, 1);
  EXPECT_EQ(tiny.worst, TravClass::kNonTraversable);
  EXPECT_TRUE(std::isnan(tiny.drivable_confidence));  // no drivable cell under it
}

TEST_F(FloorAndBoxQueries, AConfidenceBarLeavesOnlyTheDrivableAnswersThatSure) {
  const double once = OneViewProbability();  // every floor column's confidence
  const FootprintQuery on_floor{0.5, 0.5, 0.3, 0.5, 0.4};
  // Under the bar's floor (0), at it and just below the floor's confidence: the answer as it is.
  for (const double bar : {0.0, once - 1e-6}) {
    const FootprintResult r = map().QueryFootprint(on_floor, WithConfidenceBar(map(), {}, bar));
    EXPECT_EQ(r.worst, TravClass::kTraversable) << bar;
    EXPECT_NEAR(r.drivable_confidence, once, 1e-6) << bar;
    EXPECT_NEAR(r.mean_cost, OneViewFloorCost(), 1e-8) << bar;
  }
  // Above it, every floor column is undecided: no cost, no drivable confidence, as
  // `eval footprints --min-confidence` counts a footprint whose drivable_confidence is below.
  const FootprintResult unsure = map().QueryFootprint(on_floor, WithConfidenceBar(map(), {}, once + 1e-6));
  EXPECT_EQ(unsure.worst, TravClass::kUndecided);
  EXPECT_TRUE(std::isnan(unsure.mean_cost));
  EXPECT_TRUE(std::isnan(unsure.drivable_confidence));
  EXPECT_EQ(unsure.observed_cells, unsure.cells);
  // An obstacle stays an obstacle at any bar, and a path still stops where it did.
  EXPECT_EQ(map().QueryFootprint({1.12, 1.12, 0.0, 0.01, 0.01}, WithConfidenceBar(map(), {}, 1.0)).worst,
            TravClass::kNonTraversable);
  const std::vector<Eigen::Vector2d> line{{0.2, 1.15}, {2.0, 1.15}};
  const PathResult plain = map().QueryPath(line, 0.2);
  const PathResult barred = map().QueryPath(line, 0.2, WithConfidenceBar(map(), {}, 0.9));
  EXPECT_NEAR(plain.samples.front().drivable_confidence, once, 1e-6);
  EXPECT_EQ(barred.samples.front().cls, TravClass::kUndecided);
  EXPECT_TRUE(std::isnan(barred.samples.front().drivable_confidence));
  EXPECT_TRUE(barred.blocked);
  EXPECT_NEAR(barred.first_non_traversable_distance_m, plain.first_non_traversable_distance_m, 1e-12);
  // The bar reads through another source: here one that answers every column as the floor
  // beside it with no confidence (an export step's class), which no bar turns undecided.
  const TraversabilityMap::SurfaceSource no_say = [&](double, double) {
    CellInfo c = map().TopSurfaceAt(0.5, 0.5);
    c.confidence = std::numeric_limits<double>::quiet_NaN();
    return c;
  };
  EXPECT_EQ(map().QueryFootprint(on_floor, WithConfidenceBar(map(), no_say, 1.0)).worst, TravClass::kTraversable);
  EXPECT_THROW(WithConfidenceBar(map(), {}, 1.5), Error);
  EXPECT_THROW(AtConfidenceBar(map().TopSurfaceAt(0.5, 0.5), -0.1), Error);
  // One cell through the bar: undecided, still observed, with no judge.
  const CellInfo voxel = AtConfidenceBar(map().TopSurfaceAt(0.5, 0.5), 0.99);
  EXPECT_EQ(voxel.cls, TravClass::kUndecided);
  EXPECT_EQ(voxel.decided_by, ClassJudge::kNone);
  EXPECT_TRUE(voxel.observed);
}

TEST_F(FloorAndBoxQueries, PathThroughTheBoxReportsTheFirstNonTraversablePoint) {
  const PathResult r = map().QueryPath({{0.2, 1.15}, {2.0, 1.15}}, 0.0);
  EXPECT_EQ(r.samples.size(), 37u);  // every 0.05 m over 1.8 m, both ends
  EXPECT_NEAR(r.length_m, 1.8, 1e-12);
  EXPECT_TRUE(r.blocked);
  EXPECT_EQ(r.worst, TravClass::kNonTraversable);
  // The box starts at x = 1.0; the first sample inside it is x = 1.0 (or 1.05 by rounding).
  EXPECT_GE(r.first_non_traversable.x(), 1.0 - 1e-9);
  EXPECT_LE(r.first_non_traversable.x(), 1.05 + 1e-9);
  EXPECT_NEAR(r.first_non_traversable.y(), 1.15, 1e-12);
  EXPECT_NEAR(r.first_non_traversable_distance_m, r.first_non_traversable.x() - 0.2, 1e-9);
  EXPECT_DOUBLE_EQ(r.fraction_observed, 1.0);
  // 6 of the 37 samples on the box (x = 1.0 .. 1.25, cost 1), the rest on once-seen floor.
  EXPECT_NEAR(r.mean_cost, (6.0 + 31.0 * OneViewFloorCost()) / 37.0, 1e-8);
  EXPECT_EQ(r.samples.front().cls, TravClass::kTraversable);
}

TEST_F(FloorAndBoxQueries, PathWidthDecidesWhetherTheBoxIsTouched) {
  // Centre line y = 0.75; the box starts at y = 1.0.
  const PathResult narrow = map().QueryPath({{0.2, 0.75}, {2.0, 0.75}}, 0.4);
  EXPECT_FALSE(narrow.blocked);
  EXPECT_EQ(narrow.worst, TravClass::kTraversable);
  EXPECT_TRUE(std::isnan(narrow.first_non_traversable.x()));
  const PathResult wide = map().QueryPath({{0.2, 0.75}, {2.0, 0.75}}, 0.8);
  EXPECT_TRUE(wide.blocked);
  EXPECT_NEAR(wide.first_non_traversable.y(), 0.75, 1e-12);
  EXPECT_EQ(wide.samples[wide.samples.size() / 2].cell.cls, TravClass::kNonTraversable);
  // A path in the unknown.
  const PathResult unknown = map().QueryPath({{40.0, 40.0}, {41.0, 40.0}}, 0.3);
  EXPECT_EQ(unknown.worst, TravClass::kUnknown);
  EXPECT_DOUBLE_EQ(unknown.fraction_observed, 0.0);
  EXPECT_TRUE(std::isnan(unknown.mean_cost));
  EXPECT_THROW(map().QueryPath({}, 0.1), Error);
}

TEST_F(FloorAndBoxQueries, APathChecksTheOutsideOfItsTurns) {
  // East along y = 0.85, then south from (0.85, 0.85), 0.5 m wide: the lateral line turning at
  // the vertex sweeps the quarter disc towards the box's corner column [1.0, 1.1)^2, which
  // the straight legs miss (the eastern leg ends at x = 0.85, the southern leg's line stays at
  // y = 0.85 and below).
  const std::vector<Eigen::Vector2d> turn{{0.2, 0.85}, {0.85, 0.85}, {0.85, 0.2}};
  const PathResult r = map().QueryPath(turn, 0.5);
  EXPECT_TRUE(r.blocked);
  EXPECT_NEAR(r.first_non_traversable_distance_m, 0.65, 1e-9);  // at the vertex
  EXPECT_NEAR(r.length_m, 1.3, 1e-12);
  // 0.2 m wide: the swept quarter disc (radius 0.1 m) stays on the floor.
  EXPECT_FALSE(map().QueryPath(turn, 0.2).blocked);
  // One point with a width: the disc around it (radius 0.25 m reaches (1.03, 1.03)).
  const PathResult point = map().QueryPath({{0.85, 0.85}}, 0.5);
  EXPECT_TRUE(point.blocked);
  EXPECT_FALSE(map().QueryPath({{0.85, 0.85}}, 0.3).blocked);  // radius 0.15: short of the box
  EXPECT_EQ(map().QueryPath({{0.85, 0.85}}, 0.0).samples.size(), 1u);
}

TEST_F(FloorAndBoxQueries, AProjectionCoarserThanTheMapTakesEachPixelsWorstColumn) {
  // One 0.3 m pixel over [0.8, 1.1)^2: its centre (0.95, 0.95) is floor, its corner column
  // (1.05, 1.05) the box. A planner reading the pixel must see the box.
  const GridProjection coarse =
      map().Project(Eigen::AlignedBox2d(Eigen::Vector2d(0.8, 0.8), Eigen::Vector2d(1.1, 1.1)), 0.3);
  ASSERT_EQ(coarse.classes.size(), 1u);
  EXPECT_EQ(coarse.classes(0, 0), 3);
  EXPECT_NEAR(coarse.height_m(0, 0), 0.25, 1e-6);
  EXPECT_EQ(coarse.cost(0, 0), 1.0f);
  // All floor: the pixel is floor.
  const GridProjection floor =
      map().Project(Eigen::AlignedBox2d(Eigen::Vector2d(0.2, 0.2), Eigen::Vector2d(0.5, 0.5)), 0.3);
  EXPECT_EQ(floor.classes(0, 0), 1);
}

TEST_F(FloorAndBoxQueries, QueriesTooLargeToAnswerAreErrorsNotWrongAnswers) {
  // Beyond the addressable cube (+-3276.8 m at 0.1 m) a rectangle has no columns to read: it
  // was answered by its centre column alone. Inside it, 10^7 columns is the cap.
  auto message = [](const std::function<void()>& query) -> std::string {
    try {
      query();
    } catch (const Error& e) {
      return e.what();
    }
    return "no error";
  };
  EXPECT_NE(message([&] { map().QueryFootprint({1.0, 1.0, 0.0, 7000.0, 7000.0}); }).find("addressable area"),
            std::string::npos);
  EXPECT_NE(message([&] { map().QueryFootprint({1.0, 1.0, 0.0, 400.0, 400.0}); }).find("10^7 map columns"),
            std::string::npos);
  EXPECT_NE(message([&] { map().QueryPath({{0.0, 0.0}, {1e6, 0.0}}, 0.0); }).find("10^7 samples"), std::string::npos);
  // 60 km of centre line: 1.2 * 10^6 samples to return (~300 MB): refused.
  EXPECT_NE(message([&] { map().QueryPath({{0.0, 0.0}, {6e4, 0.0}}, 0.0); }).find("10^6 samples"), std::string::npos);
  // Just under the caps: answered (unobserved beyond the floor).
  EXPECT_EQ(map().QueryFootprint({1.0, 1.0, 0.0, 300.0, 300.0}).cells, 3000 * 3000);
}

TEST_F(FloorAndBoxQueries, ProjectionPutsTheLargestYInRowZero) {
  const GridProjection grid = map().Project(Eigen::AlignedBox2d(Eigen::Vector2d(0, 0), Eigen::Vector2d(3.0, 2.5)), 0.1);
  ASSERT_EQ(grid.width(), 30);
  ASSERT_EQ(grid.height(), 25);
  // Column (1.15, 1.15): u = 11, v = 25 - 1 - 11 = 13.
  EXPECT_EQ(grid.classes(13, 11), 3);
  EXPECT_NEAR(grid.height_m(13, 11), 0.25, 1e-6);
  EXPECT_EQ(grid.cost(13, 11), 1.0f);
  EXPECT_EQ(grid.classes(0, 0), 1);
  EXPECT_NEAR(grid.PixelCenter(0, 0).y(), 2.45, 1e-12);
  EXPECT_NEAR(grid.height_m(0, 0), 0.05, 1e-6);
  int box = 0;
  for (std::size_t i = 0; i < grid.classes.size(); ++i) box += grid.classes[i] == 3;
  EXPECT_EQ(box, 9);
}

TEST_F(FloorAndBoxQueries, SurfaceCellsAndBounds) {
  EXPECT_EQ(map().SurfaceCells().size(), 30u * 25u - 9u + 27u);
  const Eigen::AlignedBox3d b = map().SurfaceBounds();
  EXPECT_NEAR(b.min().x(), 0.0, 1e-9);
  EXPECT_NEAR(b.max().x(), 3.0, 1e-9);
  EXPECT_NEAR(b.max().y(), 2.5, 1e-9);
  EXPECT_NEAR(b.max().z(), 0.3, 1e-9);
}

TEST_F(FloorAndBoxQueries, ConcurrentReadersGetTheSameAnswers) {
  auto run_queries = [&]() {
    std::vector<std::string> answers;
    for (double x = -0.5; x < 3.5; x += 0.07) {
      for (double y = -0.5; y < 3.0; y += 0.09) {
        answers.push_back(QueryCsvRow(map().TopSurfaceAt(x, y)));
        answers.push_back(QueryCsvRow(map().CellAt({x, y, 0.15})));
      }
      const FootprintResult f = map().QueryFootprint({x, 1.1, x, 0.7, 0.5});
      answers.push_back(std::to_string(f.cells) + " " + std::to_string(f.mean_cost));
    }
    const PathResult p = map().QueryPath({{0.0, 0.0}, {3.0, 2.5}, {0.0, 2.5}}, 0.6);
    answers.push_back(std::to_string(p.mean_cost) + " " + std::to_string(p.first_non_traversable_distance_m));
    return answers;
  };
  const std::vector<std::string> single = run_queries();
  ASSERT_GT(single.size(), 3000u);
  std::vector<std::vector<std::string>> results(4);
  std::vector<std::thread> threads;
  for (auto& r : results) threads.emplace_back([&r, &run_queries] { r = run_queries(); });
  for (auto& t : threads) t.join();
  for (const auto& r : results) EXPECT_EQ(r, single);
}

TEST(TraversabilityMapCost, SemiTraversableCostGrowsThroughTheBand) {
  const TraversabilityMap map(OctoMapCarving());  // vehicle defaults: slope 15..25 deg, step 0.10..0.20 m
  EXPECT_EQ(map.Cost(TravClass::kTraversable, 30.0, 1.0), 0.0);
  EXPECT_EQ(map.Cost(TravClass::kNonTraversable, 0.0, 0.0), 1.0);
  EXPECT_DOUBLE_EQ(map.Cost(TravClass::kSemiTraversable, 10.0, 0.05), 0.25);
  EXPECT_DOUBLE_EQ(map.Cost(TravClass::kSemiTraversable, 20.0, 0.05), 0.5);
  EXPECT_NEAR(map.Cost(TravClass::kSemiTraversable, 10.0, -0.15), 0.5, 1e-12);
  EXPECT_DOUBLE_EQ(map.Cost(TravClass::kSemiTraversable, 40.0, 0.0), 0.75);
  EXPECT_TRUE(std::isnan(map.Cost(TravClass::kUnknown, 0.0, 0.0)));
  EXPECT_TRUE(std::isnan(map.Cost(TravClass::kUndecided, 0.0, 0.0)));
}

/// A plane rising along x at `ramp_deg` over x, y in [0, 4) m, one point per 0.1 m column at its
/// centre's height, seen `frames` times with height sigma 1 cm; every point is classed `cls` and
/// carries the per-point slope and step given: what the frames' means will be.
TraversabilityMap Ramp(double ramp_deg, TravClass cls, float point_slope_deg, float point_step_m, int frames = 1) {
  std::vector<ClassifiedPoint> points;
  for (int ix = 0; ix < 40; ++ix) {
    for (int iy = 0; iy < 40; ++iy) {
      ClassifiedPoint p = testing::Pt(testing::C(ix), testing::C(iy), std::tan(ramp_deg * kPi / 180.0) * testing::C(ix),
                                      cls, point_slope_deg, point_step_m);
      p.height_sigma_m = 0.01f;
      p.horizontal_sigma_m = 0.01f;
      points.push_back(p);
    }
  }
  MapOptions options;
  options.max_range_m = 30.0;
  options.occupied_threshold_prob = 0.5;  // one frame's hit makes a voxel occupied
  TraversabilityMap map(options);
  for (int k = 0; k < frames; ++k) map.InsertFrame(points, {2.0, 2.0, 15.0}, k);
  return map;
}

/// The slope and step of `cell` lie in its class's band of the map's vehicle (docs/interfaces.md,
/// section 3): the row tells the same story as its class.
void ExpectSlopeAndStepAgreeWithClass(const CellInfo& cell, const VehicleOptions& v) {
  const double slope = cell.slope_deg, step = std::abs(cell.step_m);
  ASSERT_TRUE(std::isfinite(slope) && std::isfinite(step));
  switch (cell.cls) {
    case TravClass::kTraversable:
      EXPECT_LE(slope, v.semi_slope_deg);
      EXPECT_LE(step, v.semi_step_m);
      break;
    case TravClass::kSemiTraversable:
      EXPECT_LE(slope, v.max_slope_deg);
      EXPECT_LE(step, v.max_step_m);
      EXPECT_TRUE(slope > v.semi_slope_deg || step > v.semi_step_m);
      break;
    case TravClass::kNonTraversable: EXPECT_TRUE(slope > v.max_slope_deg || step > v.max_step_m); break;
    default: ADD_FAILURE() << "class " << static_cast<int>(cell.cls);
  }
}

TEST(FootprintQuery, AColumnWithoutAVerdictMakesTheAnswerUndecidedUnlessAnObstacleBlocksIt) {
  // A floor at x in [0, 2): traversable except for one undecided column (x, y in [1.0, 1.1);
  // its point carries no class, as a frame that could not judge it sends) and, beside it, a
  // semi-traversable column at x in [1.1, 1.2) and a non-traversable one at x in [1.5, 1.6).
  std::vector<ClassifiedPoint> points;
  for (int ix = 0; ix < 20; ++ix) {
    for (int iy = 0; iy < 20; ++iy) {
      TravClass cls = TravClass::kTraversable;
      if (iy == 10 && ix == 10) cls = TravClass::kUndecided;
      if (iy == 10 && ix == 11) cls = TravClass::kSemiTraversable;
      if (iy == 10 && ix == 15) cls = TravClass::kNonTraversable;
      points.push_back(testing::Pt(testing::C(ix), testing::C(iy), testing::C(0), cls));
    }
  }
  TraversabilityMap map(testing::OctoMapCarving());
  map.InsertFrame(points, {1.0, 1.0, 3.0}, 1);
  ASSERT_EQ(map.TopSurfaceAt(1.05, 1.05).cls, TravClass::kUndecided);
  ASSERT_EQ(map.TopSurfaceAt(1.15, 1.05).cls, TravClass::kSemiTraversable);
  // Over open floor only: traversable. Over the undecided column: the map does not know what
  // stands there, so the footprint is not called traversable, nor semi-traversable beside the
  // semi column; every column counts as observed (the undecided one holds a surface).
  EXPECT_EQ(map.QueryFootprint({0.5, 0.5, 0.0, 0.4, 0.4}).worst, TravClass::kTraversable);
  const FootprintResult undecided = map.QueryFootprint({1.0, 1.05, 0.0, 0.4, 0.1});
  EXPECT_EQ(undecided.worst, TravClass::kUndecided);
  EXPECT_DOUBLE_EQ(undecided.fraction_observed, 1.0);
  EXPECT_EQ(map.QueryFootprint({1.1, 1.05, 0.0, 0.2, 0.1}).worst, TravClass::kUndecided);
  EXPECT_EQ(map.QueryFootprint({1.15, 1.05, 0.0, 0.1, 0.1}).worst, TravClass::kSemiTraversable);
  // The answer names the column of its worst class nearest the centre: the undecided one.
  EXPECT_NEAR(undecided.worst_x_m, 1.05, 1e-9);
  EXPECT_NEAR(undecided.worst_y_m, 1.05, 1e-9);
  // An obstacle under the footprint blocks it whatever else lies there, and is the one named.
  const FootprintResult blocked = map.QueryFootprint({1.3, 1.05, 0.0, 0.6, 0.1});
  EXPECT_EQ(blocked.worst, TravClass::kNonTraversable);
  EXPECT_NEAR(blocked.worst_x_m, 1.55, 1e-9);
  EXPECT_NEAR(blocked.worst_y_m, 1.05, 1e-9);
  // Over open floor the nearest traversable column is the one under the centre.
  const FootprintResult open = map.QueryFootprint({0.55, 0.55, 0.0, 0.4, 0.4});
  EXPECT_NEAR(open.worst_x_m, 0.55, 1e-9);
  EXPECT_NEAR(open.worst_y_m, 0.55, 1e-9);
  EXPECT_TRUE(std::isnan(map.QueryFootprint({-5.0, -5.0, 0.0, 0.4, 0.4}).worst_x_m));  // nothing observed
  // A path over the same row: the undecided sample is reported as such, the obstacle blocks.
  const PathResult path = map.QueryPath({{0.55, 1.05}, {1.45, 1.05}}, 0.0);
  EXPECT_FALSE(path.blocked);
  EXPECT_EQ(path.worst, TravClass::kUndecided);
  const PathResult through = map.QueryPath({{0.55, 1.05}, {1.85, 1.05}}, 0.0);
  EXPECT_TRUE(through.blocked);
  EXPECT_EQ(through.worst, TravClass::kNonTraversable);
}

TEST(ColumnVerdict, SlopeAndStepAreThoseThatDecidedTheClassAndTheFramesMeansAreKept) {
  const VehicleOptions vehicle;  // the maps' (MapMetadata's default)
  const double x = testing::C(20), y = testing::C(20);
  {
    // Level ground the frames call traversable, their points' slope and step noisy (35 deg,
    // 0.6 m): the surface, seen all round, agrees on traversable and its level plane decides.
    const TraversabilityMap map = Ramp(0.0, TravClass::kTraversable, 35.0f, 0.6f);
    const CellInfo cell = map.TopSurfaceAt(x, y);
    EXPECT_EQ(cell.cls, TravClass::kTraversable);
    EXPECT_EQ(cell.decided_by, ClassJudge::kBoth);
    EXPECT_NEAR(cell.slope_deg, 0.0, 0.5);
    EXPECT_NEAR(cell.step_m, 0.0, 0.02);
    ExpectSlopeAndStepAgreeWithClass(cell, vehicle);
    EXPECT_NEAR(cell.frame_mean_slope_deg, 35.0, 1e-4);
    EXPECT_NEAR(cell.frame_mean_step_m, 0.6, 1e-6);
  }
  {
    // A 30 deg ramp (steeper than max_slope_deg 25) the frames call traversable at 5 deg: the
    // surface makes it non-traversable, by its slope.
    const TraversabilityMap map = Ramp(30.0, TravClass::kTraversable, 5.0f, 0.01f);
    const CellInfo cell = map.TopSurfaceAt(x, y);
    EXPECT_EQ(cell.cls, TravClass::kNonTraversable);
    EXPECT_EQ(cell.decided_by, ClassJudge::kSurface);
    EXPECT_NEAR(cell.slope_deg, 30.0, 0.5);
    ExpectSlopeAndStepAgreeWithClass(cell, vehicle);
    EXPECT_EQ(cell.cost, 1.0);
    EXPECT_NEAR(cell.frame_mean_slope_deg, 5.0, 1e-4);
    EXPECT_NEAR(cell.frame_mean_step_m, 0.01, 1e-6);
  }
  {
    // A 20 deg ramp (semi-traversable to the surface) whose every point three frames call
    // non-traversable with a 0.5 m step (a lip the fused surface does not show): the worse of
    // the two verdicts is the frames'. Their votes decided, not a slope or step: those are NaN,
    // and the frames' means stay under their own names.
    const TraversabilityMap map = Ramp(20.0, TravClass::kNonTraversable, 20.0f, 0.5f, 3);
    const CellInfo cell = map.TopSurfaceAt(x, y);
    EXPECT_EQ(cell.cls, TravClass::kNonTraversable);
    EXPECT_EQ(cell.decided_by, ClassJudge::kFrames);
    EXPECT_TRUE(std::isnan(cell.slope_deg) && std::isnan(cell.step_m));
    EXPECT_EQ(cell.cost, 1.0);
    EXPECT_NEAR(cell.frame_mean_slope_deg, 20.0, 1e-4);
    EXPECT_NEAR(cell.frame_mean_step_m, 0.5, 1e-6);
    // A voxel's class is the frames' alone.
    const CellInfo voxel = map.CellAt(cell.center);
    EXPECT_EQ(voxel.decided_by, ClassJudge::kFrames);
    EXPECT_TRUE(std::isnan(voxel.slope_deg) && std::isnan(voxel.step_m));
    EXPECT_NEAR(voxel.frame_mean_step_m, 0.5, 1e-6);
    // Semi-traversable by the frames' votes: the middle of the band, 0.25 + 0.5 * 0.5; by a
    // slope at the band's top (max_slope_deg): 0.75.
    EXPECT_EQ(map.Cost(TravClass::kSemiTraversable, kNaN, kNaN), 0.5);
    EXPECT_NEAR(map.Cost(TravClass::kSemiTraversable, vehicle.max_slope_deg, 0.0), 0.75, 1e-12);
  }
  // An unobserved column: no judge, no values.
  const CellInfo none = Ramp(0.0, TravClass::kTraversable, 0.0f, 0.0f).TopSurfaceAt(50.0, 50.0);
  EXPECT_EQ(none.decided_by, ClassJudge::kNone);
  EXPECT_TRUE(std::isnan(none.slope_deg) && std::isnan(none.frame_mean_slope_deg));
}

}  // namespace
}  // namespace ssta

namespace ssta {
namespace {

TEST(ExplainColumn, GivesEachJudgesEvidenceAndTheRuleThatCombinedThem) {
  const double x = testing::C(20), y = testing::C(20);
  {
    // The 30 deg ramp the frames call traversable: the surface finds the slope (30 deg within its
    // sigma) and the worse of the two verdicts counts.
    const TraversabilityMap map = Ramp(30.0, TravClass::kTraversable, 5.0f, 0.01f);
    const ColumnExplanation why = map.ExplainColumn(x, y);
    EXPECT_EQ(why.cell.cls, TravClass::kNonTraversable);
    EXPECT_EQ(why.rule, JudgeRule::kWorseOfTwo);
    ASSERT_TRUE(why.surface.determined);
    EXPECT_NEAR(why.surface.slope_deg, 30.0, 0.5);
    EXPECT_GT(why.frame_log_odds[0], why.frame_log_odds[1]);  // the frames' vote: traversable
    EXPECT_GT(why.frame_log_odds[0], why.frame_log_odds[2]);
    EXPECT_GT(why.frame_probability[0], 0.5);
    // Worse of two: P(class <= k) is the product of the two judges'.
    const auto& f = why.frame_probability;
    const auto& s = why.surface.probability;
    EXPECT_NEAR(why.posterior[0], f[0] * s[0], 1e-9);
    EXPECT_NEAR(why.posterior[0] + why.posterior[1], (f[0] + f[1]) * (s[0] + s[1]), 1e-9);
    EXPECT_NEAR(why.cell.confidence, why.posterior[2], 1e-12);
    EXPECT_GE(why.occupancy, why.occupied_threshold);
    EXPECT_NEAR(why.occupancy, 1.0 / (1.0 + std::exp(-why.occupancy_log_odds)), 1e-6);
    EXPECT_TRUE(why.disc_fully_seen);
    EXPECT_GE(why.surface_columns, 9);  // a 0.2 m disc at 0.1 m columns: at least the 3 x 3
  }
  {
    // Level ground the frames call traversable, seen all round: the product rule, whose posterior
    // is the normalised product of the frames' probabilities and the surface's, these mixed with
    // class_surface_miss_prob e of a uniform one.
    const TraversabilityMap map = Ramp(0.0, TravClass::kTraversable, 2.0f, 0.01f);
    const double e = map.options().class_surface_miss_prob;
    EXPECT_EQ(e, 0.1);
    const ColumnExplanation why = map.ExplainColumn(x, y);
    EXPECT_EQ(why.rule, JudgeRule::kProduct);
    EXPECT_EQ(why.cell.cls, TravClass::kTraversable);
    const auto& f = why.frame_probability;
    std::array<double, 3> s = why.surface.probability;
    for (double& p : s) p = (1.0 - e) * p + e / 3.0;
    const double total = f[0] * s[0] + f[1] * s[1] + f[2] * s[2];
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(why.posterior[k], f[k] * s[k] / total, 1e-9) << k;
    // At the map's corner the disc reaches unseen columns: the surface cannot vouch, the frames
    // decide.
    const ColumnExplanation corner = map.ExplainColumn(testing::C(0), testing::C(0));
    EXPECT_FALSE(corner.disc_fully_seen);
    EXPECT_TRUE(corner.rule == JudgeRule::kFramesSurfacePartial || corner.rule == JudgeRule::kFramesAlone)
        << JudgeRuleName(corner.rule);
    EXPECT_EQ(corner.cell.decided_by, ClassJudge::kFrames);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(corner.posterior[k], corner.frame_probability[k], 1e-12);
  }
  // Nothing observed: no rule, no class.
  const ColumnExplanation none = Ramp(0.0, TravClass::kTraversable, 0.0f, 0.0f).ExplainColumn(50.0, 50.0);
  EXPECT_FALSE(none.cell.observed);
  EXPECT_EQ(none.rule, JudgeRule::kNone);
  EXPECT_TRUE(std::isnan(none.posterior[0]) && std::isnan(none.occupancy));
}

}  // namespace
}  // namespace ssta
