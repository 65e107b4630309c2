#pragma once

#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "ssta/core/image.h"
#include "ssta/io/camera_calibration.h"
#include "ssta/stereo/rectifier.h"

namespace ssta {

/// How cv::stereoCalibrate treats the intrinsics found by each camera's own calibration.
enum class StereoIntrinsics {
  /// Start from the per-camera intrinsics and refine them jointly with the rig extrinsics.
  /// Every board pose is then shared by both cameras (one pose per pair instead of two), which
  /// is the maximum-likelihood estimate of the rig model and the usual choice.
  kRefine,
  /// Keep each camera's own intrinsics and solve only the rig extrinsics (for a rig whose
  /// cameras were calibrated separately with more images than the stereo set).
  kFix,
};

/// Options of `ssta calibrate-stereo`. Every field has a working default but the board.
struct StereoCalibratorOptions {
  /// Inner corners of the chessboard along its rows (columns of corners) and along its
  /// columns; OpenCV's sample board is 9x6. Both at least 2, and not equal (a square board has
  /// an orientation ambiguity that can swap corners between the left and right views).
  int board_cols = 9;
  int board_rows = 6;
  /// Side of one chessboard square [m]; sets the scale of the baseline and of T_BS.
  double square_m = 0.025;
  /// See StereoIntrinsics.
  StereoIntrinsics intrinsics = StereoIntrinsics::kRefine;
  /// Outlier threshold on a pair's stereo RMS reprojection error, left or right view [px].
  /// One grossly wrong pair inflates every pair's error, so outliers are found by taking out
  /// the worst pair and solving again until no pair exceeds this (or only min_pairs are left);
  /// the pairs taken out are the outliers. Set it well above the typical error (3 to 5 times
  /// the stereo RMS of a clean set).
  double outlier_px = 1.0;
  /// When true, the outliers are left out of the final solution; when false they are only
  /// flagged and the solution uses every pair with the board in both views.
  bool drop_outliers = false;
  /// Fewest pairs with the board found in both views to accept a calibration; the outlier
  /// search never leaves fewer. Three is the mathematical minimum for the pinhole + 4-coefficient model;
  /// fewer than about ten boards rarely constrain the distortion well.
  int min_pairs = 5;
  /// Board coverage is measured on a coarse grid of `coverage_cols` x `coverage_rows` image
  /// cells: the fraction of cells that hold at least one detected corner.
  int coverage_cols = 8;
  int coverage_rows = 6;
  /// Pose of cam0 in the body frame (T_BS of cam0); cam1's T_BS is body_T_cam0 * cam0_T_cam1.
  /// Must be rigid.
  Eigen::Isometry3d body_T_cam0 = Eigen::Isometry3d::Identity();
  /// How CheckRectification rectifies the pairs to check the result: as the pipeline will with
  /// the same config section (`rectification`: alpha, crop to the common area), so that the
  /// check's focal length, common area and picture are the ones classification will see.
  RectifierOptions rectification;

  /// On failure writes a message that starts with the option name (as on the command line,
  /// without "--", or the config key for `rectification`) and returns false.
  bool IsValid(std::string* error) const;
};

/// What happened to one left/right image pair.
struct CalibrationPairReport {
  std::string left_path;
  std::string right_path;
  bool board_in_left = false;   ///< chessboard found in the left image
  bool board_in_right = false;  ///< chessboard found in the right image
  /// Empty when the pair took part in the final solution; otherwise why not ("board not found
  /// in the right image", "dropped as an outlier").
  std::string skip_reason;
  /// RMS reprojection error of this view under its camera's own calibration (cv::calibrateCamera
  /// on the same pairs as the stereo error below) [px]; NaN when not detected in both views.
  double left_mono_rms_px = 0.0;
  double right_mono_rms_px = 0.0;
  /// RMS reprojection error of the left and right view under the final stereo solution, or for
  /// a dropped pair under the solve it was taken out of [px]. NaN when not detected.
  double left_stereo_rms_px = 0.0;
  double right_stereo_rms_px = 0.0;
  /// Found as an outlier (see StereoCalibratorOptions::outlier_px).
  bool outlier = false;
  /// Left out of the final solve (drop_outliers).
  bool dropped = false;

