#include <cmath>
#include <cstdint>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <octomap/ColorOcTree.h>
#include <opencv2/imgcodecs.hpp>
#include <yaml-cpp/yaml.h>

#include "map_test_util.h"
#include "ssta/files/file_util.h"
#include "ssta/io/image_io.h"
#include "ssta/mapping/confidence_bar.h"
#include "ssta/mapping/map_export.h"
#include "temp_dir.h"

namespace ssta {
namespace {

using testing::OctoMapCarving;

using testing::Pt;
using testing::TempDir;

/// An asymmetric 5 x 3 patch of floor with its lower-left corner at (-1.0, 2.0):
///   y 2.2..2.3:  T T T T N      (N non-traversable at the top right)
///   y 2.1..2.2:  T T . T T      (. never observed)
///   y 2.0..2.1:  S T T T T      (S semi-traversable at the bottom left)
TraversabilityMap AsymmetricMap() {
  std::vector<ClassifiedPoint> points;
  for (int i = 0; i < 5; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (i == 2 && j == 1) continue;
      TravClass c = TravClass::kTraversable;
      if (i == 4 && j == 2) c = TravClass::kNonTraversable;
      if (i == 0 && j == 0) c = TravClass::kSemiTraversable;
      points.push_back(Pt(-0.95 + 0.1 * i, 2.05 + 0.1 * j, 0.05, c, 18.0f, 0.05f));
    }
  }
  TraversabilityMap map(OctoMapCarving());
  map.InsertFrame(points, {-0.75, 2.15, 2.0}, 1);
  return map;
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

TEST(MapExport, GridRowZeroIsTheLargestYAndTheOriginIsTheLowerLeftCorner) {
  const TempDir dir;
  const TraversabilityMap map = AsymmetricMap();
  const std::string prefix = dir / "grid";
  GridExportOptions raw;
  raw.fill_min_neighbours = 0;  // keep the unobserved cell unknown
  const GridProjection grid = ExportGrid(map, prefix, raw);
  ASSERT_EQ(grid.width(), 5);
  ASSERT_EQ(grid.height(), 3);

  const std::vector<std::vector<int>> expected_classes = {{1, 1, 1, 1, 3}, {1, 1, 0, 1, 1}, {2, 1, 1, 1, 1}};
  const ImageU8 classes = ReadLabelImage(prefix + "_classes.png");
  const cv::Mat pgm = cv::imread(prefix + ".pgm", cv::IMREAD_UNCHANGED);
  const cv::Mat colour = cv::imread(prefix + ".png", cv::IMREAD_COLOR);  // BGR
  ASSERT_EQ(classes.width(), 5);
  ASSERT_EQ(pgm.cols, 5);
  ASSERT_EQ(pgm.rows, 3);
  ASSERT_EQ(pgm.type(), CV_8UC1);
  for (int v = 0; v < 3; ++v) {
    for (int u = 0; u < 5; ++u) {
      const int c = expected_classes[v][u];
      EXPECT_EQ(classes(v, u), c) << v << "," << u;
      const int nav = c == 3 ? 0 : (c == 0 ? 205 : 254);
      EXPECT_EQ(pgm.at<std::uint8_t>(v, u), nav) << v << "," << u;
      const Rgb8 rgb = ClassColour(static_cast<TravClass>(c));
      const cv::Vec3b bgr = colour.at<cv::Vec3b>(v, u);
      EXPECT_EQ(bgr[2], rgb.r);
      EXPECT_EQ(bgr[1], rgb.g);
      EXPECT_EQ(bgr[0], rgb.b);
    }
  }
  EXPECT_EQ(colour.at<cv::Vec3b>(0, 4), cv::Vec3b(0, 0, 255));  // red, top right
  EXPECT_EQ(colour.at<cv::Vec3b>(2, 0), cv::Vec3b(255, 0, 0));  // blue, bottom left

  const YAML::Node yaml = YAML::LoadFile(prefix + ".yaml");
  EXPECT_EQ(yaml["image"].as<std::string>(), "grid.pgm");
  EXPECT_DOUBLE_EQ(yaml["resolution"].as<double>(), 0.1);
  ASSERT_EQ(yaml["origin"].size(), 3u);
  EXPECT_NEAR(yaml["origin"][0].as<double>(), -1.0, 1e-9);
  EXPECT_NEAR(yaml["origin"][1].as<double>(), 2.0, 1e-9);
  EXPECT_EQ(yaml["origin"][2].as<double>(), 0.0);
  EXPECT_EQ(yaml["negate"].as<int>(), 0);
  EXPECT_DOUBLE_EQ(yaml["occupied_thresh"].as<double>(), 0.65);
  EXPECT_DOUBLE_EQ(yaml["free_thresh"].as<double>(), 0.196);
  // map_server's trinary reading of the PGM values: p = (255 - v) / 255.
  EXPECT_GT((255 - 0) / 255.0, 0.65);
  EXPECT_LT((255 - 254) / 255.0, 0.196);
  const double unknown = (255 - 205) / 255.0;
  EXPECT_TRUE(unknown >= 0.196 && unknown <= 0.65);
}

ImageU8 ClassGrid(const std::vector<std::vector<int>>& rows) {
  ImageU8 image(static_cast<int>(rows[0].size()), static_cast<int>(rows.size()), 0);
  for (int v = 0; v < image.height(); ++v) {
    for (int u = 0; u < image.width(); ++u) image(v, u) = static_cast<std::uint8_t>(rows[v][u]);
  }
  return image;
}

TEST(MapExport, FillHolesTakesTheNeighboursMajorityOnlyInsideTheObservedArea) {
  // 0 unknown, 1 traversable, 2 semi, 3 non-traversable, 4 undecided.
  const ImageU8 classes = ClassGrid({{1, 1, 1, 0, 0, 0},    // (0,3): 1 1 3 3 known
                                     {1, 0, 1, 3, 3, 0},    // (1,1): 8 known, 7 traversable
                                     {1, 1, 3, 0, 3, 0},    // (2,3): 8 known, 5 non, 3 trav
                                     {2, 2, 1, 1, 3, 0},    // (2,5), (1,5): the edge, 3 / 2 known
                                     {4, 0, 2, 1, 0, 0}});  // (4,1): 2 2 1 2 and an undecided
  ImageU8 five = classes;
  EXPECT_EQ(FillHoles(&five, 5), 2);
  EXPECT_EQ(five(1, 1), 1);
  EXPECT_EQ(five(2, 3), 3);
  EXPECT_EQ(five(0, 3), 0);
  EXPECT_EQ(five(4, 1), 0);  // the undecided neighbour does not count: 4 known
  EXPECT_EQ(five(4, 0), 4);  // an undecided cell is no hole
  for (int v = 0; v < 5; ++v) EXPECT_EQ(five(v, 5), 0) << v;  // the edge of the observed area

  ImageU8 four = classes;
  EXPECT_EQ(FillHoles(&four, 4), 4);
  EXPECT_EQ(four(0, 3), 3);  // 2 traversable against 2 non-traversable: the worse
  EXPECT_EQ(four(4, 1), 2);  // 3 semi against 1 traversable
  EXPECT_EQ(four(2, 5), 0);  // 3 known

  // A hole two cells wide: each has 7 classified neighbours in the input, so with 8 neither is
  // filled, although after filling one the other would have 8.
  const ImageU8 wide = ClassGrid({{1, 1, 1, 1}, {1, 0, 0, 1}, {1, 1, 1, 1}});
  ImageU8 eight = wide;
  EXPECT_EQ(FillHoles(&eight, 8), 0);
  ImageU8 seven = wide;
  EXPECT_EQ(FillHoles(&seven, 7), 2);

  ImageU8 bad = classes;
  EXPECT_THROW(FillHoles(&bad, 0), Error);
  EXPECT_THROW(FillHoles(&bad, 9), Error);
}

TEST(MapExport, GridExportFillsTheHoleOfTheMapByDefault) {
  const TempDir dir;
  GridExportChanges changes;
  const GridProjection filled = ExportGrid(AsymmetricMap(), dir / "grid", GridExportOptions{}, &changes);
  EXPECT_EQ(filled.classes(1, 2), 1);  // the unobserved cell amid traversable ones
  EXPECT_EQ(changes.holes_filled, 1);
  EXPECT_EQ(ReadLabelImage(dir / "grid_classes.png")(1, 2), 1);
  GridExportOptions bad;
  bad.fill_min_neighbours = 9;
  EXPECT_THROW(ExportGrid(AsymmetricMap(), dir / "bad", bad), Error);
}

/// A 12 x 12 projection at 0.1 m: traversable ground at height 0 and slope 3 deg everywhere.
GridProjection LevelGround() {
  GridProjection g;
  g.resolution_m = 0.1;
  g.classes = ImageU8(12, 12, 1);
  g.cost = ImageF(12, 12, 0.0f);
  g.height_m = ImageF(12, 12, 0.0f);
  g.slope_deg = ImageF(12, 12, 3.0f);
  g.step_m = ImageF(12, 12, 0.4f);
  return g;
}

TEST(MapExport, LevelCellsAtTheHeightOfTheGroundAroundThemAreNotSteps) {
  GridProjection g = LevelGround();
  auto non = [&](int v, int u, float z, float slope) {
    g.classes(v, u) = 3;
    g.cost(v, u) = 1.0f;
    g.height_m(v, u) = z;
    g.slope_deg(v, u) = slope;
  };
  non(1, 1, 0.0f, 3.0f);   // level, at the ground's height: a step only by a frame's plane
  non(1, 4, 0.1f, 3.0f);   // one cell (the tolerance) above the ground: still ground
  non(1, 7, 0.2f, 3.0f);   // two cells up: an obstacle's top, kept
  non(9, 1, 0.0f, 20.0f);  // steep (>= the 15 deg level limit): kept
  non(9, 4, 0.0f, 14.9f);  // level, just
  for (int v = 5; v <= 7; ++v) {  // a 3 x 3 block
    for (int u = 5; u <= 7; ++u) non(v, u, 0.0f, 3.0f);
  }
  g.classes(10, 9) = 0;  // unobserved: no height, not a candidate
  g.height_m(10, 9) = std::nanf("");
  const GridProjection input = g;
  // Radius 1.5 pixels, the 8 neighbours: the block's corners see 5 ground pixels, its edges 3
  // and its centre none (the input is read, so changed pixels do not count).
  auto changed = [](int v, int u) {
    return (v == 1 && (u == 1 || u == 4)) || (v == 9 && u == 4) || ((v == 5 || v == 7) && (u == 5 || u == 7));
  };
  EXPECT_EQ(JudgeStepsByLocalGround(&g, 0.15, 0.1, 15.0), 7);
  for (int v = 0; v < 12; ++v) {
    for (int u = 0; u < 12; ++u) {
      EXPECT_EQ(g.classes(v, u), changed(v, u) ? 1 : input.classes(v, u)) << v << "," << u;
      EXPECT_EQ(g.cost(v, u), changed(v, u) ? 0.0f : input.cost(v, u)) << v << "," << u;
      if (std::isfinite(input.height_m(v, u))) {
        EXPECT_EQ(g.height_m(v, u), input.height_m(v, u));
      }
      EXPECT_EQ(g.step_m(v, u), input.step_m(v, u));  // as observed
    }
  }
  // 2.5 pixels reach the ground beyond the block from each of its pixels.
  g = input;
  EXPECT_EQ(JudgeStepsByLocalGround(&g, 0.25, 0.1, 15.0), 12);
  EXPECT_EQ(g.classes(6, 6), 1);
  EXPECT_EQ(g.classes(1, 7), 3);
  EXPECT_EQ(g.classes(9, 1), 3);
  // Fewer than 5 traversable pixels within the radius: no verdict of the ground.
  GridProjection sparse = input;
  sparse.classes = ImageU8(12, 12, 0);
  sparse.classes(1, 1) = 3;
  for (int u = 0; u < 4; ++u) sparse.classes(0, u) = 1;
  EXPECT_EQ(JudgeStepsByLocalGround(&sparse, 0.3, 0.1, 15.0), 0);
  sparse.classes(2, 1) = 1;
  EXPECT_EQ(JudgeStepsByLocalGround(&sparse, 0.3, 0.1, 15.0), 1);
  EXPECT_THROW(JudgeStepsByLocalGround(&g, 0.0, 0.1, 15.0), Error);
  EXPECT_THROW(JudgeStepsByLocalGround(&g, 1.0, -0.1, 15.0), Error);
}

bool InPatch(int ix, int iy) { return ix >= 5 && ix < 8 && iy >= 5 && iy < 8; }
bool InBox(int ix, int iy) { return ix >= 20 && ix < 23 && iy >= 20 && iy < 23; }

// A 30 x 30 cell traversable floor at z in [0, 0.1) with a patch (cells 5..7) that a frame
// called a step (non-traversable at slope 2 deg: eq. 5 against a plane that does not pass
// there) at the floor's height, and a box (cells 20..22) 0.3 m high; `hole`: cell (12, 12) of
// the floor is never observed.
TraversabilityMap FloorWithPatchAndBox(bool hole) {
  std::vector<ClassifiedPoint> points;
  for (int ix = 0; ix < 30; ++ix) {
    for (int iy = 0; iy < 30; ++iy) {
      if (hole && ix == 12 && iy == 12) continue;
      const bool non = InPatch(ix, iy) || InBox(ix, iy);
      const double z = InBox(ix, iy) ? testing::C(3) : testing::C(0);
      points.push_back(Pt(testing::C(ix), testing::C(iy), z,
                          non ? TravClass::kNonTraversable : TravClass::kTraversable, 2.0f, 0.3f));
    }
  }
  TraversabilityMap map(OctoMapCarving());
  map.InsertFrame(points, {1.5, 1.5, 3.0}, 1);
  return map;
}

/// The export with the steps against the local ground on (1 m), as the maps of frames classed
/// by eq. 5 want it.
GridExportOptions LocalGround() {
  GridExportOptions options;
  options.local_ground_radius_m = 1.0;
  return options;
}

TEST(MapExport, GridExportJudgesStepsByTheLocalGroundWhenAsked) {
  // The export calls the patch traversable, not the box top.
  const TraversabilityMap map = FloorWithPatchAndBox(false);
  const TempDir dir;
  GridExportChanges changes;
  const GridProjection judged = ExportGrid(map, dir / "judged", LocalGround(), &changes);
  EXPECT_EQ(changes.judged_by_local_ground, 9);  // the patch
  GridExportOptions off;
  off.local_ground_radius_m = 0.0;
  const GridProjection as_observed = ExportGrid(map, dir / "observed", off);
  ASSERT_EQ(judged.width(), 30);
  ASSERT_EQ(judged.height(), 30);
  int patch_judged = 0, patch_observed = 0, box_judged = 0;
  for (int v = 0; v < 30; ++v) {
    for (int u = 0; u < 30; ++u) {
      const int ix = u, iy = 29 - v;
      if (InPatch(ix, iy)) {
        patch_judged += judged.classes(v, u) == 1;
        patch_observed += as_observed.classes(v, u) == 3;
      }
      if (InBox(ix, iy)) box_judged += judged.classes(v, u) == 3;
    }
  }
  EXPECT_EQ(patch_judged, 9);
  EXPECT_EQ(patch_observed, 9);
  EXPECT_EQ(box_judged, 9);
  EXPECT_EQ(ReadLabelImage(dir / "judged_classes.png")(29 - 6, 6), 1);
  EXPECT_EQ(map.TopSurfaceAt(testing::C(6), testing::C(6)).cls, TravClass::kNonTraversable);  // queries as observed
  GridExportOptions bad;
  bad.local_ground_radius_m = -1.0;
  EXPECT_THROW(ExportGrid(map, dir / "bad", bad), Error);
}

bool SameCost(double a, double b) { return (std::isnan(a) && std::isnan(b)) || a == b; }

TEST(MapExport, QueriesAsExportedAnswerEveryCellAsTheExportedGridShowsIt) {
  // The patch is judged traversable and the hole filled in the export; TopSurfaceAsExported
  // answers each cell with the export's class and cost, from a projection of the cell and its
  // surroundings only (here the whole floor is within reach of some cells, not of others).
  const TraversabilityMap map = FloorWithPatchAndBox(true);
  const TempDir dir;
  for (const double resolution : {0.0, 0.2}) {  // the map's (one column per pixel), and coarser
    GridExportOptions options = LocalGround();
    options.resolution_m = resolution;
    GridExportChanges changes;
    const GridProjection grid = ExportGrid(map, dir / "grid", options, &changes);
    EXPECT_GT(changes.judged_by_local_ground, 0);
    int mismatches = 0, judged = 0, filled = 0;
    for (int v = 0; v < grid.height(); ++v) {
      for (int u = 0; u < grid.width(); ++u) {
        const Eigen::Vector2d c = grid.PixelCenter(v, u);
        const CellInfo exported = TopSurfaceAsExported(map, c.x(), c.y(), options);
        const CellInfo observed = map.TopSurfaceAt(c.x(), c.y());
        mismatches += exported.cls != static_cast<TravClass>(grid.classes(v, u)) ||
                      !SameCost(exported.cost, grid.cost(v, u));
        judged += observed.cls == TravClass::kNonTraversable && exported.cls == TravClass::kTraversable;
        filled += !observed.observed && exported.cls != TravClass::kUnknown;
      }
    }
    EXPECT_EQ(mismatches, 0) << "resolution " << resolution;
    EXPECT_EQ(judged, changes.judged_by_local_ground) << "resolution " << resolution;
    if (resolution == 0.0) {  // the hole; at 0.2 m its pixel holds floor as well
      EXPECT_EQ(changes.holes_filled, 1);
      EXPECT_EQ(filled, 1);
    }
  }
  const CellInfo patch = TopSurfaceAsExported(map, testing::C(6), testing::C(6), LocalGround());
  EXPECT_TRUE(patch.observed);
  EXPECT_EQ(patch.cls, TravClass::kTraversable);
  EXPECT_EQ(patch.cost, 0.0);
  EXPECT_NEAR(patch.center.z(), testing::C(0), 1e-9);
  // The map's evidence there was for non-traversable: no probability for the export's class.
  EXPECT_TRUE(std::isnan(patch.probability));
  // Nor a slope and step that decided it: the export did.
  EXPECT_EQ(patch.decided_by, ClassJudge::kExport);
  EXPECT_TRUE(std::isnan(patch.slope_deg) && std::isnan(patch.step_m));
  EXPECT_NEAR(patch.frame_mean_step_m, 0.3, 1e-6);  // the frames' mean stays
  const CellInfo floor = TopSurfaceAsExported(map, testing::C(2), testing::C(2), LocalGround());  // kept as it is
  EXPECT_EQ(floor.cls, TravClass::kTraversable);
  EXPECT_EQ(floor.probability, map.TopSurfaceAt(testing::C(2), testing::C(2)).probability);
  EXPECT_GT(floor.probability, 0.5);
  EXPECT_EQ(map.TopSurfaceAt(testing::C(6), testing::C(6)).cls, TravClass::kNonTraversable);
  const CellInfo hole = TopSurfaceAsExported(map, testing::C(12), testing::C(12));
  EXPECT_FALSE(hole.observed);
  EXPECT_EQ(hole.cls, TravClass::kTraversable);
  EXPECT_TRUE(std::isnan(hole.cost));
  EXPECT_TRUE(std::isnan(hole.center.z()));
  EXPECT_EQ(hole.decided_by, ClassJudge::kExport);
  EXPECT_EQ(TopSurfaceAsExported(map, testing::C(21), testing::C(21)).cls, TravClass::kNonTraversable);  // box
  GridExportOptions off;  // without the two steps: the map as observed
  off.local_ground_radius_m = 0.0;
  off.fill_min_neighbours = 0;
  EXPECT_EQ(TopSurfaceAsExported(map, testing::C(6), testing::C(6), off).cls, TravClass::kNonTraversable);
  EXPECT_EQ(TopSurfaceAsExported(map, testing::C(12), testing::C(12), off).cls, TravClass::kUnknown);
  EXPECT_THROW(TopSurfaceAsExported(map, std::nan(""), 1.0), Error);
}

TEST(MapExport, FootprintsAndPathsCanReadTheSurfaceAsExported) {
  const TraversabilityMap map = FloorWithPatchAndBox(true);
  // A 0.3 x 0.3 m footprint on the patch: a step as observed, floor as exported.
  const FootprintQuery on_patch{testing::C(6), testing::C(6), 0.0, 0.3, 0.3};
  const Eigen::AlignedBox2d patch_box(Eigen::Vector2d(0.45, 0.45), Eigen::Vector2d(0.75, 0.75));
  const FootprintResult observed = map.QueryFootprint(on_patch);
  const FootprintResult exported = map.QueryFootprint(on_patch, ExportedSurface(map, patch_box, LocalGround()));
  EXPECT_EQ(observed.worst, TravClass::kNonTraversable);
  EXPECT_EQ(observed.cells, 9);
  EXPECT_EQ(exported.worst, TravClass::kTraversable);
  EXPECT_EQ(exported.cells, 9);
  EXPECT_EQ(exported.mean_cost, 0.0);
  // The export, not the map's evidence, made those cells traversable: no confidence to give.
  EXPECT_TRUE(std::isnan(exported.drivable_confidence));
  // The hole is unobserved as observed; as exported it holds its filled class and counts.
  const FootprintQuery on_hole{testing::C(12), testing::C(12), 0.0, 0.05, 0.05};
  const Eigen::AlignedBox2d hole_box(Eigen::Vector2d(1.2, 1.2), Eigen::Vector2d(1.3, 1.3));
  EXPECT_EQ(map.QueryFootprint(on_hole).observed_cells, 0);
  EXPECT_EQ(map.QueryFootprint(on_hole).worst, TravClass::kUnknown);
  EXPECT_EQ(map.QueryFootprint(on_hole, ExportedSurface(map, hole_box, LocalGround())).observed_cells, 1);
  EXPECT_EQ(map.QueryFootprint(on_hole, ExportedSurface(map, hole_box, LocalGround())).worst, TravClass::kTraversable);
  // A path along the patch's middle row is blocked as observed, clear as exported; one through
  // the box is blocked either way, at the box's edge.
  const std::vector<Eigen::Vector2d> across_patch{{testing::C(0), testing::C(6)}, {testing::C(15), testing::C(6)}};
  const Eigen::AlignedBox2d path_box(Eigen::Vector2d(0.0, 0.6), Eigen::Vector2d(1.6, 0.7));
  EXPECT_TRUE(map.QueryPath(across_patch, 0.0).blocked);
  EXPECT_FALSE(map.QueryPath(across_patch, 0.0, ExportedSurface(map, path_box, LocalGround())).blocked);
  const std::vector<Eigen::Vector2d> across_box{{testing::C(15), testing::C(21)}, {testing::C(29), testing::C(21)}};
  const PathResult to_box = map.QueryPath(across_box, 0.0, ExportedSurface(map, path_box, LocalGround()));  // box outside
  EXPECT_TRUE(to_box.blocked);
  EXPECT_NEAR(to_box.first_non_traversable_distance_m, 2.0 - testing::C(15), 0.051);  // x = 2.0
  // Columns outside the projected region answer as the whole export, projected on their own.
  const ExportedSurface corner(map, Eigen::AlignedBox2d(Eigen::Vector2d(2.5, 2.5), Eigen::Vector2d(2.9, 2.9)),
                               LocalGround());
  EXPECT_EQ(corner(testing::C(6), testing::C(6)).cls, TravClass::kTraversable);
  EXPECT_EQ(corner(testing::C(12), testing::C(12)).cls, TravClass::kTraversable);  // the filled hole
  EXPECT_EQ(corner(testing::C(21), testing::C(21)).cls, TravClass::kNonTraversable);
  EXPECT_THROW(corner(std::nan(""), 0.0), Error);
  EXPECT_THROW(ExportedSurface(map, Eigen::AlignedBox2d()), Error);  // empty region
}

TEST(MapExport, AConfidenceBarExportsTheUnsureDrivableCellsUndecided) {
  // A 1.0 x 0.4 m floor: its left half (x < 0.5) seen by three frames, its right half by one,
  // so the right half is the less sure of the two.
  TraversabilityMap map(OctoMapCarving());
  for (int frame = 0; frame < 3; ++frame) {
    std::vector<ClassifiedPoint> points;
    for (int i = 0; i < 10; ++i) {
      for (int j = 0; j < 4; ++j) {
        if (i >= 5 && frame > 0) continue;
        points.push_back(Pt(testing::C(i), testing::C(j), 0.05, TravClass::kTraversable));
      }
    }
    map.InsertFrame(points, {0.5, 0.2, 2.0}, 1000 + frame);
  }
  GridExportOptions plain;
  plain.fill_min_neighbours = 0;
  const GridProjection all = ProjectAsExported(map, plain);
  const double left = all.confidence(0, 0), right = all.confidence(0, 9);
  ASSERT_GT(left, right);
  GridExportOptions barred = plain;
  barred.min_confidence = 0.5 * (left + right);
  GridExportChanges changes;
  const GridProjection sure = ProjectAsExported(map, barred, &changes);
  EXPECT_EQ(changes.below_confidence_bar, 20);  // the right half, 5 x 4 cells
  GridProjection by_hand = all;
  EXPECT_EQ(ApplyConfidenceBar(&by_hand, barred.min_confidence), 20);
  for (int v = 0; v < all.height(); ++v) {
    for (int u = 0; u < all.width(); ++u) {
      const auto expected = u < 5 ? TravClass::kTraversable : TravClass::kUndecided;
      EXPECT_EQ(static_cast<TravClass>(sure.classes(v, u)), expected) << v << "," << u;
      EXPECT_EQ(sure.classes(v, u), by_hand.classes(v, u));
      EXPECT_EQ(std::isnan(sure.cost(v, u)), u >= 5);
      // A query through the same bar reads the exported cell as the barred export shows it.
      const Eigen::Vector2d p = all.PixelCenter(v, u);
      const ExportedSurface unbarred(map, Eigen::AlignedBox2d(p, p), plain);
      EXPECT_EQ(AtConfidenceBar(unbarred(p.x(), p.y()), barred.min_confidence).cls,
                ExportedSurface(map, Eigen::AlignedBox2d(p, p), barred)(p.x(), p.y()).cls);
    }
  }
  // The navigation PGM shows the barred cells unknown (205), the sure ones free (254).
  TempDir dir;
  ExportGrid(map, dir / "g", barred);
  const cv::Mat pgm = cv::imread(dir / "g.pgm", cv::IMREAD_UNCHANGED);
  ASSERT_EQ(pgm.cols, 10);
  EXPECT_EQ(pgm.at<std::uint8_t>(0, 0), 254);
  EXPECT_EQ(pgm.at<std::uint8_t>(0, 9), 205);
  barred.min_confidence = 1.5;
  EXPECT_THROW(ProjectAsExported(map, barred), Error);
}

TEST(MapExport, GridOfAnEmptyMapNeedsARegion) {
  const TempDir dir;
  const TraversabilityMap empty(OctoMapCarving());
  EXPECT_THROW(ExportGrid(empty, dir / "g"), Error);
  GridExportOptions options;
  options.region = Eigen::AlignedBox2d(Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(0.3, 0.2));
  const GridProjection grid = ExportGrid(empty, dir / "g", options);
  EXPECT_EQ(grid.width(), 3);
  EXPECT_EQ(grid.height(), 2);
  const cv::Mat pgm = cv::imread(dir / "g.pgm", cv::IMREAD_UNCHANGED);
  EXPECT_EQ(cv::countNonZero(pgm == 205), 6);
}

TEST(MapExport, CsvPlyAndPcdListEveryOccupiedVoxel) {
  const TempDir dir;
  const TraversabilityMap map = AsymmetricMap();
  ExportCsv(map, dir / "m.csv");
  ExportPly(map, dir / "m.ply");
  ExportPcd(map, dir / "m.pcd");

  const auto csv = Lines(ReadTextFile(dir / "m.csv"));
  ASSERT_EQ(csv.size(), 15u);
  EXPECT_EQ(csv[0], "x,y,z,class,cost,probability,slope_deg,step_m,observations,confidence,decided_by,frame_mean_slope_deg,frame_mean_step_m");
  int non_traversable = 0;
  for (std::size_t i = 1; i < csv.size(); ++i) {
    if (csv[i].find(",3,1.0000,") != std::string::npos) {
      ++non_traversable;
      EXPECT_EQ(csv[i], "-0.5500,2.2500,0.0500,3,1.0000,0.6357,nan,nan,1,0.6357,frames,18.00,0.050");
    }
  }
  EXPECT_EQ(non_traversable, 1);

  const auto ply = Lines(ReadTextFile(dir / "m.ply"));
  EXPECT_EQ(ply[0], "ply");
  EXPECT_NE(std::find(ply.begin(), ply.end(), "element vertex 14"), ply.end());
  const auto header_end = std::find(ply.begin(), ply.end(), "end_header");
  ASSERT_NE(header_end, ply.end());
  EXPECT_EQ(ply.end() - header_end - 1, 14);

  const auto pcd = Lines(ReadTextFile(dir / "m.pcd"));
  EXPECT_NE(std::find(pcd.begin(), pcd.end(), "POINTS 14"), pcd.end());
  const auto data = std::find(pcd.begin(), pcd.end(), "DATA ascii");
  ASSERT_NE(data, pcd.end());
  EXPECT_EQ(pcd.end() - data - 1, 14);
  std::istringstream first(*(data + 1));
  std::vector<std::string> fields{std::istream_iterator<std::string>(first), {}};
  EXPECT_EQ(fields.size(), 10u);
}

TEST(MapExport, OctovisFileIsAColorOcTreeInClassColours) {
  const TempDir dir;
  const TraversabilityMap map = AsymmetricMap();
  ExportOctovis(map, dir / "m.ot");
  std::unique_ptr<octomap::AbstractOcTree> tree(octomap::AbstractOcTree::read(dir / "m.ot"));
  auto* colour = dynamic_cast<octomap::ColorOcTree*>(tree.get());
  ASSERT_NE(colour, nullptr);
  const octomap::ColorOcTreeNode* red = colour->search(-0.55, 2.25, 0.05);
  ASSERT_NE(red, nullptr);
  EXPECT_TRUE(colour->isNodeOccupied(red));
  EXPECT_EQ(red->getColor(), octomap::ColorOcTreeNode::Color(255, 0, 0));
  const octomap::ColorOcTreeNode* blue = colour->search(-0.95, 2.05, 0.05);
  ASSERT_NE(blue, nullptr);
  EXPECT_EQ(blue->getColor(), octomap::ColorOcTreeNode::Color(0, 0, 255));
  EXPECT_EQ(colour->search(-0.75, 2.15, 0.05), nullptr);
}

TEST(MapExport, ErrorsNameTheFile) {
  const TempDir dir;
  const TraversabilityMap map = AsymmetricMap();
  const std::string path = dir / "missing/m.csv";
  try {
    ExportCsv(map, path);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  EXPECT_THROW(ExportGrid(map, dir / "missing/grid"), Error);
}

TEST(MapExport, QueryCsvRowPrintsUnknownAsNaN) {
  CellInfo unknown;
  unknown.center = {1.0, 2.0, std::nan("")};
  EXPECT_EQ(QueryCsvRow(unknown), "1.0000,2.0000,nan,0,nan,nan,nan,nan,0,nan,,nan,nan");
}

TEST(MapExport, QueryCsvRowPrintsFarPointsWholeInExponentForm) {
  // A point asked far outside any map: %.4f would need 300 digits (and was cut at 63).
  CellInfo far;
  far.center = Eigen::Vector3d(1e308, -2.5e12, 999999999.0);
  const std::string row = QueryCsvRow(far);
  EXPECT_EQ(row, "1.000000e+308,-2.500000e+12,999999999.0000,0,nan,nan,nan,nan,0,nan,,nan,nan");
  EXPECT_DOUBLE_EQ(std::stod(row.substr(0, row.find(','))), 1e308);
}

}  // namespace
}  // namespace ssta
