#include <cmath>

#include <gtest/gtest.h>

#include "eval_test_helpers.h"
#include "ssta/core/error.h"
#include "ssta/eval/class_grid.h"
#include "ssta/eval/grid_evaluator.h"

namespace ssta {
namespace {

using test::GridYaml;
using test::MakeLabels;
using test::TempDir;
using test::WriteLabels;
using test::WriteText;

constexpr double kTol = 1e-12;

ClassGrid MakeGrid(const ImageU8& classes, double resolution, double x0, double y0,
                   const std::string& source) {
  ClassGrid grid;
  grid.classes = classes;
  grid.resolution_m = resolution;
  grid.origin_m = {x0, y0};
  grid.source = source;
  return grid;
}

// 3 x 2 cells of 1 m, lower-left corner (10, 20): row 0 spans y in [21, 22), row 1 y in [20, 21).
ClassGrid AsymmetricGrid() { return MakeGrid(MakeLabels({{1, 2, 3}, {3, 3, 1}}), 1.0, 10.0, 20.0, "g"); }

TEST(eval_ClassGrid, RowZeroHoldsTheLargestY) {
  const ClassGrid grid = AsymmetricGrid();
  EXPECT_EQ(grid.ClassAt({10.5, 21.5}), 1);  // top-left
  EXPECT_EQ(grid.ClassAt({12.5, 21.5}), 3);  // top-right
  EXPECT_EQ(grid.ClassAt({10.5, 20.5}), 3);  // bottom-left (the origin cell)
  EXPECT_EQ(grid.ClassAt({12.5, 20.5}), 1);  // bottom-right
  const Eigen::Vector2d centre = grid.CellCentre({0, 1});
  EXPECT_NEAR(centre.x(), 11.5, kTol);
  EXPECT_NEAR(centre.y(), 21.5, kTol);
}

TEST(eval_ClassGrid, OutsideIsUnknownAndBoundsAreHalfOpen) {
  const ClassGrid grid = AsymmetricGrid();
  EXPECT_EQ(grid.ClassAt({9.99, 20.5}), 0);
  EXPECT_EQ(grid.ClassAt({10.5, 22.0}), 0);  // upper edge excluded
  EXPECT_EQ(grid.ClassAt({13.0, 20.5}), 0);  // right edge excluded
  EXPECT_EQ(grid.ClassAt({10.0, 20.0}), 3);  // lower-left corner included
  EXPECT_EQ(grid.ClassAt({11.0, 21.0}), 2);  // shared corner: larger x, larger y
  EXPECT_FALSE(grid.CellAt({std::nan(""), 20.5}).has_value());
}

TEST(eval_ClassGrid, ReadsMapServerYamlWithImageRowZeroOnTop) {
  TempDir dir;
  WriteLabels(dir / "map_classes.png", MakeLabels({{1, 2, 3}, {3, 3, 1}}));
  WriteText(dir / "map.yaml", GridYaml("map.pgm", 0.5, -1.0, 2.0) + "mode: trinary\n");
  const ClassGrid grid = ReadClassGrid(dir / "map.yaml", dir / "map_classes.png");
  EXPECT_DOUBLE_EQ(grid.resolution_m, 0.5);
  EXPECT_DOUBLE_EQ(grid.origin_m.x(), -1.0);
  EXPECT_DOUBLE_EQ(grid.origin_m.y(), 2.0);
  EXPECT_EQ(grid.ClassAt({-0.75, 2.75}), 1);  // top-left pixel of the PNG
  EXPECT_EQ(grid.ClassAt({0.25, 2.25}), 1);   // bottom-right pixel of the PNG
  EXPECT_EQ(grid.source, dir / "map_classes.png");
}

TEST(eval_ClassGrid, ATruthGridWithoutTheSeenKeyOfTodaysRendererGetsAWarningNamingItsYaml) {
  TempDir dir;
  const std::filesystem::path gt = dir.path() / "seq" / "gt";
  std::filesystem::create_directories(gt);
  WriteLabels(gt / "grid_classes.png", ImageU8(2, 2, 1));
  WriteText(gt / "grid.yaml", GridYaml("grid_classes.png", 0.1, 0.0, 0.0));
  const ClassGrid old_truth = ReadGroundTruthGrid(dir / "seq");
  EXPECT_EQ(old_truth.seen, "");
  const std::string warning = StaleTruthGridWarning(old_truth);
  EXPECT_NE(warning.find((gt / "grid.yaml").string()), std::string::npos) << warning;
  EXPECT_NE(warning.find("render the sequence again"), std::string::npos) << warning;
  WriteText(gt / "grid.yaml", GridYaml("grid_classes.png", 0.1, 0.0, 0.0) + "seen: both_cameras\n");
  EXPECT_EQ(StaleTruthGridWarning(ReadGroundTruthGrid(dir / "seq")), "");
  WriteText(gt / "grid.yaml", GridYaml("grid_classes.png", 0.1, 0.0, 0.0) + "seen: labelled_pixels\n");
  EXPECT_NE(StaleTruthGridWarning(ReadGroundTruthGrid(dir / "seq")), "");
}

TEST(eval_ClassGrid, BadYamlNamesFileAndKey) {
  TempDir dir;
  WriteLabels(dir / "m_classes.png", ImageU8(2, 2, 1));
  auto expect_error = [&](const std::string& yaml, const std::string& fragment) {
    WriteText(dir / "m.yaml", yaml);
    try {
      ReadClassGrid(dir / "m.yaml", dir / "m_classes.png");
      ADD_FAILURE() << "expected ssta::Error for: " << yaml;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
  };
  expect_error("resolution: 0\norigin: [0, 0, 0]\n", "m.yaml: resolution");
  expect_error("origin: [0, 0, 0]\n", "m.yaml: resolution: missing key");
  expect_error("resolution: 0.1\norigin: [0, 0, 0.5]\n", "m.yaml: origin: a rotated grid");
  expect_error("resolution: 0.1\norigin: [0]\n", "m.yaml: origin: expected");
  expect_error("resolution: 0.1\norigin: [0, zero, 0]\n", "m.yaml: origin: wrong type");
  expect_error("resolution: [0.1\n", "m.yaml:");
  EXPECT_THROW(ReadClassGrid(dir / "none.yaml", dir / "m_classes.png"), Error);
}

// Truth: 4 x 2 cells of 1 m at (0, 0), row 0 = y in [1, 2):
//   1 1 2 2
//   1 3 3 255
// Prediction: 2 x 1 cells of 2 m at (1, 0), covering x in [1, 5): classes 1 | 3.
// Truth centres x = 0.5 (outside: 0), 1.5 and 2.5 (cell 0: 1), 3.5 (cell 1: 3):
//   (1,0) (1,1) (2,1) (2,3)
//   (1,0) (3,1) (3,1) (255,3)
void ExpectShiftedCase(const ConfusionMatrix& m) {
  EXPECT_EQ(m.Count(1, 0), 2);
  EXPECT_EQ(m.Count(1, 1), 1);
  EXPECT_EQ(m.Count(2, 1), 1);
  EXPECT_EQ(m.Count(2, 3), 1);
  EXPECT_EQ(m.Count(3, 1), 2);
  EXPECT_EQ(m.dont_care(), 1);
  EXPECT_EQ(m.Scored(), 7);
  EXPECT_NEAR(m.Accuracy(), 1.0 / 7.0, kTol);
  EXPECT_NEAR(m.Coverage(), 5.0 / 7.0, kTol);
  EXPECT_NEAR(m.Iou(TravClass::kTraversable), 1.0 / 6.0, kTol);
  EXPECT_NEAR(m.Iou(TravClass::kSemiTraversable), 0.0, kTol);
  EXPECT_NEAR(m.Iou(TravClass::kNonTraversable), 0.0, kTol);
  EXPECT_NEAR(m.MeanIou(), 1.0 / 18.0, kTol);
}

TEST(eval_ScoreGrid, ShiftedCoarserPredictionScoresAsComputedByHand) {
  const ClassGrid truth = MakeGrid(MakeLabels({{1, 1, 2, 2}, {1, 3, 3, 255}}), 1.0, 0.0, 0.0, "t");
  const ClassGrid predicted = MakeGrid(MakeLabels({{1, 3}}), 2.0, 1.0, 0.0, "p");
  ExpectShiftedCase(ScoreGrid(truth, predicted));
}

TEST(eval_ScoreGrid, FinerPredictionIsSampledAtTruthCentres) {
  // Truth 1 x 2 cells of 1 m: top (y in [1, 2)) non-traversable, bottom traversable.
  const ClassGrid truth = MakeGrid(MakeLabels({{3}, {1}}), 1.0, 0.0, 0.0, "t");
  // Prediction 4 x 4 cells of 0.5 m from (-0.5, 0): rows from the top y in [1.5, 2), [1, 1.5), ...
  // The truth centres (0.5, 1.5) and (0.5, 0.5) fall in column 2, rows 0 and 2.
  const ClassGrid predicted = MakeGrid(
      MakeLabels({{0, 0, 3, 0}, {0, 0, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 0}}), 0.5, -0.5, 0.0, "p");
  const ConfusionMatrix m = ScoreGrid(truth, predicted);
  EXPECT_DOUBLE_EQ(m.Accuracy(), 1.0);
  EXPECT_DOUBLE_EQ(m.MeanIou(), 1.0);
  // The same prediction upside down gets both wrong: the row convention matters.
  const ClassGrid flipped = MakeGrid(
      MakeLabels({{0, 0, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 0}, {0, 0, 3, 0}}), 0.5, -0.5, 0.0, "p");
  EXPECT_DOUBLE_EQ(ScoreGrid(truth, flipped).Accuracy(), 0.0);
}

TEST(eval_ScoreGrid, ResampledPredictionAndPictureLiveOnTheTruthGrid) {
  const ClassGrid truth = MakeGrid(MakeLabels({{1, 1, 2, 2}, {1, 3, 3, 255}}), 1.0, 0.0, 0.0, "t");
  const ClassGrid predicted = MakeGrid(MakeLabels({{1, 3}}), 2.0, 1.0, 0.0, "p");
  const ImageU8 resampled = ResampleToGrid(predicted, truth);
  const ImageU8 expected = MakeLabels({{0, 1, 1, 3}, {0, 1, 1, 3}});
  ASSERT_EQ(resampled.width(), 4);
  ASSERT_EQ(resampled.height(), 2);
  for (std::size_t i = 0; i < expected.size(); ++i) EXPECT_EQ(resampled[i], expected[i]) << i;
  // 2 rows enlarged to 180 px each; truth cell (0, 0) is traversable green at the panel start.
  const ImageRgb picture = MakeGridComparisonPicture(truth, predicted);
  EXPECT_EQ(picture.height(), 18 + 360 + 4 + 22);
  EXPECT_EQ(picture(18 + 179, 4 + 179), (Rgb8{0, 255, 0}));
  EXPECT_EQ(picture(18 + 180, 4 + 180), (Rgb8{255, 0, 0}));  // truth cell (1, 1): non-traversable
}

TEST(eval_ScoreGrid, PictureIsCroppedToTheScoredCellsAndAMargin) {
  // 200 x 100 cells of don't-care with a 4 x 3 block of truth at columns 50..53, rows 40..42;
  // the prediction marks the block's first cell non-traversable.
  ImageU8 t(200, 100, 255), p(200, 100, 0);
  for (int v = 40; v <= 42; ++v) {
    for (int u = 50; u <= 53; ++u) t(v, u) = 1;
  }
  p(40, 50) = 3;
  const ClassGrid truth = MakeGrid(t, 1.0, 0.0, 0.0, "t");
  const ClassGrid predicted = MakeGrid(p, 1.0, 0.0, 0.0, "p");
  const ImageRgb picture = MakeGridComparisonPicture(truth, predicted);
  // Crop: columns 40..63, rows 30..52 (24 x 23 cells); scale ceil(360 / 23) = 16 px per cell.
  const int scale = 16, panel_w = 24 * scale;
  EXPECT_EQ(picture.height(), 18 + 23 * scale + 4 + 22);
  EXPECT_EQ(picture.width(), 3 * panel_w + 4 * 4);
  const int y = 18 + 10 * scale, x_truth = 4 + 10 * scale, x_pred = x_truth + panel_w + 4;
  EXPECT_EQ(picture(y, x_truth), (Rgb8{0, 255, 0}));         // first truth cell
  EXPECT_EQ(picture(y - 1, x_truth), (Rgb8{255, 255, 255}));  // the margin: don't care
  EXPECT_EQ(picture(y, x_pred), (Rgb8{255, 0, 0}));           // its prediction
  EXPECT_EQ(picture(y, x_pred + panel_w + 4), (Rgb8{255, 0, 255}));  // errors panel: wrong
}

TEST(eval_ScoreGrid, RejectsPredictedValuesAboveFour) {
  const ClassGrid truth = MakeGrid(ImageU8(2, 2, 1), 1.0, 0.0, 0.0, "gt/grid_classes.png");
  const ClassGrid predicted = MakeGrid(MakeLabels({{1, 7}}), 1.0, 0.0, 0.0, "map_classes.png");
  try {
    ScoreGrid(truth, predicted);
    FAIL() << "expected ssta::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("map_classes.png: value 7"), std::string::npos) << e.what();
  }
}

// One row of ten 1 m cells along x from the origin: centres (0.5, 0.5) .. (9.5, 0.5).
ClassGrid RowOfTen(std::uint8_t first_four, std::uint8_t rest, const std::string& source) {
  ImageU8 classes(10, 1, rest);
  for (int u = 0; u < 4; ++u) classes(0, u) = first_four;
  return MakeGrid(classes, 1.0, 0.0, 0.0, source);
}

TEST(eval_ScoreGridByDistance, BandsHoldTheCellsAtTheirDistanceFromAPoint) {
  // From (0, 0.5) the centres lie 0.5, 1.5, ..., 9.5 m away: two per 2 m band. The prediction
  // is right on the first four cells and wrong on the rest.
  const ClassGrid truth = RowOfTen(1, 1, "t");
  const ClassGrid predicted = RowOfTen(1, 3, "p");
  const std::vector<DistanceBand> bands = ScoreGridByDistance(truth, predicted, {{0.0, 0.5}}, 2.0);
  ASSERT_EQ(bands.size(), 5u);
  const double accuracy[] = {1.0, 1.0, 0.0, 0.0, 0.0};
  for (std::size_t k = 0; k < bands.size(); ++k) {
    EXPECT_DOUBLE_EQ(bands[k].from_m, 2.0 * k);
    EXPECT_DOUBLE_EQ(bands[k].to_m, 2.0 * k + 2.0);
    EXPECT_EQ(bands[k].matrix.Scored(), 2) << k;
    EXPECT_DOUBLE_EQ(bands[k].matrix.Accuracy(), accuracy[k]) << k;
  }
  EXPECT_EQ(bands[2].matrix.Count(1, 3), 2);
  // Bands of 3 m: 0.5 1.5 2.5 | 3.5 4.5 5.5 | 6.5 7.5 8.5 | 9.5.
  const std::vector<DistanceBand> wide = ScoreGridByDistance(truth, predicted, {{0.0, 0.5}}, 3.0);
  ASSERT_EQ(wide.size(), 4u);
  EXPECT_EQ(wide[0].matrix.Scored(), 3);
  EXPECT_EQ(wide[1].matrix.Correct(), 1);
  EXPECT_EQ(wide[3].matrix.Scored(), 1);
}

TEST(eval_ScoreGridByDistance, DistanceIsToThePolylineAndEmptyBandsStay) {
  // The path runs down x = 0 from y = 5 to y = -5 and on to (2, -5); truth cells of 1 m:
  //   centre (0.5, 0.5): 0.5 m from the first leg -> band 0
  //   centre (6.5, 0.5): 6.5 m from the first leg -> band 3 (bands 1 and 2 empty)
  //   centre (2.5, -7.5): 2.55 m from the end (2, -5) of the second leg -> band 1
  ImageU8 classes(7, 9, 255);  // 7 x 9 cells of 1 m from (0, -8): y up to 1
  const ClassGrid empty = MakeGrid(classes, 1.0, 0.0, -8.0, "t");
  const GridCell a = *empty.CellAt({0.5, 0.5}), b = *empty.CellAt({6.5, 0.5}), c = *empty.CellAt({2.5, -7.5});
  classes(a.row, a.col) = 1;
  classes(b.row, b.col) = 3;
  classes(c.row, c.col) = 2;
  const ClassGrid truth = MakeGrid(classes, 1.0, 0.0, -8.0, "t");
  const ClassGrid predicted = MakeGrid(ImageU8(7, 9, 1), 1.0, 0.0, -8.0, "p");
  const std::vector<DistanceBand> bands =
      ScoreGridByDistance(truth, predicted, {{0.0, 5.0}, {0.0, -5.0}, {2.0, -5.0}}, 2.0);
  ASSERT_EQ(bands.size(), 4u);
  EXPECT_EQ(bands[0].matrix.Count(1, 1), 1);
  EXPECT_EQ(bands[0].matrix.Scored(), 1);
  EXPECT_EQ(bands[1].matrix.Count(2, 1), 1);
  EXPECT_EQ(bands[1].matrix.Scored(), 1);
  EXPECT_EQ(bands[2].matrix.Scored(), 0);
  EXPECT_EQ(bands[3].matrix.Count(3, 1), 1);
  EXPECT_EQ(bands[3].matrix.Scored(), 1);
}

TEST(eval_ScoreGridByDistance, BadPathOrBandIsAnError) {
  const ClassGrid grid = RowOfTen(1, 1, "t");
  EXPECT_THROW(ScoreGridByDistance(grid, grid, {}, 2.0), Error);
  EXPECT_THROW(ScoreGridByDistance(grid, grid, {{0.0, std::nan("")}}, 2.0), Error);
  EXPECT_THROW(ScoreGridByDistance(grid, grid, {{0.0, 0.0}}, 0.0), Error);
  EXPECT_THROW(ScoreGridByDistance(grid, grid, {{0.0, 0.0}}, std::nan("")), Error);
  // A path 100 km away is not this grid's (and would make 50000 bands).
  EXPECT_THROW(ScoreGridByDistance(grid, grid, {{1e5, 0.0}}, 2.0), Error);
  EXPECT_EQ(ScoreGridByDistance(grid, grid, {{1e4, 0.0}}, 2.0).size(), 5000u);  // 9990.5..9999.5 m: bands to 4999
}

TEST(eval_EvaluateExportedGrid, ScoresByDistanceFromTheSequencesPoses) {
  TempDir dir;
  WriteLabels(dir / "seq/gt/grid_classes.png", RowOfTen(1, 1, "t").classes);
  WriteText(dir / "seq/gt/grid.yaml", GridYaml("grid_classes.png", 1.0, 0.0, 0.0));
  WriteLabels(dir / "map_classes.png", RowOfTen(1, 3, "p").classes);
  WriteText(dir / "map.yaml", GridYaml("map.pgm", 1.0, 0.0, 0.0));
  // Without poses there are no bands.
  EXPECT_TRUE(EvaluateExportedGrid(dir / "map", dir / "seq").by_distance.empty());
  // The vehicle stands at (0, 0.5) for three poses: as from one point above.
  WriteText(dir / "seq/pose0/data.csv",
            "#timestamp [ns],p_x [m],p_y [m],p_z [m],q_w [],q_x [],q_y [],q_z []\n"
            "1000,0,0.5,0.2,1,0,0,0\n2000,0,0.5,0.2,1,0,0,0\n3000,0,0.5,0.2,1,0,0,0\n");
  const GridEvalSummary s = EvaluateExportedGrid(dir / "map", dir / "seq");
  ASSERT_EQ(s.by_distance.size(), 5u);
  EXPECT_DOUBLE_EQ(s.by_distance[1].matrix.Accuracy(), 1.0);
  EXPECT_DOUBLE_EQ(s.by_distance[2].matrix.Accuracy(), 0.0);
  const std::string json = s.ToJson();
  EXPECT_NE(json.find("\"by_distance_from_path\""), std::string::npos) << json;
  // Cumulative: 4 of the 6 cells within 6 m are right.
  EXPECT_NE(json.find("\"accuracy_within\": 0.6666666666666666"), std::string::npos) << json;
  const std::string report = s.BriefReport();
  EXPECT_NE(report.find("by distance from the path"), std::string::npos) << report;
  EXPECT_NE(report.find("0.667"), std::string::npos) << report;
  // A pose file that is there but broken is an error naming it.
  WriteText(dir / "seq/pose0/data.csv", "1000,0,0.5\n");
  try {
    EvaluateExportedGrid(dir / "map", dir / "seq");
    FAIL() << "expected ssta::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("pose0/data.csv"), std::string::npos) << e.what();
  }
}

TEST(eval_EvaluateExportedGrid, ScoresExportAgainstSequenceGroundTruth) {
  TempDir dir;
  WriteLabels(dir / "seq/gt/grid_classes.png", MakeLabels({{1, 1, 2, 2}, {1, 3, 3, 255}}));
  WriteText(dir / "seq/gt/grid.yaml", GridYaml("grid_classes.png", 1.0, 0.0, 0.0));
  WriteLabels(dir / "map_classes.png", MakeLabels({{1, 3}}));
  WriteText(dir / "map.yaml", GridYaml("map.pgm", 2.0, 1.0, 0.0));
  const GridEvalSummary s = EvaluateExportedGrid(dir / "map", dir / "seq");
  ExpectShiftedCase(s.matrix);
  EXPECT_EQ(s.scored_cells_outside_prediction, 2);
  const std::string json = s.ToJson();
  EXPECT_NE(json.find("\"kind\": \"grid\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"scored_cells_outside_prediction\": 2"), std::string::npos) << json;
  EXPECT_NE(json.find("\"origin\": [1, 0, 0]"), std::string::npos) << json;
  EXPECT_NE(json.find("\"confusion\": [\n      [0, 0, 0, 0, 0],\n      [2, 1, 0, 0, 0],"),
            std::string::npos)
      << json;
  EXPECT_NE(s.BriefReport().find("outside the predicted grid (scored as unknown): 2"),
            std::string::npos);
}

TEST(eval_EvaluateExportedGrid, MissingFilesAreNamed) {
  TempDir dir;
  WriteLabels(dir / "seq/mav0/gt/grid_classes.png", ImageU8(2, 2, 1));
  WriteText(dir / "seq/mav0/gt/grid.yaml", GridYaml("grid_classes.png", 1.0, 0.0, 0.0));
  WriteText(dir / "map.yaml", GridYaml("map.pgm", 1.0, 0.0, 0.0));
  try {
    EvaluateExportedGrid(dir / "map", dir / "seq");
    FAIL() << "expected ssta::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("map_classes.png"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ssta
