// DiffMaps: the change categories on hand-built projections and maps, the files it writes, and
// the maps it refuses to compare.

#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "map_test_util.h"
#include "ssta/core/error.h"
#include "ssta/files/file_util.h"
#include "ssta/mapping/map_diff.h"
#include "ssta/pictures/map_diff_picture.h"
#include "temp_dir.h"

namespace ssta {
namespace {

using testing::C;
using testing::OctoMapCarving;
using testing::Pt;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

CellChange Change(int a, double conf_a, int b, double conf_b, double slope_a = 5.0, double slope_b = 5.0,
                  double step_a = 0.02, double step_b = 0.02) {
  return ClassifyChange(static_cast<std::uint8_t>(a), conf_a, slope_a, step_a, static_cast<std::uint8_t>(b), conf_b,
                        slope_b, step_b);
}

TEST(MapDiff, ClassifiesEachPairOfClassesAsDocumented) {
  EXPECT_EQ(Change(0, kNaN, 0, kNaN), CellChange::kNone);
  EXPECT_EQ(Change(4, kNaN, 0, kNaN), CellChange::kNone);
  EXPECT_EQ(Change(1, 0.9, 1, 0.9), CellChange::kUnchanged);
  EXPECT_EQ(Change(3, 0.3, 3, 0.3), CellChange::kUnchanged);  // the same class, however unsure
  EXPECT_EQ(Change(1, 0.9, 3, 0.9), CellChange::kNewObstacle);
  EXPECT_EQ(Change(3, 0.9, 1, 0.9), CellChange::kCleared);
  EXPECT_EQ(Change(0, kNaN, 3, 0.9), CellChange::kNewlySeen);
  EXPECT_EQ(Change(0, kNaN, 1, 0.2), CellChange::kNewlySeen);
  EXPECT_EQ(Change(2, 0.9, 0, kNaN), CellChange::kNoLongerSeen);
  // Undecided on one side: seen, not judged.
  EXPECT_EQ(Change(4, kNaN, 1, 0.9), CellChange::kUncertain);
  EXPECT_EQ(Change(3, 0.9, 4, kNaN), CellChange::kUncertain);
  // Low confidence in either map, at the threshold and just below (0.6).
  EXPECT_EQ(Change(1, 0.6, 3, 0.6), CellChange::kNewObstacle);
  EXPECT_EQ(Change(1, 0.59, 3, 0.9), CellChange::kUncertain);
  EXPECT_EQ(Change(3, 0.9, 1, 0.59), CellChange::kUncertain);
  EXPECT_EQ(Change(1, kNaN, 3, 0.9), CellChange::kUncertain);
  // Next to semi: the slope or the step must move by more than the noise (20 deg, 0.10 m).
  EXPECT_EQ(Change(1, 0.9, 2, 0.9, 5.0, 24.0), CellChange::kUncertain);
  EXPECT_EQ(Change(1, 0.9, 2, 0.9, 3.0, 24.0), CellChange::kHarder);
  EXPECT_EQ(Change(2, 0.9, 1, 0.9, 24.0, 3.0), CellChange::kEasier);
  EXPECT_EQ(Change(2, 0.9, 3, 0.9, 5.0, 5.0, 0.12, 0.21), CellChange::kUncertain);
  EXPECT_EQ(Change(2, 0.9, 3, 0.9, 5.0, 5.0, 0.12, 0.30), CellChange::kNewObstacle);
  EXPECT_EQ(Change(3, 0.9, 2, 0.9, 5.0, 5.0, 0.30, 0.12), CellChange::kCleared);
  EXPECT_EQ(Change(2, 0.9, 3, 0.9, kNaN, 5.0, kNaN, 0.3), CellChange::kUncertain);  // nothing to compare
  // Across semi (1 <-> 3) the class itself moved two thresholds: no noise test.
  EXPECT_EQ(Change(1, 0.9, 3, 0.9, 5.0, 5.0, 0.02, 0.02), CellChange::kNewObstacle);
  // Options move the thresholds.
  MapDiffOptions strict;
  strict.min_confidence = 0.95;
  EXPECT_EQ(ClassifyChange(1, 0.9, 5, 0.02, 3, 0.99, 5, 0.3, strict), CellChange::kUncertain);
  strict.min_confidence = 0.0;
  strict.slope_noise_deg = 1.0;
  EXPECT_EQ(ClassifyChange(1, 0.1, 14, 0.02, 2, 0.1, 16, 0.02, strict), CellChange::kHarder);
  EXPECT_TRUE(IsRealChange(CellChange::kNewObstacle));
  EXPECT_FALSE(IsRealChange(CellChange::kNewlySeen));
  EXPECT_FALSE(IsRealChange(CellChange::kUncertain));
  EXPECT_STREQ(CellChangeName(CellChange::kNoLongerSeen), "no_longer_seen");
}

/// A projection of `w` x 1 pixels of 0.1 m at the origin, confident and level everywhere.
GridProjection Row(const std::vector<int>& classes) {
  GridProjection g;
  g.resolution_m = 0.1;
  const int w = static_cast<int>(classes.size());
  g.classes = ImageU8(w, 1, 0);
  g.confidence = ImageF(w, 1, 0.95f);
  g.slope_deg = ImageF(w, 1, 2.0f);
  g.step_m = ImageF(w, 1, 0.01f);
  g.cost = ImageF(w, 1, 0.0f);
  g.height_m = ImageF(w, 1, 0.0f);
  for (int u = 0; u < w; ++u) g.classes(0, u) = static_cast<std::uint8_t>(classes[u]);
  return g;
}

TEST(MapDiff, CountsAndListsTheChangedColumnsOfTwoProjections) {
  GridProjection a = Row({1, 1, 1, 3, 0, 2, 1, 1, 0});
  GridProjection b = Row({1, 3, 3, 1, 1, 0, 2, 1, 0});
  a.confidence(0, 7) = 0.4f;  // unsure in A: the change to 2 below is uncertain
  b.classes(0, 7) = 3;
  b.slope_deg(0, 6) = 24.0f;  // 1 -> 2 with the slope 22 deg up: harder
  MapDiffOptions no_rim;  // the rule for moved boundaries is checked below
  no_rim.boundary_shift_columns = 0;
  const MapDiff d = DiffProjections(a, b, no_rim);
  const std::vector<CellChange> expected = {CellChange::kUnchanged,  CellChange::kNewObstacle, CellChange::kNewObstacle,
                                            CellChange::kCleared,    CellChange::kNewlySeen,   CellChange::kNoLongerSeen,
                                            CellChange::kHarder,     CellChange::kUncertain,   CellChange::kNone};
  for (int u = 0; u < 9; ++u) EXPECT_EQ(static_cast<CellChange>(d.change(0, u)), expected[u]) << "pixel " << u;
  EXPECT_EQ(d.summary.counts[static_cast<int>(CellChange::kNewObstacle)], 2u);
  EXPECT_EQ(d.summary.compared, 6u);  // pixels 0-3, 6, 7
  EXPECT_EQ(d.summary.RealChanges(), 4u);
  ASSERT_EQ(d.cells.size(), 7u);
  EXPECT_NEAR(d.cells[0].xy.x(), 0.15, 1e-12);
  EXPECT_NEAR(d.cells[0].xy.y(), 0.05, 1e-12);
  EXPECT_EQ(d.cells[0].class_a, 1);
  EXPECT_EQ(d.cells[0].class_b, 3);
  EXPECT_NEAR(d.cells[0].confidence_b, 0.95, 1e-6);
  EXPECT_TRUE(std::isnan(d.cells[3].confidence_a));  // newly seen: no class in A
  EXPECT_NE(d.summary.BriefReport().find("new_obstacle: 2"), std::string::npos) << d.summary.BriefReport();

  // An obstacle's rim that moved by one column: each map holds the other's class beside it.
  const MapDiff rim = DiffProjections(Row({1, 1, 3, 3}), Row({1, 3, 3, 3}));
  EXPECT_EQ(static_cast<CellChange>(rim.change(0, 1)), CellChange::kUncertain);
  EXPECT_EQ(static_cast<CellChange>(DiffProjections(Row({1, 1, 3, 3}), Row({1, 3, 3, 3}), no_rim).change(0, 1)),
            CellChange::kNewObstacle);

  GridProjection shifted = b;
  shifted.origin.x() = 0.1;
  EXPECT_THROW(DiffProjections(a, shifted), Error);
}

/// A level traversable floor at z in [0, 0.1) over x in [0, 3), y in [0, y_end) (0.1 m columns),
/// seen three times from above; with `crate`, non-traversable voxels up to 0.3 m over the
/// columns x, y in [1.0, 1.3) instead of the floor there (testing::FloorAndBox).
TraversabilityMap Floor(double y_end, bool crate, const MapMetadata& metadata = {}) {
  std::vector<ClassifiedPoint> points;
  for (const ClassifiedPoint& p : testing::FloorAndBox()) {
    const int ix = static_cast<int>(std::floor(p.world_p.x() / 0.1));
    const int iy = static_cast<int>(std::floor(p.world_p.y() / 0.1));
    if (p.world_p.y() >= y_end) continue;
    if (testing::InBoxColumn(ix, iy) && !crate) {
      if (p.world_p.z() < 0.1f) points.push_back(Pt(p.world_p.x(), p.world_p.y(), C(0), TravClass::kTraversable, 2.0f, 0.01f));
      continue;
    }
    points.push_back(p);
  }
  TraversabilityMap map(OctoMapCarving(), metadata);
  for (int t = 1; t <= 3; ++t) map.InsertFrame(points, testing::FloorAndBoxOrigin(), t);
  return map;
}

TEST(MapDiff, FindsTheCrateAddedToAFloorAndTheGroundSeenOnlyOnce) {
  // A: the floor up to y = 2.0 without the crate; B: the floor up to 2.5 with it.
  const TraversabilityMap a = Floor(2.0, false);
  const TraversabilityMap b = Floor(2.5, true);
  const MapDiff d = DiffMaps(a, "a.ot", b, "b.ot");
  const double r = 0.1;
  auto change_at = [&](double x, double y) {
    const int u = static_cast<int>(std::floor((x - d.b.origin.x()) / r));
    const int v = d.b.height() - 1 - static_cast<int>(std::floor((y - d.b.origin.y()) / r));
    return static_cast<CellChange>(d.change(v, u));
  };
  for (int ix = 10; ix < 13; ++ix) {
    for (int iy = 10; iy < 13; ++iy) EXPECT_EQ(change_at(C(ix), C(iy)), CellChange::kNewObstacle) << ix << "," << iy;
  }
  // Every new obstacle lies on the crate or within the vehicle's step radius of it (the ground
  // beside a 0.3 m step is a step for the vehicle), and nothing else changed on the floor.
  const double reach = b.metadata().vehicle.step_radius_m + r;
  for (const CellDiff& c : d.cells) {
    if (c.change == CellChange::kNewObstacle) {
      EXPECT_LE(std::max({1.0 - c.xy.x(), c.xy.x() - 1.3, 1.0 - c.xy.y(), c.xy.y() - 1.3}), reach)
          << c.xy.transpose();
    } else {
      EXPECT_EQ(c.change, CellChange::kNewlySeen) << c.xy.transpose();
      EXPECT_GE(c.xy.y(), 2.0);
      EXPECT_EQ(c.class_b, 1);
    }
  }
  EXPECT_EQ(d.summary.counts[static_cast<int>(CellChange::kNewlySeen)], 30u * 5u);  // y in [2.0, 2.5)
  // The other way round the crate is cleared and the strip no longer seen.
  const MapDiff back = DiffMaps(b, "b.ot", a, "a.ot");
  EXPECT_EQ(back.summary.counts[static_cast<int>(CellChange::kCleared)],
            d.summary.counts[static_cast<int>(CellChange::kNewObstacle)]);
  EXPECT_EQ(back.summary.counts[static_cast<int>(CellChange::kNoLongerSeen)], 150u);
  // A map against itself: nothing changed.
  const MapDiff same = DiffMaps(a, "a.ot", a, "a.ot");
  EXPECT_EQ(same.cells.size(), 0u);
  EXPECT_EQ(same.summary.counts[static_cast<int>(CellChange::kUnchanged)], 30u * 20u);
}

TEST(MapDiff, WritesTheChangedColumnsAsCsvAndAPicture) {
  const testing::TempDir dir;
  const MapDiff d = DiffMaps(Floor(2.0, false), "a.ot", Floor(2.5, true), "b.ot");
  WriteMapDiff(d, dir / "out", "test");
  std::istringstream csv(ReadTextFile(dir / "out/diff.csv"));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, kMapDiffCsvHeader);
  std::size_t rows = 0, new_obstacles = 0;
  while (std::getline(csv, line)) {
    ++rows;
    if (line.find(",new_obstacle") != std::string::npos) ++new_obstacles;
  }
  EXPECT_EQ(rows, d.cells.size());
  EXPECT_EQ(new_obstacles, d.summary.counts[static_cast<int>(CellChange::kNewObstacle)]);
  // A newly seen row has no confidence in A.
  EXPECT_NE(ReadTextFile(dir / "out/diff.csv").find(",0,1,nan,"), std::string::npos);
  const cv::Mat png = cv::imread(dir / "out/diff.png", cv::IMREAD_COLOR);
  ASSERT_FALSE(png.empty());
  // The crate's centre column is drawn red (the picture is BGR here).
  int red = 0;
  for (int v = 0; v < png.rows; ++v) {
    for (int u = 0; u < png.cols; ++u) {
      const cv::Vec3b p = png.at<cv::Vec3b>(v, u);
      const Rgb8 c = change_colours::kNewObstacle;
      red += p[2] == c.r && p[1] == c.g && p[0] == c.b;
    }
  }
  EXPECT_GT(red, 9 * 25);  // 9 crate columns of at least 5 x 5 px, plus the swatch
}

TEST(MapDiff, RefusesMapsOfAnotherResolutionWorldFrameOrVehicle) {
  const TraversabilityMap a = Floor(2.0, false);
  auto message = [&](const TraversabilityMap& b) {
    try {
      DiffMaps(a, "a.ot", b, "b.ot");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("compared");
  };
  MapOptions coarse = OctoMapCarving();
  coarse.resolution_m = 0.2;
  TraversabilityMap b_coarse(coarse);
  b_coarse.InsertFrame(testing::FloorAndBox(), testing::FloorAndBoxOrigin(), 1);
  EXPECT_EQ(message(b_coarse).rfind("b.ot: resolution 0.2 m, but a.ot has 0.1 m; maps compare only when", 0), 0u)
      << message(b_coarse);
  MapMetadata site;
  site.world_frame = "site";
  EXPECT_EQ(message(Floor(2.0, false, site)).rfind("b.ot: world frame 'site', but a.ot has (unnamed);", 0), 0u)
      << message(Floor(2.0, false, site));
  MapMetadata heavy;
  heavy.vehicle.max_step_m = 0.3;
  const std::string vehicle = message(Floor(2.0, false, heavy));
  EXPECT_NE(vehicle.find("vehicle.max_step_m"), std::string::npos) << vehicle;
  EXPECT_NE(vehicle.find("b.ot"), std::string::npos) << vehicle;
  EXPECT_NE(vehicle.find("a.ot"), std::string::npos) << vehicle;
  EXPECT_EQ(message(TraversabilityMap(OctoMapCarving())), "compared");  // an empty B: all no longer seen
  const TraversabilityMap empty(OctoMapCarving());
  EXPECT_THROW(DiffMaps(empty, "a.ot", empty, "b.ot"), Error);
  MapDiffOptions bad;
  bad.min_confidence = 1.5;
  EXPECT_THROW(DiffMaps(a, "a.ot", a, "b.ot", bad), Error);
}

}  // namespace
}  // namespace ssta
