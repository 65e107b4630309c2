#include <cmath>
#include <filesystem>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "eval_test_helpers.h"
#include "ssta/core/error.h"
#include "ssta/eval/label_evaluator.h"
#include "ssta/io/image_io.h"

namespace ssta {
namespace {

using test::MakeLabels;
using test::TempDir;
using test::WriteLabels;

constexpr double kTol = 1e-12;

// Truth frames a, b, c (under mav0/, as EuRoC nests it); predictions a, b and d.
//   a: truth {1 1 / 2 3}, predicted {1 2 / 2 3}
//   b: truth {1 255 / 3 3}, predicted {1 1 / 0 3}
//   c: truth {2 2 / 2 1}, no prediction
//   d: prediction without truth
class eval_LabelFolders : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string gt = dir_ / "seq/mav0/gt/labels/";
    WriteLabels(gt + "a.png", MakeLabels({{1, 1}, {2, 3}}));
    WriteLabels(gt + "b.png", MakeLabels({{1, 255}, {3, 3}}));
    WriteLabels(gt + "c.png", MakeLabels({{2, 2}, {2, 1}}));
    const std::string pred = dir_ / "out/labels/";
    WriteLabels(pred + "a.png", MakeLabels({{1, 2}, {2, 3}}));
    WriteLabels(pred + "b.png", MakeLabels({{1, 1}, {0, 3}}));
    WriteLabels(pred + "d.png", MakeLabels({{1, 1}, {1, 1}}));
  }
  std::string Seq() const { return dir_ / "seq"; }
  std::string Out() const { return dir_ / "out"; }

  TempDir dir_;
};

TEST_F(eval_LabelFolders, ReportsMissingFramesOnBothSides) {
  const LabelEvalSummary s = EvaluateLabelFolders(Out(), Seq());
  ASSERT_EQ(s.frames.size(), 3u);
  EXPECT_EQ(s.frames[0].name, "a.png");
  EXPECT_EQ(s.frames[2].name, "c.png");
  EXPECT_TRUE(s.frames[2].prediction_missing);
  EXPECT_EQ(s.missing_prediction, std::vector<std::string>{"c.png"});
  EXPECT_EQ(s.missing_truth, std::vector<std::string>{"d.png"});
  const std::string report = s.BriefReport();
  EXPECT_NE(report.find("missing prediction: c.png"), std::string::npos) << report;
  EXPECT_NE(report.find("missing truth: d.png"), std::string::npos) << report;
}

TEST_F(eval_LabelFolders, MissingPredictionScoredAsUnknownByDefault) {
  const LabelEvalSummary s = EvaluateLabelFolders(Out(), Seq());
  const ConfusionMatrix& m = s.total;
  EXPECT_EQ(m.Scored(), 11);
  EXPECT_EQ(m.Count(2, 0), 3);  // frame c
  EXPECT_EQ(m.Count(1, 0), 1);  // frame c
  EXPECT_EQ(m.dont_care(), 1);
  EXPECT_NEAR(m.Accuracy(), 5.0 / 11.0, kTol);
  EXPECT_NEAR(m.Coverage(), 6.0 / 11.0, kTol);
  EXPECT_NEAR(m.Iou(TravClass::kTraversable), 1.0 / 2.0, kTol);
  EXPECT_NEAR(m.Iou(TravClass::kSemiTraversable), 1.0 / 5.0, kTol);
  EXPECT_NEAR(m.Iou(TravClass::kNonTraversable), 2.0 / 3.0, kTol);
  EXPECT_NEAR(m.MeanIou(), 41.0 / 90.0, kTol);
  // Per frame: a has 3 of 4 right.
  EXPECT_NEAR(s.frames[0].matrix.Accuracy(), 3.0 / 4.0, kTol);
  EXPECT_NEAR(s.frames[2].matrix.Coverage(), 0.0, kTol);
}

