#pragma once

#include <string>
#include <vector>

#include "ssta/eval/disparity_evaluator.h"
#include "ssta/stereo/stereo_matcher.h"

namespace ssta {

/// What RunStereoBench runs.
struct StereoBenchOptions {
  int max_pairs = 0;     ///< score at most this many pairs (in file-name order), 0: all
  int warmup_pairs = 1;  ///< the first pair is matched this many times more, untimed, first
  DisparityEvalOptions rule;  ///< the bad-pixel rule of the score

  /// The first bad field, as "key: requirement", in `*error`.
  bool IsValid(std::string* error) const;
};

/// A stereo matcher's accuracy and speed on pairs with disparity truth.
struct StereoBenchReport {
  std::string data;               ///< the data folder
  std::string matcher;            ///< stereo.algorithm (and "at half size" for downscale 2)
  int width = 0, height = 0;      ///< size of the first pair [px]
  DisparityEvalSummary score;     ///< pixels of all pairs pooled
  std::vector<double> match_ms;   ///< wall time of StereoMatcher::Compute per pair [ms]
  /// Process CPU time of StereoMatcher::Compute per pair [ms] (std::clock: all threads, so
  /// CPU above wall means both cores worked; on a loaded machine it grows less than wall).
  std::vector<double> match_cpu_ms;

  /// Median of match_ms (Quantile 0.5) [ms].
  double MedianMatchMs() const;
  /// Median of match_cpu_ms [ms].
  double MedianMatchCpuMs() const;
  /// The score's report and the matching time.
  std::string BriefReport() const;
  /// The score's JSON with "kind": "stereo_bench", "data", "matcher", "width", "height",
  /// "median_match_ms", "median_match_cpu_ms", "match_ms" and "match_cpu_ms" (per pair) added.
  std::string ToJson() const;
};

/// Runs `matcher` (its options as they are: no rig, so auto_num_disparities does not apply)
/// over the pairs of `data_dir`, laid out as `left/NAME.png`, `right/NAME.png` (rectified grey
/// or colour, read as grey) and `gt/NAME.png` (disparity truth, ReadDisparityPng), one pair per
/// truth file, and scores each disparity against its truth. Only Compute is timed (reading is
/// not). Throws ssta::Error naming the folder or file that is missing or unreadable, and the
/// truth file whose size differs from its left image.
StereoBenchReport RunStereoBench(const std::string& data_dir, const StereoMatcherOptions& matcher,
                                 const StereoBenchOptions& options = {});

}  // namespace ssta
