#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "ssta/core/image.h"

namespace ssta {

namespace internal {
class JsonWriter;  // include/ssta/core/json_writer.h
}  // namespace internal

/// The bad-pixel rule of a disparity score (KITTI's D1): a pixel with a truth disparity is bad
/// when its estimate is off by more than `max_error_px` AND by more than `max_error_ratio` of
/// the truth, or when it has no estimate.
struct DisparityEvalOptions {
  double max_error_px = 3.0;      ///< [px] absolute part of the rule, >= 0
  double max_error_ratio = 0.05;  ///< relative part of the rule (0.05 = 5 % of the truth), >= 0

  /// "max_error_px: ..." or "max_error_ratio: ..." in `*error` when a value is negative or not finite.
  bool IsValid(std::string* error) const;
};

/// Pixel counts of a disparity score, summed over one or more pairs (every truth pixel of every
/// pair weighs the same). Only pixels with a truth disparity (> 0) are counted; an estimate of
/// 0 (or not finite, or negative) is "no disparity".
struct DisparityEvalSummary {
  std::string prediction;         ///< the estimate (file or folder), for the report
  std::string truth;              ///< the truth (file or folder), for the report
  int pairs = 0;                  ///< pairs (images) scored
  std::int64_t truth_pixels = 0;  ///< pixels with a truth disparity
  std::int64_t matched_pixels = 0;       ///< of those, with an estimate
  std::int64_t bad_matched_pixels = 0;   ///< of the matched ones, bad by the rule
  double sum_abs_error_px = 0.0;         ///< sum of |estimate - truth| over matched pixels [px]
  static constexpr double kNoiseBinPx = 1.0 / 256.0;  ///< a step of KITTI's 16-bit disparity
  static constexpr double kNoiseHalfRangePx = 16.0;
  static constexpr int kNoiseBins = static_cast<int>(2.0 * kNoiseHalfRangePx / kNoiseBinPx);
  /// The noise of the good matches (matched and not bad): a histogram of their signed errors
  /// (estimate - truth) in kNoiseBins bins of kNoiseBinPx over +-kNoiseHalfRangePx, the
  /// outermost bins taking what lies beyond.
  std::vector<std::int64_t> good_error_histogram = std::vector<std::int64_t>(kNoiseBins, 0);
  /// The same for the difference of the errors of two good matches one above the other (rows v
  /// and v + 1 of one column): what a step between neighbouring pixels is measured with.
  /// Independent errors differ with sqrt(2) times their sigma; errors the matcher makes alike at
  /// neighbouring pixels (smoothness, overlapping windows) differ with less.
  std::vector<std::int64_t> neighbour_difference_histogram = std::vector<std::int64_t>(kNoiseBins, 0);
  /// Depth edges, where a matcher's window and smoothness spread one surface's disparity over
  /// its neighbour (a post widened: fattening; a drop-off's lip given the disparity of the
  /// ground beyond: erosion). A truth pixel lies behind an edge when a truth pixel within
  /// kEdgeRadiusPx of it (a square window) is nearer by a bad error under the rule, in front of
  /// one when such a pixel is farther; a pixel may be both.
  static constexpr int kEdgeRadiusPx = 4;
  std::int64_t behind_edge_pixels = 0;  ///< truth pixels behind a depth edge
  /// Of those, matched with an estimate nearer than the truth by a bad error: the nearer
  /// side's disparity spread over them.
  std::int64_t fattened_pixels = 0;
  std::int64_t front_edge_pixels = 0;  ///< truth pixels in front of a depth edge
  /// Of those, matched with an estimate farther than the truth by a bad error: the farther
  /// side's disparity spread over them.
  std::int64_t eroded_pixels = 0;
  DisparityEvalOptions rule;             ///< the bad-pixel rule used