TEST_F(eval_LabelFolders, SkipPolicyLeavesMissingFramesOutOfTheScores) {
  LabelEvalOptions options;
  options.missing_prediction = MissingPrediction::kSkip;
  const LabelEvalSummary s = EvaluateLabelFolders(Out(), Seq(), options);
  const ConfusionMatrix& m = s.total;
  EXPECT_EQ(s.missing_prediction.size(), 1u);  // still reported
  EXPECT_EQ(m.Scored(), 7);
  EXPECT_NEAR(m.Accuracy(), 5.0 / 7.0, kTol);
  EXPECT_NEAR(m.Coverage(), 6.0 / 7.0, kTol);
  EXPECT_NEAR(m.MeanIou(), 11.0 / 18.0, kTol);
}

TEST_F(eval_LabelFolders, AcceptsAFolderOfPngsDirectly) {
  const LabelEvalSummary s = EvaluateLabelFolders(dir_ / "out/labels", Seq());
  EXPECT_EQ(s.total.Scored(), 11);
  EXPECT_EQ(s.missing_truth, std::vector<std::string>{"d.png"});
}

TEST_F(eval_LabelFolders, SizeMismatchNamesTheFile) {
  WriteLabels(dir_ / "out/labels/b.png", ImageU8(3, 2, 1));
  try {
    EvaluateLabelFolders(Out(), Seq());
    FAIL() << "expected ssta::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("b.png: size 3x2"), std::string::npos) << e.what();
  }
}

TEST_F(eval_LabelFolders, UnknownClassValueInPredictionNamesTheFile) {
  WriteLabels(dir_ / "out/labels/a.png", MakeLabels({{1, 1}, {5, 1}}));
  try {
    EvaluateLabelFolders(Out(), Seq());
    FAIL() << "expected ssta::Error";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("a.png: value 5 at (v 1, u 0)"), std::string::npos) << message;
  }
}

TEST_F(eval_LabelFolders, MissingGroundTruthIsAnError) {
  EXPECT_THROW(EvaluateLabelFolders(Out(), dir_ / "nowhere"), Error);
  EXPECT_THROW(EvaluateLabelFolders(dir_ / "no_prediction", Seq()), Error);
}

TEST_F(eval_LabelFolders, JsonHoldsTotalsMissingFramesAndPerFrameMetrics) {
  const std::string json = EvaluateLabelFolders(Out(), Seq()).ToJson();
  EXPECT_NE(json.find("\"kind\": \"labels\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"frames_truth\": 3"), std::string::npos) << json;
  EXPECT_NE(json.find("\"missing_prediction\": [\n    \"c.png\"\n  ]"), std::string::npos) << json;
  EXPECT_NE(json.find("\"missing_truth\": [\n    \"d.png\"\n  ]"), std::string::npos) << json;
  EXPECT_NE(json.find("\"scored\": 11"), std::string::npos) << json;
  EXPECT_NE(json.find("\"accuracy\": 0.75"), std::string::npos) << json;  // frame a
  EXPECT_NE(json.find("\"name\": \"c.png\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"prediction_missing\": true"), std::string::npos) << json;
  // Frame c has no verdicts: its decided accuracy is 0/0, written as null.
  EXPECT_NE(json.find("\"decided_accuracy\": null"), std::string::npos) << json;
}

cv::Vec3b PixelRgb(const cv::Mat& bgr, int v, int u) {
  const cv::Vec3b p = bgr.at<cv::Vec3b>(v, u);
  return {p[2], p[1], p[0]};
}

