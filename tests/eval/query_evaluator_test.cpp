#include <gtest/gtest.h>

#include "eval_test_helpers.h"
#include "ssta/core/error.h"
#include "ssta/eval/class_grid.h"
#include "ssta/eval/query_evaluator.h"

namespace ssta {
namespace {

using test::GridYaml;
using test::MakeLabels;
using test::TempDir;
using test::WriteLabels;
using test::WriteText;

constexpr double kTol = 1e-12;
const char kHeader[] = "x,y,z,class,cost,probability,slope_deg,step_m,observations\n";

// Truth: 4 x 2 cells of 1 m at (0, 0), row 0 = y in [1, 2):
//   1 1 2 2
//   1 3 3 255
void WriteTruth(const TempDir& dir) {
  WriteLabels(dir / "seq/gt/grid_classes.png", MakeLabels({{1, 1, 2, 2}, {1, 3, 3, 255}}));
  WriteText(dir / "seq/gt/grid.yaml", GridYaml("grid_classes.png", 1.0, 0.0, 0.0));
}

TEST(eval_Query, ScoresRowsAgainstTheTruthCellAtXY) {
  TempDir dir;
  WriteTruth(dir);
  WriteText(dir / "q.csv", std::string(kHeader) +
                               "0.5,1.5,0.0,1,0.1,0.9,2.0,0.01,5\n"    // truth 1, right
                               "2.2,1.1,0.3,3,1.0,0.8,40.0,0.3,2\n"   // truth 2, wrong
                               "1.5,0.5,0.0,0,nan,0,nan,nan,0\n"      // truth 3, unknown
                               "3.5,0.5,0.0,2,0.5,0.5,20,0.1,1\n"     // don't care
                               "9.0,0.5,0.0,1,0.1,0.9,2.0,0.01,5\n"   // outside the truth
                               "\r\n"
                               " 0.5 , 0.2 ,0.0, 1 ,0.1,0.9,2.0,0.01,5\r\n");  // truth 1, right
  const QueryEvalSummary s = EvaluateQueryCsv(dir / "q.csv", dir / "seq");
  // The same scores from a truth grid read beforehand (as `ssta eval query` does, to warn first).
  const QueryEvalSummary from_grid = EvaluateQueryCsv(dir / "q.csv", ReadGroundTruthGrid(dir / "seq"));
  EXPECT_EQ(from_grid.ToJson(), s.ToJson());
  EXPECT_EQ(from_grid.prediction, dir / "q.csv");
  EXPECT_EQ(s.rows, 6);
  EXPECT_EQ(s.outside_truth, 1);
  const ConfusionMatrix& m = s.matrix;
  EXPECT_EQ(m.Scored(), 4);
  EXPECT_EQ(m.dont_care(), 1);
  EXPECT_EQ(m.Count(2, 3), 1);
  EXPECT_EQ(m.Count(3, 0), 1);
  EXPECT_NEAR(m.Accuracy(), 2.0 / 4.0, kTol);
  EXPECT_NEAR(m.Coverage(), 3.0 / 4.0, kTol);
  EXPECT_NEAR(m.Iou(TravClass::kTraversable), 1.0, kTol);
  EXPECT_NEAR(m.Iou(TravClass::kSemiTraversable), 0.0, kTol);
  EXPECT_NEAR(m.Iou(TravClass::kNonTraversable), 0.0, kTol);
  EXPECT_NEAR(m.MeanIou(), 1.0 / 3.0, kTol);
  const std::string json = s.ToJson();
  EXPECT_NE(json.find("\"kind\": \"query\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"outside_truth\": 1"), std::string::npos) << json;
}

TEST(eval_Query, ReadsLineNumbersAndColumnsByName) {
  TempDir dir;
  WriteText(dir / "q.csv", "\nclass,y,x\n3,2.5,-1.25\n");
  const auto rows = ReadQueryCsv(dir / "q.csv");
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].line, 3);
  EXPECT_DOUBLE_EQ(rows[0].x_m, -1.25);
  EXPECT_DOUBLE_EQ(rows[0].y_m, 2.5);
  EXPECT_EQ(rows[0].predicted, 3);
}

TEST(eval_Query, MalformedCsvNamesFileAndLine) {
  TempDir dir;
  const std::string path = dir / "q.csv";
  auto expect_error = [&](const std::string& text, const std::string& fragment) {
    WriteText(path, text);
    try {
      ReadQueryCsv(path);
      ADD_FAILURE() << "expected ssta::Error for: " << text;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
  };
  const std::string good = "0.5,1.5,0.0,1,0.1,0.9,2.0,0.01,5\n";
  expect_error(kHeader + good + "abc,1.5,0.0,1,0.1,0.9,2.0,0.01,5\n", path + ":3: column 'x'");
  expect_error(kHeader + good + good + "0.5,1.5,0.0,1\n", path + ":4: expected 9 fields");
  expect_error(kHeader + std::string("0.5,1.5,0.0,7,0.1,0.9,2.0,0.01,5\n"),
               path + ":2: column 'class': '7'");
  expect_error(kHeader + std::string("0.5,1.5,0.0,1.5,0.1,0.9,2.0,0.01,5\n"), path + ":2: column 'class'");
  expect_error(kHeader + std::string("0.5,inf,0.0,1,0.1,0.9,2.0,0.01,5\n"), path + ":2: column 'y'");
  expect_error("a,b,c\n1,2,3\n", path + ":1: header must name");
  expect_error("", path + ":1: empty file");
  EXPECT_THROW(ReadQueryCsv(dir / "missing.csv"), Error);
}

TEST(eval_Query, HeaderOnlyScoresNothing) {
  TempDir dir;
  WriteTruth(dir);
  WriteText(dir / "q.csv", kHeader);
  const QueryEvalSummary s = EvaluateQueryCsv(dir / "q.csv", dir / "seq");
  EXPECT_EQ(s.rows, 0);
  EXPECT_EQ(s.matrix.Scored(), 0);
  EXPECT_NE(s.ToJson().find("\"accuracy\": null"), std::string::npos);
}

}  // namespace
}  // namespace ssta