  /// Share of truth pixels that are bad, the ones without an estimate included (NaN when
  /// there are no truth pixels).
  double D1All() const;
  /// Share of matched pixels that are bad (NaN when none is matched).
  double D1Matched() const;
  /// Mean |estimate - truth| over matched pixels [px] (NaN when none is matched).
  double EndPointErrorPx() const;
  /// Share of truth pixels with an estimate (NaN when there are no truth pixels).
  double Density() const;
  /// Median of the good matches' errors (estimate - truth) [px]: the matcher's bias, which no
  /// noise model averages away (a constant offset e tilts a ground plane like a camera pitched
  /// by about e h / (f b)); NaN without good matches.
  double GoodErrorMedianPx() const;
  /// Robust sigma of the good matches' errors, 1.4826 times their median absolute deviation
  /// [px]: the matcher's disparity noise (stereo.disparity_sigma_px); NaN without good matches.
  double GoodErrorSigmaPx() const;
  /// The same of the error differences of vertically neighbouring good matches [px]; NaN
  /// without such pairs.
  double NeighbourDifferenceSigmaPx() const;
  /// NeighbourDifferenceSigmaPx / (sqrt(2) GoodErrorSigmaPx): 1 when neighbouring errors are
  /// independent, 0 when they are equal (sqrt(1 - rho) for Gaussian errors of correlation rho).
  double NeighbourDifferenceRatio() const;

  /// Share of the truth pixels behind a depth edge that are fattened (NaN when there are none).
  double FattenedShare() const;
  /// Share of the truth pixels in front of a depth edge that are eroded (NaN when there are none).
  double ErodedShare() const;

  /// Adds the counts of `other` (the same rule) to these.
  void Add(const DisparityEvalSummary& other);
  /// A few lines: what was scored, D1 over all and over matched pixels, EPE, density, the
  /// noise of the good matches and the depth edges.
  std::string BriefReport() const;
  /// {"kind": "disparity", "prediction", "truth", "pairs", "truth_pixels", "matched_pixels",
  ///  "bad_matched_pixels", "max_error_px", "max_error_ratio", "d1_all", "d1_matched",
  ///  "epe_px", "density", "good_error_median_px", "good_error_sigma_px",
  ///  "neighbour_difference_sigma_px", "neighbour_difference_ratio", "edge_radius_px",
  ///  "behind_edge_pixels", "fattened_pixels", "fattened_share", "front_edge_pixels",
  ///  "eroded_pixels", "eroded_share"}.
  std::string ToJson() const;
};

/// Scores `estimate` against `truth` (both disparities in px, the same size; 0 = none) with
/// the rule of `options`. Throws ssta::Error giving both sizes when they differ, and the
/// IsValid message when `options` are invalid.
DisparityEvalSummary ScoreDisparity(const ImageF& truth, const ImageF& estimate,
                                    const DisparityEvalOptions& options = {});

/// Reads a disparity PNG in KITTI's convention (16 bit, disparity = value / 256, 0 = none), as
/// `ssta classify --disparity` and `ssta synth` write them. Throws ssta::Error naming the file
/// when it is missing, cannot be decoded or is not 16-bit single-channel.
ImageF ReadDisparityPng(const std::string& path);

/// Scores disparity PNGs: `prediction` and `truth` are both files, or both folders (a folder's
/// `disparity/` subfolder is taken when there is one, so a `classify --disparity` output folder
/// and a synthetic sequence's `gt/` work as they are). Folders are paired by file name: every
/// truth PNG needs an estimate of the same name. Throws ssta::Error naming the file that is
/// missing, unreadable or of another size than its truth.
DisparityEvalSummary EvaluateDisparityFiles(const std::string& prediction, const std::string& truth,
                                            const DisparityEvalOptions& options = {});

namespace internal {

/// Writes the score of `summary` as fields of the JSON object being built: "pairs",
/// "truth_pixels", "matched_pixels", "bad_matched_pixels", "max_error_px", "max_error_ratio",
/// "d1_all", "d1_matched", "epe_px", "density", the noise and the depth edges
/// (DisparityEvalSummary::ToJson, the stereo bench).
void WriteDisparityScoreFields(const DisparityEvalSummary& summary, JsonWriter* json);

}  // namespace internal

}  // namespace ssta
