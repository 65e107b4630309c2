#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>

#include "ssta/core/classes.h"

namespace ssta {

/// Counts of (truth, predicted) class pairs and the scores derived from them. The one place
/// where the project's accuracy figures are defined:
///
/// - Rows are the truth class 0..4, columns the predicted class 0..4. Truth 255 (don't care) is
///   counted apart and never enters a score.
/// - Scored samples are those whose truth is a verdict, 1..3 (traversable, semi-traversable,
///   non-traversable). Truth 0 (unknown) and 4 (undecided) are rare in ground truth and carry no
///   verdict to compare against: they are kept in the matrix for inspection but not scored.
/// - Accuracy = correct / scored. A predicted 0 or 4 on a scored sample counts as wrong.
/// - Coverage = scored samples with a predicted verdict 1..3 / scored.
/// - Decided accuracy = correct / scored samples with a predicted verdict 1..3 (how good the
///   verdicts are where the method gave one).
/// - IoU of class c in 1..3 = TP / (TP + FP + FN), counted over scored samples only:
///   TP = M[c][c], FN = scored samples of truth c predicted anything else (0 and 4 included),
///   FP = scored samples of truth other than c predicted c.
/// - A class is present when TP + FP + FN > 0 (it occurs in the truth or in the prediction of a
///   scored sample). Mean IoU averages the IoU of the present classes 1..3; absent classes are
///   left out. With no present class (nothing scored) the mean IoU is NaN.
///
/// Ratios with a zero denominator are NaN (written as null in JSON). The JSON "metrics" object
/// written by the scorers holds: scored, correct, decided (counts); not_scored {dont_care,
/// truth_unknown, truth_undecided}; accuracy, coverage, decided_accuracy, mean_iou (numbers or
/// null); present_classes; iou {traversable, semi-traversable, non-traversable}; recall {the
/// same keys}; unsafe {count, truly_blocked, rate}; falsely_blocked {count, truly_free, rate};
/// confusion
/// (5 rows of 5 counts, rows truth 0..4, columns predicted 0..4).
/// A "sample" is a pixel, a
/// grid cell or a query point depending on the scorer. A value type; not thread-safe for
/// concurrent writers.
class ConfusionMatrix {
 public:
  static constexpr int kSize = kNumClasses;

  /// Adds `count` samples of truth `truth` predicted as `predicted`. Preconditions (checked,
  /// ssta::InternalError): truth is 0..4 or kDontCare, predicted is 0..4, count >= 0.
  void Add(std::uint8_t truth, std::uint8_t predicted, std::int64_t count = 1);
  /// Sums another matrix into this one (aggregation over frames).
  ConfusionMatrix& operator+=(const ConfusionMatrix& other);

  /// Samples of truth `truth` (0..4) predicted as `predicted` (0..4).
  std::int64_t Count(int truth, int predicted) const;
  /// Samples whose truth is don't care (255); these are not in the matrix.
  std::int64_t dont_care() const { return dont_care_; }
  /// Samples of truth `truth` (0..4), whatever was predicted.
  std::int64_t TruthTotal(int truth) const;
  /// Scored samples (truth 1..3) predicted as `predicted` (0..4).
  std::int64_t ScoredPredictedTotal(int predicted) const;
  /// Samples with truth 1..3.
  std::int64_t Scored() const;
  /// Scored samples whose prediction equals the truth.
  std::int64_t Correct() const;
  /// Scored samples with a predicted verdict 1..3.
  std::int64_t Decided() const;

  /// TP + FP + FN of `c` over scored samples; `c` must be 1..3 (checked).
  std::int64_t IouDenominator(TravClass c) const;
  /// IoU of class `c` (1..3, checked); NaN when the class is not present.
  double Iou(TravClass c) const;
  /// True when `c` (1..3) occurs in the truth or the prediction of a scored sample.
  bool IsPresent(TravClass c) const { return IouDenominator(c) > 0; }
  /// Number of present classes among 1..3 (the denominator of MeanIou).
  int PresentClasses() const;
  /// Mean IoU over the present classes 1..3; NaN when none is present.
  double MeanIou() const;
  /// Correct / scored; NaN when nothing is scored.
  double Accuracy() const;
  /// Decided / scored; NaN when nothing is scored.
  double Coverage() const;
  /// Correct / decided; NaN when nothing was decided.
  double DecidedAccuracy() const;

  // What a planner is told. A planner asks whether the robot may be there: a truly
  // non-traversable sample answered traversable or semi-traversable sends it into an obstacle,
  // a truly free one (traversable or semi-traversable) answered non-traversable closes a way
  // that is open. Unknown and undecided answers are neither: a planner treats them as not known.

  /// Recall of class `c` (1..3, checked): truth-c samples predicted c / truth-c samples; NaN
  /// when the truth has none.
  double Recall(TravClass c) const;
  /// Whether one sample (class ids) is unsafe: truth non-traversable, predicted traversable or
  /// semi-traversable.
  static bool IsUnsafe(std::uint8_t truth, std::uint8_t predicted);
  /// Whether one sample is falsely blocked: truth traversable or semi-traversable, predicted
  /// non-traversable.
  static bool IsFalselyBlocked(std::uint8_t truth, std::uint8_t predicted);
  /// Samples of truth non-traversable predicted traversable or semi-traversable.
  std::int64_t Unsafe() const;
  /// Unsafe() / samples of truth non-traversable; NaN when the truth has none.
  double UnsafeRate() const;
  /// Samples of truth traversable or semi-traversable predicted non-traversable.
  std::int64_t FalselyBlocked() const;
  /// FalselyBlocked() / samples of truth traversable or semi-traversable; NaN when none.
  double FalselyBlockedRate() const;

  /// A few lines for a terminal: counts, accuracy, coverage, mean IoU, per-class IoU and the
  /// matrix. `unit` names the samples ("pixels", "cells", "points").
  std::string BriefReport(std::string_view unit) const;

 private:
  std::array<std::array<std::int64_t, kSize>, kSize> counts_{};
  std::int64_t dont_care_ = 0;
};

}  // namespace ssta
