#pragma once

#include <functional>
#include <string>
#include <vector>

#include "ssta/core/image.h"
#include "ssta/core/progress.h"
#include "ssta/eval/confusion_matrix.h"
#include "ssta/eval/distance_band.h"

namespace ssta {

/// Scores one predicted label image against its truth, pixel by pixel (metric rules in
/// ConfusionMatrix). Throws ssta::Error when the sizes differ, the truth holds a value other
/// than 0..4 or 255, or the prediction holds a value other than 0..4; messages start with
/// `truth_name` or `predicted_name` (normally the file paths) and give the pixel (v, u).
ConfusionMatrix ScoreLabels(const ImageU8& truth, const ImageU8& predicted,
                            const std::string& truth_name = "truth",
                            const std::string& predicted_name = "prediction");

/// Side-by-side picture for a person: truth | prediction | errors, each panel titled, over a
/// legend strip. Truth and prediction are in class colours (ColourizeLabels: traversable green,
/// semi-traversable blue, non-traversable red, unknown black, undecided grey, don't care
/// white). The errors panel shows scored pixels predicted right dark grey, wrong magenta, with
/// no verdict (predicted 0 or 4) orange, and pixels that are not scored white.
/// Precondition (ssta::Error): same size, valid ids as in ScoreLabels.
ImageRgb MakeComparisonPicture(const ImageU8& truth, const ImageU8& predicted);

/// What to do with a truth frame that has no prediction.
enum class MissingPrediction {
  kScoreAsUnknown,  ///< score every pixel as predicted 0: lowers accuracy and coverage
  kSkip,            ///< leave the frame out of the scores (it is still listed and counted)
};

/// Options of EvaluateLabelFolders.
struct LabelEvalOptions {
  /// A truth frame without a prediction is always reported; this decides whether it is scored.
  /// Scoring it as unknown keeps a method from gaining by dropping hard frames.
  MissingPrediction missing_prediction = MissingPrediction::kScoreAsUnknown;
  /// When not empty, a comparison picture (MakeComparisonPicture) per frame with a prediction
  /// is written to this folder under the frame's file name; the folder is created.
  std::string pictures_dir;

  /// Called after each truth frame with the number done and the total; may be empty. Lets a
  /// command line show progress; called on the calling thread.
  Progress progress;
  /// How many of the worst frames (lowest accuracy) BriefReport lists; >= 0.
  int worst_frames_listed = 5;
  /// [m] Width of the bands of depth from the camera the pixels are also scored in, when the
  /// truth has the true disparity and the rig (gt/disparity/, gt/rig.yaml): a pixel's depth is
  /// f b / its true disparity. Stereo's depth error grows with the square of the depth, so what
  /// the rig resolves and what it cannot are told apart. 0: no bands.
  double depth_band_m = 5.0;

  /// False, with a message naming the field, when pictures_dir names an existing non-folder,
  /// worst_frames_listed is negative or depth_band_m is negative or not finite.
  bool IsValid(std::string* error) const;
};

/// The score of one frame.
struct FrameScore {
  std::string name;                 ///< file name, e.g. "1403636579763555584.png"
  bool prediction_missing = false;  ///< true: no prediction file for this truth frame
  ConfusionMatrix matrix;           ///< empty when the frame was skipped
};

/// Result of EvaluateLabelFolders.
struct LabelEvalSummary {
  std::string prediction_dir;  ///< folder the predicted PNGs were read from
  std::string truth_dir;       ///< folder the truth PNGs were read from
  ConfusionMatrix total;       ///< sum over all scored frames (pixel-weighted)
  std::vector<FrameScore> frames;               ///< every truth frame, by file name
  std::vector<std::string> missing_prediction;  ///< truth frames without a prediction
  std::vector<std::string> missing_truth;       ///< predictions without a truth frame (unscored)
  MissingPrediction missing_prediction_policy = MissingPrediction::kScoreAsUnknown;
  int worst_frames_listed = 5;  ///< copied from the options, for BriefReport
  /// The scored pixels by depth from the camera (LabelEvalOptions::depth_band_m), pixels
  /// without a true disparity left out; empty when the truth has no disparity or rig.
  std::vector<DistanceBand> by_depth;
  double depth_band_m = 0.0;  ///< the bands' width [m]
  std::string depth_source;   ///< what the depths come from, for the report; "" without bands

  /// Frame counts, missing frames, the worst frames by accuracy and the aggregate
  /// ConfusionMatrix::BriefReport.
  std::string BriefReport() const;
  /// JSON document; "metrics" objects as described at ConfusionMatrix:
  /// {"kind": "labels", "unit": "pixels", "prediction", "truth", "frames_truth",
  ///  "frames_predicted", "frames_scored", "missing_prediction_policy", "missing_prediction": [...],
  ///  "missing_truth": [...], "metrics": {...}, "by_depth": {"path", "band_m", "bands": [...]}
  ///  (only with depth bands; shaped as eval grid's "by_distance_from_path"), "frames":
  ///  [{"name", "prediction_missing", "scored_in_total", "metrics"}]}.
  std::string ToJson() const;
};

/// Scores a folder of predicted label images against a synthetic sequence's truth.
/// `prediction` is the output folder of `ssta classify` (PNGs under prediction/labels/) or a
/// folder holding the PNGs directly. Truth is SEQ/gt/labels/ (or SEQ/mav0/gt/labels/). Frames
/// are matched by file name (*.png); a frame's true disparity, for the depth bands, is
/// gt/disparity/ under the same name (frames without one are left out of the bands). Throws
/// ssta::Error naming the file or folder: a missing folder, a folder without any PNG (nothing to
/// score is a wrong path, not a score), an unreadable image, a size mismatch, an invalid class
/// value, or a gt/rig.yaml without a positive focal_px and baseline_m.
LabelEvalSummary EvaluateLabelFolders(const std::string& prediction, const std::string& sequence,
                                      const LabelEvalOptions& options = {});

}  // namespace ssta
