#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "mapping/map_test_util.h"
#include "ssta/core/error.h"
#include "ssta/pictures/map_picture.h"
#include "temp_dir.h"

namespace ssta {
namespace {

using testing::OctoMapCarving;
using testing::Pt;
namespace colours = picture_colours;

/// A 2 x 1 m floor at 0.1 m cells (x in [0, 2), y in [0, 1)): traversable, a semi-traversable
/// cell at (0.15, 0.15), a 0.2 m non-traversable patch over x in [1.5, 1.7), y in [0.4, 0.6),
/// and the cell at (0.55, 0.75) never observed. Seen from (-0.5, 0.5) and then (-0.5, -0.3).
TraversabilityMap FloorMap() {
  std::vector<ClassifiedPoint> points;
  for (int i = 0; i < 20; ++i) {
    for (int j = 0; j < 10; ++j) {
      if (i == 5 && j == 7) continue;
      TravClass c = TravClass::kTraversable;
      if (i == 1 && j == 1) c = TravClass::kSemiTraversable;
      if (i >= 15 && i < 17 && j >= 4 && j < 6) c = TravClass::kNonTraversable;
      points.push_back(Pt(0.05 + 0.1 * i, 0.05 + 0.1 * j, 0.05, c));
    }
  }
  TraversabilityMap map(OctoMapCarving());
  map.InsertFrame(points, {-0.5, 0.5, 1.0}, 1);
  map.InsertFrame(points, {-0.5, -0.3, 1.0}, 2);
  return map;
}

Rgb8 At(const MapPicture& picture, const Eigen::Vector2d& xy) {
  const Eigen::Vector2i px = picture.PixelOf(xy);
  return picture.image(px.y(), px.x());
}

int Count(const ImageRgb& image, const Rgb8& colour, int u0, int u1, int v0, int v1) {
  int n = 0;
  for (int v = v0; v < v1; ++v) {
    for (int u = u0; u < u1; ++u) n += image(v, u) == colour ? 1 : 0;
  }
  return n;
}

TEST(MapPicture, EachCellIsDrawnInItsClassColourWhereTheMapSays) {
  MapPictureOptions options;
  options.hillshade = false;
  options.grid.fill_min_neighbours = 0;  // keep the unobserved cell unknown
  const MapPicture picture = RenderMapPicture(FloorMap(), options);
  ASSERT_GE(picture.cell_px, 6);
  EXPECT_EQ(At(picture, {0.15, 0.15}), colours::kSemiTraversable);
  EXPECT_EQ(At(picture, {1.65, 0.55}), colours::kNonTraversable);
  EXPECT_EQ(At(picture, {1.05, 0.25}), colours::kTraversable);
  EXPECT_EQ(At(picture, {1.95, 0.95}), colours::kTraversable);  // x right, y up

  // The unobserved cell is hatched: its own colour and the hatch, never the background.
  const Eigen::Vector2i hole = picture.PixelOf({0.5, 0.8});  // the cell's top-left corner
  const int cell = picture.cell_px;
  const int unknown = Count(picture.image, colours::kUnknown, hole.x(), hole.x() + cell, hole.y(), hole.y() + cell);
  const int hatch = Count(picture.image, colours::kUnknownHatch, hole.x(), hole.x() + cell, hole.y(), hole.y() + cell);
  EXPECT_GT(unknown, 0);
  EXPECT_GT(hatch, 0);
  EXPECT_EQ(unknown + hatch, cell * cell);
  EXPECT_EQ(picture.image(0, picture.image.width() - 1), colours::kBackground);
}

TEST(MapPicture, TheRegionHoldsTheWholePathAndThePathIsDrawnOverTheCells) {
  const MapPicture picture = RenderMapPicture(FloorMap());
  // The default region: the surface [0, 2] x [0, 1] and a metre around each path point.
  EXPECT_LE(picture.grid.origin.x(), -1.5 + 1e-9);
  EXPECT_LE(picture.grid.origin.y(), -1.3 + 1e-9);
  EXPECT_GE(picture.grid.origin.x() + picture.grid.width() * picture.grid.resolution_m, 2.0 - 1e-9);
  EXPECT_EQ(At(picture, {-0.5, 0.1}), colours::kPath);     // the line between the two origins
  EXPECT_EQ(At(picture, {-0.5, 0.5}), colours::kPathHalo);  // the start: a ring with a light centre
  EXPECT_EQ(At(picture, {-0.5, -0.3}), colours::kPath);    // the end: a dark square
}

TEST(MapPicture, ReliefShadesSlopesFacingTheLightBrighterAndLeavesLevelGroundAsItIs) {
  // Traversable ground rising 45 deg towards +x (facing the light from -x) for x < 1, level
  // beyond, and falling 45 deg for x in [2, 3).
  std::vector<ClassifiedPoint> points;
  for (int i = 0; i < 30; ++i) {
    const double x = 0.05 + 0.1 * i;
    const double z = x < 1.0 ? x : (x < 2.0 ? 1.05 : 1.05 - (x - 2.0) - 0.1);
    for (int j = 0; j < 10; ++j) points.push_back(Pt(x, 0.05 + 0.1 * j, z, TravClass::kTraversable));
  }
  TraversabilityMap map(OctoMapCarving());
  map.InsertFrame(points, {1.5, 0.5, 4.0}, 1);
  const MapPicture shaded = RenderMapPicture(map);
  EXPECT_GT(At(shaded, {0.45, 0.55}).g, colours::kTraversable.g + 10);  // facing the light
  EXPECT_EQ(At(shaded, {1.55, 0.55}), colours::kTraversable);           // level
  EXPECT_LT(At(shaded, {2.55, 0.55}).g, colours::kTraversable.g - 10);  // facing away
  MapPictureOptions flat;
  flat.hillshade = false;
  EXPECT_EQ(At(RenderMapPicture(map, flat), {0.45, 0.55}), colours::kTraversable);
}

TEST(MapPicture, ALargeMapIsCoarsenedToTheCellLimit) {
  MapPictureOptions options;
  options.max_cells = 100;
  options.grid.region = Eigen::AlignedBox2d(Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(30.0, 10.0));
  const MapPicture picture = RenderMapPicture(FloorMap(), options);
  EXPECT_NEAR(picture.grid.resolution_m, 0.3, 1e-9);  // 300 columns of 0.1 m into at most 100
  EXPECT_EQ(picture.grid.width(), 100);
}

TEST(MapPicture, BadOptionsAndAnEmptyMapAreErrors) {
  MapPictureOptions options;
  options.max_cells = 10;
  EXPECT_THROW(RenderMapPicture(FloorMap(), options), Error);
  options = MapPictureOptions{};
  options.max_map_px = 0;
  EXPECT_THROW(RenderMapPicture(FloorMap(), options), Error);
  EXPECT_THROW(RenderMapPicture(TraversabilityMap(OctoMapCarving())), Error);  // nothing to draw, no region
}

TEST(MapPicture, ExportWritesThePngAndNamesAnUnwritableFile) {
  const testing::TempDir dir;
  const std::string path = dir / "map.png";
  const MapPicture picture = ExportPicture(FloorMap(), path);
  const cv::Mat read = cv::imread(path, cv::IMREAD_COLOR);  // BGR
  ASSERT_EQ(read.cols, picture.image.width());
  ASSERT_EQ(read.rows, picture.image.height());
  const Rgb8 c = picture.image(100, 100);
  EXPECT_EQ(read.at<cv::Vec3b>(100, 100), cv::Vec3b(c.b, c.g, c.r));
  try {
    ExportPicture(FloorMap(), dir / "missing-folder/map.png");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("missing-folder"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ssta
