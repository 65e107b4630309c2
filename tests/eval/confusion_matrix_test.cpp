#include <cmath>

#include <gtest/gtest.h>

#include "eval_test_helpers.h"
#include "ssta/core/error.h"
#include "ssta/eval/confusion_matrix.h"
#include "ssta/eval/label_evaluator.h"

namespace ssta {
namespace {

using test::MakeLabels;

constexpr double kTol = 1e-12;

// Hand-computed case with every rule in it: don't care, truth 0 and 4 (not scored), predicted 0
// and 4 on scored pixels (wrong, no verdict), and a prediction of 3 on a don't-care pixel (no
// false positive).
//   pairs (truth, predicted): (1,1) (1,1) (1,2) (2,2) | (2,2) (2,0) (3,3) (3,1) |
//                             (255,3) (0,1) (4,1) (1,4)
ConfusionMatrix MixedCase() {
  const ImageU8 truth = MakeLabels({{1, 1, 1, 2}, {2, 2, 3, 3}, {255, 0, 4, 1}});
  const ImageU8 predicted = MakeLabels({{1, 1, 2, 2}, {2, 0, 3, 1}, {3, 1, 1, 4}});
  return ScoreLabels(truth, predicted);
}

TEST(eval_ConfusionMatrix, CountsPairsOfTheHandComputedImage) {
  const ConfusionMatrix m = MixedCase();
  EXPECT_EQ(m.Count(1, 1), 2);
  EXPECT_EQ(m.Count(1, 2), 1);
  EXPECT_EQ(m.Count(1, 4), 1);
  EXPECT_EQ(m.Count(2, 2), 2);
  EXPECT_EQ(m.Count(2, 0), 1);
  EXPECT_EQ(m.Count(3, 3), 1);
  EXPECT_EQ(m.Count(3, 1), 1);
  EXPECT_EQ(m.Count(0, 1), 1);
  EXPECT_EQ(m.Count(4, 1), 1);
  EXPECT_EQ(m.dont_care(), 1);
  std::int64_t total = 0;
  for (int t = 0; t < 5; ++t) total += m.TruthTotal(t);
  EXPECT_EQ(total + m.dont_care(), 12);
}

TEST(eval_ConfusionMatrix, ScoresOnlyTruthOneToThree) {
  const ConfusionMatrix m = MixedCase();
  EXPECT_EQ(m.Scored(), 9);
  EXPECT_EQ(m.Correct(), 5);
  EXPECT_EQ(m.Decided(), 7);  // two scored pixels predicted 0 and 4
  EXPECT_NEAR(m.Accuracy(), 5.0 / 9.0, kTol);
  EXPECT_NEAR(m.Coverage(), 7.0 / 9.0, kTol);
  EXPECT_NEAR(m.DecidedAccuracy(), 5.0 / 7.0, kTol);
}

TEST(eval_ConfusionMatrix, IouCountsOnlyScoredPixels) {
  const ConfusionMatrix m = MixedCase();
  // traversable: TP 2, FN 2 (predicted 2 and 4), FP 1 (truth 3); truth 0/4 predicted 1 ignored.
  EXPECT_NEAR(m.Iou(TravClass::kTraversable), 2.0 / 5.0, kTol);
  // semi: TP 2, FN 1 (predicted 0), FP 1 (truth 1).
  EXPECT_NEAR(m.Iou(TravClass::kSemiTraversable), 2.0 / 4.0, kTol);
  // non: TP 1, FN 1, FP 0 (the 3 on the don't-care pixel is not a false positive).
  EXPECT_NEAR(m.Iou(TravClass::kNonTraversable), 1.0 / 2.0, kTol);
  EXPECT_EQ(m.PresentClasses(), 3);
  EXPECT_NEAR(m.MeanIou(), (0.4 + 0.5 + 0.5) / 3.0, kTol);
}

TEST(eval_ConfusionMatrix, PerfectPredictionScoresOne) {
  const ImageU8 truth = MakeLabels({{1, 2, 3}, {255, 3, 1}});
  // Whatever is predicted on the don't-care pixel does not matter.
  const ImageU8 predicted = MakeLabels({{1, 2, 3}, {0, 3, 1}});
  const ConfusionMatrix m = ScoreLabels(truth, predicted);
  EXPECT_DOUBLE_EQ(m.Accuracy(), 1.0);
  EXPECT_DOUBLE_EQ(m.MeanIou(), 1.0);
  EXPECT_DOUBLE_EQ(m.Coverage(), 1.0);
  EXPECT_EQ(m.Scored(), 5);
}

TEST(eval_ConfusionMatrix, AllTraversablePredictionOfMixedTruth) {
  const ImageU8 truth = MakeLabels({{1, 1, 1}, {2, 2, 3}});
  const ImageU8 predicted(3, 2, 1);
  const ConfusionMatrix m = ScoreLabels(truth, predicted);
  EXPECT_NEAR(m.Iou(TravClass::kTraversable), 3.0 / 6.0, kTol);
  EXPECT_NEAR(m.Iou(TravClass::kSemiTraversable), 0.0, kTol);
  EXPECT_NEAR(m.Iou(TravClass::kNonTraversable), 0.0, kTol);
  EXPECT_NEAR(m.MeanIou(), 1.0 / 6.0, kTol);
  EXPECT_NEAR(m.Accuracy(), 0.5, kTol);
  EXPECT_NEAR(m.Coverage(), 1.0, kTol);
}

TEST(eval_ConfusionMatrix, SafetyFiguresCountWhatAPlannerIsTold) {
  ConfusionMatrix m;
  m.Add(3, 1, 2);   // unsafe: an obstacle answered traversable
  m.Add(3, 2, 1);   // unsafe: answered semi-traversable
  m.Add(3, 3, 5);
  m.Add(3, 0, 2);   // not known: neither unsafe nor blocked
  m.Add(1, 3, 4);   // falsely blocked
  m.Add(2, 3, 1);   // falsely blocked
  m.Add(1, 1, 15);
  m.Add(2, 2, 5);
  m.Add(1, 4, 1);   // undecided: not blocked
  m.Add(255, 3, 7);  // don't care: never counted
  EXPECT_EQ(m.Unsafe(), 3);
  EXPECT_NEAR(m.UnsafeRate(), 3.0 / 10.0, kTol);
  EXPECT_EQ(m.FalselyBlocked(), 5);
  EXPECT_NEAR(m.FalselyBlockedRate(), 5.0 / 26.0, kTol);
  EXPECT_NEAR(m.Recall(TravClass::kNonTraversable), 5.0 / 10.0, kTol);
  EXPECT_NEAR(m.Recall(TravClass::kTraversable), 15.0 / 20.0, kTol);
  EXPECT_NEAR(m.Recall(TravClass::kSemiTraversable), 5.0 / 6.0, kTol);
  EXPECT_TRUE(std::isnan(ConfusionMatrix().UnsafeRate()));
  EXPECT_TRUE(std::isnan(ConfusionMatrix().Recall(TravClass::kTraversable)));
}

TEST(eval_ConfusionMatrix, MeanIouLeavesOutClassesAbsentFromTruthAndPrediction) {
  const ImageU8 truth = MakeLabels({{1, 1, 2, 2}});
  const ImageU8 predicted = MakeLabels({{1, 2, 2, 2}});
  const ConfusionMatrix m = ScoreLabels(truth, predicted);
  EXPECT_FALSE(m.IsPresent(TravClass::kNonTraversable));
  EXPECT_TRUE(std::isnan(m.Iou(TravClass::kNonTraversable)));
  EXPECT_EQ(m.PresentClasses(), 2);
  EXPECT_NEAR(m.MeanIou(), (1.0 / 2.0 + 2.0 / 3.0) / 2.0, kTol);
}

TEST(eval_ConfusionMatrix, ClassPredictedButAbsentFromTruthIsPresentWithIouZero) {
  const ImageU8 truth = MakeLabels({{1, 1}});
  const ImageU8 predicted = MakeLabels({{1, 3}});
  const ConfusionMatrix m = ScoreLabels(truth, predicted);
  EXPECT_TRUE(m.IsPresent(TravClass::kNonTraversable));
  EXPECT_EQ(m.PresentClasses(), 2);
  EXPECT_NEAR(m.MeanIou(), (0.5 + 0.0) / 2.0, kTol);
}

TEST(eval_ConfusionMatrix, PredictionsOnUnscoredPixelsDoNotMakeAClassPresent) {
  // Non-traversable is predicted only where the truth is don't care, unknown or undecided.
  const ImageU8 truth = MakeLabels({{1, 255, 0, 4}});
  const ImageU8 predicted = MakeLabels({{1, 3, 3, 3}});
  const ConfusionMatrix m = ScoreLabels(truth, predicted);
  EXPECT_FALSE(m.IsPresent(TravClass::kNonTraversable));
  EXPECT_EQ(m.PresentClasses(), 1);
  EXPECT_DOUBLE_EQ(m.MeanIou(), 1.0);
  EXPECT_DOUBLE_EQ(m.Accuracy(), 1.0);
}

TEST(eval_ConfusionMatrix, NothingScoredGivesNaN) {
  const ConfusionMatrix m = ScoreLabels(MakeLabels({{255, 0}}), MakeLabels({{1, 1}}));
  EXPECT_EQ(m.Scored(), 0);
  EXPECT_TRUE(std::isnan(m.Accuracy()));
  EXPECT_TRUE(std::isnan(m.Coverage()));
  EXPECT_TRUE(std::isnan(m.MeanIou()));
  EXPECT_EQ(m.PresentClasses(), 0);
}

TEST(eval_ConfusionMatrix, SumIsPixelWeighted) {
  ConfusionMatrix total = ScoreLabels(MakeLabels({{1, 1, 1}}), MakeLabels({{1, 1, 1}}));
  total += ScoreLabels(MakeLabels({{2}}), MakeLabels({{1}}));
  EXPECT_EQ(total.Scored(), 4);
  EXPECT_NEAR(total.Accuracy(), 3.0 / 4.0, kTol);  // not the mean of per-frame 1.0 and 0.0
  EXPECT_NEAR(total.Iou(TravClass::kTraversable), 3.0 / 4.0, kTol);
}

TEST(eval_ConfusionMatrix, AddChecksItsPreconditions) {
  ConfusionMatrix m;
  EXPECT_THROW(m.Add(1, 5), InternalError);
  EXPECT_THROW(m.Add(7, 1), InternalError);
  EXPECT_THROW(m.Iou(TravClass::kUnknown), InternalError);
  m.Add(kDontCare, 1, 3);
  EXPECT_EQ(m.dont_care(), 3);
}

TEST(eval_ScoreLabels, RejectsSizeMismatchNamingThePrediction) {
  try {
    ScoreLabels(ImageU8(4, 3, 1), ImageU8(3, 4, 1), "gt/a.png", "pred/a.png");
    FAIL() << "expected ssta::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("pred/a.png"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("3x4"), std::string::npos) << e.what();
  }
}

TEST(eval_ScoreLabels, RejectsPredictedValuesAboveFourNamingThePixel) {
  const ImageU8 truth(3, 2, 1);
  ImageU8 predicted(3, 2, 1);
  predicted(1, 2) = 255;  // don't care is a truth value only
  try {
    ScoreLabels(truth, predicted, "gt/a.png", "pred/a.png");
    FAIL() << "expected ssta::Error";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("pred/a.png"), std::string::npos) << message;
    EXPECT_NE(message.find("(v 1, u 2)"), std::string::npos) << message;
  }
}

TEST(eval_ScoreLabels, RejectsTruthValuesThatAreNoClass) {
  ImageU8 truth(2, 2, 1);
  truth(0, 1) = 9;
  EXPECT_THROW(ScoreLabels(truth, ImageU8(2, 2, 1)), Error);
}

TEST(eval_ConfusionMatrix, BriefReportShowsTheScores) {
  const std::string report = MixedCase().BriefReport("pixels");
  EXPECT_NE(report.find("scored pixels: 9"), std::string::npos) << report;
  EXPECT_NE(report.find("accuracy 0.5556"), std::string::npos) << report;
  EXPECT_NE(report.find("coverage 0.7778"), std::string::npos) << report;
  EXPECT_NE(report.find("mean IoU 0.4667"), std::string::npos) << report;
}

}  // namespace
}  // namespace ssta