TEST_F(eval_LabelFolders, WritesSideBySidePicturesInClassColours) {
  LabelEvalOptions options;
  options.pictures_dir = dir_ / "pictures";
  EvaluateLabelFolders(Out(), Seq(), options);
  EXPECT_TRUE(std::filesystem::exists(dir_ / "pictures/b.png"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "pictures/c.png"));  // nothing to compare
  const cv::Mat picture = cv::imread(dir_ / "pictures/a.png", cv::IMREAD_COLOR);
  ASSERT_FALSE(picture.empty());
  // Layout: 18 px title band, panels 4 px apart starting at u = 4, 4 px gap, 22 px legend.
  EXPECT_EQ(picture.rows, 18 + 2 + 4 + 22);
  constexpr int kTop = 18;
  const int truth_u = 4, pred_u = 4 + 2 + 4, errors_u = pred_u + 2 + 4;
  EXPECT_EQ(PixelRgb(picture, kTop + 0, truth_u + 1), cv::Vec3b(0, 255, 0));    // truth 1
  EXPECT_EQ(PixelRgb(picture, kTop + 1, truth_u + 1), cv::Vec3b(255, 0, 0));    // truth 3
  EXPECT_EQ(PixelRgb(picture, kTop + 0, pred_u + 1), cv::Vec3b(0, 0, 255));     // predicted 2
  EXPECT_EQ(PixelRgb(picture, kTop + 0, errors_u + 1), cv::Vec3b(255, 0, 255)); // wrong
  EXPECT_EQ(PixelRgb(picture, kTop + 0, errors_u + 0), cv::Vec3b(64, 64, 64));  // right
}

TEST(eval_ComparisonPicture, ShowsDontCareWhiteAndNoVerdictOrange) {
  const ImageRgb picture = MakeComparisonPicture(MakeLabels({{255, 1}}), MakeLabels({{1, 4}}));
  EXPECT_EQ(picture(18, 4), (Rgb8{255, 255, 255}));        // truth don't care
  EXPECT_EQ(picture(18, 4 + 2 + 4 + 1), (Rgb8{128, 128, 128}));  // predicted undecided
  EXPECT_EQ(picture(18, 4 + 2 * 6 + 1), (Rgb8{255, 165, 0}));    // no verdict on truth 1
}

}  // namespace
}  // namespace ssta

namespace ssta {
namespace {

TEST(eval_LabelFoldersEdges, EmptyFoldersAreErrorsNotScores) {
  TempDir dir;
  WriteLabels(dir / "seq/gt/labels/a.png", MakeLabels({{1}}));
  std::filesystem::create_directories(dir / "out/labels");
  try {
    EvaluateLabelFolders(dir / "out", dir / "seq");
    FAIL() << "expected ssta::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no label PNGs"), std::string::npos) << e.what();
  }
  std::filesystem::create_directories(dir / "seq2/gt/labels");
  EXPECT_THROW(EvaluateLabelFolders(dir / "seq/gt/labels", dir / "seq2"), Error);
}

TEST(eval_LabelFoldersEdges, AcceptsTheGtFolderItselfAndReportsProgressAndWorstFrames) {
  TempDir dir;
  WriteLabels(dir / "seq/gt/labels/a.png", MakeLabels({{1, 1}}));
  WriteLabels(dir / "seq/gt/labels/b.png", MakeLabels({{1, 1}}));
  WriteLabels(dir / "out/a.png", MakeLabels({{1, 1}}));
  WriteLabels(dir / "out/b.png", MakeLabels({{1, 3}}));
  LabelEvalOptions options;
  std::vector<std::pair<int, int>> calls;
  options.progress = [&calls](int done, int total) { calls.emplace_back(done, total); };
  const LabelEvalSummary s = EvaluateLabelFolders(dir / "out", dir / "seq/gt/", options);
  EXPECT_EQ(calls, (std::vector<std::pair<int, int>>{{1, 2}, {2, 2}}));
  const std::string report = s.BriefReport();
  EXPECT_NE(report.find("worst frames by accuracy: b.png (0.500) a.png (1.000)"), std::string::npos)
      << report;
}