  bool used() const { return skip_reason.empty(); }
};

/// Epipolar check of the written calibration: the chessboard is detected again in the images
/// the project's Rectifier produces, and corresponding corners must lie on the same row.
struct RectificationCheck {
  int pairs_checked = 0;     ///< used pairs whose board was found in both rectified images
  int corners_checked = 0;   ///< corners compared over those pairs
  double mean_abs_dv_px = 0.0;  ///< mean |v_left - v_right| over the corners [px]
  double max_abs_dv_px = 0.0;   ///< largest |v_left - v_right| [px]
  double rectified_f_px = 0.0;  ///< focal length of the rectified pair [px]
  int crop_width = 0, crop_height = 0;  ///< common area kept by the Rectifier [px]
  std::string picture_pair;  ///< left image of the pair drawn in the picture
};

/// The result of a stereo calibration and its quality figures.
struct StereoCalibrationSummary {
  /// The calibration as written to cam0/ and cam1/sensor.yaml (frames: camera x right, y down,
  /// z forward; T_BS maps camera into body coordinates; lengths in metres).
  StereoCalibration calibration;
  std::vector<CalibrationPairReport> pairs;  ///< one per input pair, in input order
  int pairs_used = 0;  ///< pairs in the final solution
  double left_mono_rms_px = 0.0;   ///< RMS of cv::calibrateCamera on the left images [px]
  double right_mono_rms_px = 0.0;  ///< same for the right images [px]
  double stereo_rms_px = 0.0;      ///< RMS of cv::stereoCalibrate over both views [px]
  double left_coverage = 0.0;   ///< fraction in [0, 1] of coverage-grid cells with a corner
  double right_coverage = 0.0;
  double baseline_m = 0.0;  ///< distance between the optical centres [m]
  /// Pose of cam1 in cam0 (x right, y down, z forward) [m].
  Eigen::Isometry3d cam0_T_cam1 = Eigen::Isometry3d::Identity();
  RectificationCheck rectification;  ///< filled by CheckRectification / CalibrateStereoRig
  StereoCalibratorOptions options;   ///< the options used

  /// A few lines for a terminal: per-pair table, RMS figures, coverage, baseline, epipolar.
  std::string BriefReport() const;
  /// The same as a JSON document (units in the key names).
  std::string ToJson() const;
};

/// Calibrates a stereo rig from chessboard pairs with OpenCV: sub-pixel corners, each camera
/// alone (cv::calibrateCamera, k3 fixed to 0 because the ASL format holds k1, k2, p1, p2 only),
/// then the pair (cv::stereoCalibrate, see StereoIntrinsics). Stateless apart from its options;
/// safe to share between threads.
class StereoCalibrator {
 public:
  /// Throws ssta::Error (message starting with the option name) when the options are invalid.
  explicit StereoCalibrator(const StereoCalibratorOptions& options);

  /// Calibrates from `left_paths[i]` paired with `right_paths[i]`. Pairs where the board is
  /// missing in either view are kept in the report with a reason and left out of the solve.
  /// Throws ssta::Error, one line naming the files or option at fault, when the counts differ,
  /// a file cannot be read, the images differ in size, or fewer than min_pairs pairs remain.
  /// The returned summary has no rectification check yet (see CheckRectification).
  StereoCalibrationSummary Calibrate(const std::vector<std::string>& left_paths,
                                     const std::vector<std::string>& right_paths) const;

  const StereoCalibratorOptions& options() const { return options_; }

 private:
  StereoCalibratorOptions options_;
};

/// Rectifies the used pairs of `summary` with the project's Rectifier (the options'
/// `rectification`) built from `calibration` (normally read back from the written files),
/// detects the board again in each rectified pair, and measures |v_left - v_right| of
/// corresponding corners. Returns the figures and, in `*picture` (may be null), one rectified
/// pair side by side (left | right, cropped to the common area) with horizontal lines every 20
/// rows and the re-detected corners marked: the first pair whose board was found again, else
/// the first used pair. Throws ssta::Error when the Rectifier rejects the calibration.
RectificationCheck CheckRectification(const StereoCalibration& calibration,
                                      const StereoCalibrationSummary& summary, ImageRgb* picture);

/// The whole `ssta calibrate-stereo`: calibrates, writes `out_dir/cam0/sensor.yaml` and
/// `out_dir/cam1/sensor.yaml` (ASL format, docs/interfaces.md, section 2), reads them back with
/// LoadStereoCalibration, runs CheckRectification on what was read and writes
/// `out_dir/rectified_pair.png` and `out_dir/calibration_report.json`. Throws ssta::Error
/// as StereoCalibrator::Calibrate does, or naming a file that cannot be written.
StereoCalibrationSummary CalibrateStereoRig(const StereoCalibratorOptions& options,
                                            const std::vector<std::string>& left_paths,
                                            const std::vector<std::string>& right_paths,
                                            const std::string& out_dir);

/// Expands a POSIX glob pattern (glob(3), no brace or tilde expansion) into the matching paths
/// in byte order. A pattern that names an existing file yields that file (also when the name
/// holds wildcard characters). Returns an empty list when nothing matches.
std::vector<std::string> ExpandGlob(const std::string& pattern);

/// Reads a body transform from YAML: either a `T_BS:` block as in sensor.yaml (so an existing
/// cam0/sensor.yaml can be reused) or a top-level `data:` list of 16 numbers, row-major 4x4.
/// Throws ssta::Error naming the file and key when it is missing or not rigid.
Eigen::Isometry3d LoadBodyTransform(const std::string& path);

/// Builds a rigid transform from 16 numbers, row-major 4x4. Throws ssta::Error (message
/// starting with `what`) when there are not 16 finite numbers or the matrix is not rigid.
Eigen::Isometry3d BodyTransformFromRowMajor(const std::vector<double>& values,
                                            const std::string& what);

}  // namespace ssta