// Depth bands from the true disparity and the rendered rig: f b = 100 px x 0.1 m = 10 px m, so a
// true disparity of 4 px is 2.5 m away, 1.25 px 8 m and 0.5 px 20 m; a pixel without one is left
// out of the bands (not of the totals).
TEST(eval_LabelFoldersEdges, ScoresPixelsInBandsOfTheirTrueDepth) {
  TempDir dir;
  //              2.5 m  2.5 m  8 m  8 m  20 m  none
  // truth           1      3    3    1     3     3
  // predicted       1      3    1    3     1     1
  WriteLabels(dir / "seq/gt/labels/a.png", MakeLabels({{1, 3, 3, 1, 3, 3}}));
  WriteLabels(dir / "out/labels/a.png", MakeLabels({{1, 3, 1, 3, 1, 1}}));
  ImageU16 disparity(6, 1, 0);
  const double d[] = {4.0, 4.0, 1.25, 1.25, 0.5, 0.0};
  for (int u = 0; u < 6; ++u) disparity(0, u) = static_cast<std::uint16_t>(std::lround(d[u] * 256.0));
  std::filesystem::create_directories(dir / "seq/gt/disparity");
  WriteImage(disparity, dir / "seq/gt/disparity/a.png");
  // Without the rig there are no depths.
  EXPECT_TRUE(EvaluateLabelFolders(dir / "out", dir / "seq").by_depth.empty());
  test::WriteText(dir / "seq/gt/rig.yaml", "scene: yard\nfocal_px: 100\nbaseline_m: 0.1\n");
  const LabelEvalSummary s = EvaluateLabelFolders(dir / "out", dir / "seq");
  EXPECT_EQ(s.total.Scored(), 6);
  ASSERT_EQ(s.by_depth.size(), 5u);  // 0-5, 5-10, 10-15, 15-20, 20-25 m
  EXPECT_EQ(s.by_depth[0].matrix.Scored(), 2);
  EXPECT_NEAR(s.by_depth[0].matrix.Accuracy(), 1.0, kTol);
  EXPECT_EQ(s.by_depth[1].matrix.Scored(), 2);
  EXPECT_NEAR(s.by_depth[1].matrix.Recall(TravClass::kNonTraversable), 0.0, kTol);
  EXPECT_NEAR(s.by_depth[1].matrix.UnsafeRate(), 1.0, kTol);
  EXPECT_NEAR(s.by_depth[1].matrix.FalselyBlockedRate(), 1.0, kTol);
  EXPECT_EQ(s.by_depth[2].matrix.Scored() + s.by_depth[3].matrix.Scored(), 0);
  EXPECT_EQ(s.by_depth[4].matrix.Scored(), 1);
  EXPECT_NEAR(s.by_depth[4].accuracy_within, 2.0 / 5.0, kTol);
  EXPECT_NE(s.BriefReport().find("by depth from the camera (true disparity, f b = 10 px m)"), std::string::npos)
      << s.BriefReport();
  EXPECT_NE(s.ToJson().find("\"by_depth\""), std::string::npos);
  // No bands when asked for none; a rig without a baseline is named.
  LabelEvalOptions none;
  none.depth_band_m = 0.0;
  EXPECT_TRUE(EvaluateLabelFolders(dir / "out", dir / "seq", none).by_depth.empty());
  test::WriteText(dir / "seq/gt/rig.yaml", "focal_px: 100\n");
  try {
    EvaluateLabelFolders(dir / "out", dir / "seq");
    FAIL() << "a rig without baseline_m was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("rig.yaml"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("baseline_m"), std::string::npos) << e.what();
  }
}

TEST(eval_LabelFoldersEdges, OptionsValidation) {
  TempDir dir;
  test::WriteText(dir / "file", "x");
  LabelEvalOptions options;
  std::string error;
  EXPECT_TRUE(options.IsValid(&error));
  options.pictures_dir = dir / "file";
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("pictures_dir"), std::string::npos) << error;
  options.pictures_dir.clear();
  options.worst_frames_listed = -1;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("worst_frames_listed"), std::string::npos) << error;
  options.worst_frames_listed = 5;
  options.depth_band_m = -1.0;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("depth_band_m"), std::string::npos) << error;
}

}  // namespace
}  // namespace ssta
