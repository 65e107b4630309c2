#include "ssta/calibration/stereo_calibrator.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <sstream>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "calibration/board_detection.h"
#include "ssta/core/error.h"
#include "ssta/io/image_io.h"

namespace ssta {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Corners of the board found in one pair (both views, same physical corner order).
struct PairCorners {
  std::size_t index = 0;  ///< into the input list
  std::vector<cv::Point2f> left;
  std::vector<cv::Point2f> right;
};

/// One solve of the rig from a set of pairs.
struct Solution {
  cv::Mat k_left, d_left, k_right, d_right;  ///< camera matrices, 5 distortion values (k3 = 0)
  cv::Mat r, t;                              ///< p_right = r * p_left + t (OpenCV's convention)
  double left_mono_rms = 0.0, right_mono_rms = 0.0, stereo_rms = 0.0;
  std::vector<double> left_mono, right_mono;      ///< per pair [px]
  std::vector<double> left_stereo, right_stereo;  ///< per pair [px]
};

std::string FileName(const std::string& path) {
  return std::filesystem::path(path).filename().string();
}

std::string SizeText(int width, int height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

std::vector<cv::Point3f> BoardPoints(const StereoCalibratorOptions& o) {
  std::vector<cv::Point3f> points;
  for (int r = 0; r < o.board_rows; ++r) {
    for (int c = 0; c < o.board_cols; ++c) {
      points.emplace_back(static_cast<float>(c * o.square_m), static_cast<float>(r * o.square_m), 0.0f);
    }
  }
  return points;
}

std::vector<double> ToVector(const cv::Mat& m, int column) {
  std::vector<double> out;
  for (int i = 0; i < m.rows; ++i) out.push_back(m.at<double>(i, column));
  return out;
}

Solution Solve(const std::vector<PairCorners>& pairs, const cv::Size& size,
               const StereoCalibratorOptions& options) {
  const std::vector<std::vector<cv::Point3f>> object(pairs.size(), BoardPoints(options));
  std::vector<std::vector<cv::Point2f>> left, right;
  for (const PairCorners& p : pairs) {
    left.push_back(p.left);
    right.push_back(p.right);
  }
  const cv::TermCriteria criteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-10);
  Solution s;
  std::vector<cv::Mat> rvecs, tvecs;
  cv::Mat std_intrinsics, std_extrinsics, per_view;
  // k3 stays 0: the ASL format carries k1, k2, p1, p2 only, and a k3 solved here but dropped
  // on writing would leave a model that no longer fits the data.
  s.left_mono_rms = cv::calibrateCamera(object, left, size, s.k_left, s.d_left, rvecs, tvecs,
                                        std_intrinsics, std_extrinsics, per_view,
                                        cv::CALIB_FIX_K3, criteria);
  s.left_mono = ToVector(per_view, 0);
  s.right_mono_rms = cv::calibrateCamera(object, right, size, s.k_right, s.d_right, rvecs, tvecs,
                                         std_intrinsics, std_extrinsics, per_view,
                                         cv::CALIB_FIX_K3, criteria);
  s.right_mono = ToVector(per_view, 0);

  const int flags = options.intrinsics == StereoIntrinsics::kFix
                        ? cv::CALIB_FIX_INTRINSIC
                        : cv::CALIB_USE_INTRINSIC_GUESS | cv::CALIB_FIX_K3;
  cv::Mat e, f;
  s.stereo_rms = cv::stereoCalibrate(object, left, right, s.k_left, s.d_left, s.k_right,
                                     s.d_right, size, s.r, s.t, e, f, per_view, flags, criteria);
  s.left_stereo = ToVector(per_view, 0);
  s.right_stereo = ToVector(per_view, 1);
  return s;
}

CameraCalibration ToCamera(const cv::Mat& k, const cv::Mat& d, const cv::Size& size,
                           const Eigen::Isometry3d& body_T_camera) {
  CameraCalibration c;
  c.width = size.width;
  c.height = size.height;
  c.fu = k.at<double>(0, 0);
  c.fv = k.at<double>(1, 1);
  c.cu = k.at<double>(0, 2);
  c.cv = k.at<double>(1, 2);
  const cv::Mat d64 = d.reshape(1, 1);
  for (int i = 0; i < 4; ++i) c.distortion[static_cast<std::size_t>(i)] = d64.at<double>(0, i);
  c.body_T_camera = body_T_camera;
  return c;
}

/// Fraction of `cols` x `rows` image cells holding at least one corner.
double Coverage(const std::vector<const std::vector<cv::Point2f>*>& views, const cv::Size& size,
                int cols, int rows) {
  std::vector<bool> touched(static_cast<std::size_t>(cols * rows), false);
  for (const auto* corners : views) {
    for (const cv::Point2f& p : *corners) {
      const int cu = std::clamp(static_cast<int>(p.x * cols / size.width), 0, cols - 1);
      const int cv = std::clamp(static_cast<int>(p.y * rows / size.height), 0, rows - 1);
      touched[static_cast<std::size_t>(cv * cols + cu)] = true;
    }
  }
  return static_cast<double>(std::count(touched.begin(), touched.end(), true)) / touched.size();
}

cv::Mat ReadGreyMat(const std::string& path, ImageU8* storage) {
  *storage = ReadGreyImage(path);
  return cv::Mat(storage->height(), storage->width(), CV_8UC1, storage->data());
}

/// A pair taken out by FindOutliers, with its errors in the solve it was taken out of [px].
struct RemovedPair {
  std::size_t index = 0;  ///< into the input list
  double left_mono = 0.0, right_mono = 0.0, left_stereo = 0.0, right_stereo = 0.0;
};

struct OutlierSearch {
  std::vector<RemovedPair> removed;  ///< in the order they were taken out
  std::vector<std::size_t> kept;     ///< input indices of the pairs left, in order
  Solution remaining;                ///< the solve over `kept`
};

/// One grossly wrong pair (a mismatched image, a board that moved during the exposure) drags
/// the whole rig solution and inflates every pair's error, so a single pass with a threshold
/// flags everything or nothing. Instead the worst pair is taken out and the rig solved again,
/// until no pair exceeds outlier_px or min_pairs would not be left.
OutlierSearch FindOutliers(const std::vector<PairCorners>& pairs, const Solution& all,
                           const cv::Size& size, const StereoCalibratorOptions& o) {
  OutlierSearch search;
  std::vector<PairCorners> active = pairs;
  search.remaining = all;
  while (true) {
    const Solution& s = search.remaining;
    std::size_t worst = 0;
    for (std::size_t j = 1; j < active.size(); ++j) {
      if (std::max(s.left_stereo[j], s.right_stereo[j]) >
          std::max(s.left_stereo[worst], s.right_stereo[worst])) {
        worst = j;
      }
    }
    if (std::max(s.left_stereo[worst], s.right_stereo[worst]) <= o.outlier_px ||
        static_cast<int>(active.size()) <= o.min_pairs) {
      break;
    }
    search.removed.push_back({active[worst].index, s.left_mono[worst], s.right_mono[worst],
                              s.left_stereo[worst], s.right_stereo[worst]});
    active.erase(active.begin() + static_cast<std::ptrdiff_t>(worst));
    search.remaining = Solve(active, size, o);
  }
  for (const PairCorners& p : active) search.kept.push_back(p.index);
  return search;
}

std::string TooFewPairsMessage(const std::vector<CalibrationPairReport>& reports,
                               const std::vector<PairCorners>& found,
                               const StereoCalibratorOptions& o) {
  std::ostringstream m;
  m << "too few boards: the " << o.board_cols << "x" << o.board_rows
    << " chessboard was found in both views of " << found.size() << " of " << reports.size()
    << " pairs";
  if (!found.empty()) {
    m << " (";
    for (std::size_t i = 0; i < found.size(); ++i) {
      const CalibrationPairReport& r = reports[found[i].index];
      m << (i ? ", " : "") << FileName(r.left_path) << "/" << FileName(r.right_path);
    }
    m << ")";
  }
  m << "; need at least " << o.min_pairs << " (--min-pairs)";
  if (found.size() < reports.size()) {
    m << "; not found in";
    int listed = 0;
    for (const CalibrationPairReport& r : reports) {
      if (r.board_in_left && r.board_in_right) continue;
      if (listed++ == 6) {
        m << " ...";
        break;
      }
      if (!r.board_in_left) m << " " << FileName(r.left_path);
      if (!r.board_in_right) m << " " << FileName(r.right_path);
    }
  }
  return m.str();
}

/// The boards found in every pair, and the report of each pair so far.
struct Detections {
  std::vector<CalibrationPairReport> reports;  ///< one per input pair
  std::vector<PairCorners> found;              ///< pairs with the board in both views
  cv::Size size;                               ///< common size of all images
};

Detections DetectBoards(const std::vector<std::string>& left_paths,
                        const std::vector<std::string>& right_paths,
                        const StereoCalibratorOptions& o) {
  Detections d;
  std::string size_source;
  for (std::size_t i = 0; i < left_paths.size(); ++i) {
    CalibrationPairReport report;
    report.left_path = left_paths[i];
    report.right_path = right_paths[i];
    report.left_mono_rms_px = report.right_mono_rms_px = kNaN;
    report.left_stereo_rms_px = report.right_stereo_rms_px = kNaN;
    PairCorners corners;
    corners.index = i;
    for (const bool is_left : {true, false}) {
      const std::string& path = is_left ? left_paths[i] : right_paths[i];
      ImageU8 storage;
      const cv::Mat grey = ReadGreyMat(path, &storage);
      if (size_source.empty()) {
        d.size = grey.size();
        size_source = path;
      } else if (grey.size() != d.size) {
        throw Error(path + ": image is " + SizeText(grey.cols, grey.rows) + " but " +
                    size_source + " is " + SizeText(d.size.width, d.size.height) +
                    "; all images of a calibration must have the same size");
      }
      (is_left ? report.board_in_left : report.board_in_right) = internal::DetectChessboard(
          grey, o.board_cols, o.board_rows, is_left ? &corners.left : &corners.right);
    }
    if (!report.board_in_left && !report.board_in_right) {
      report.skip_reason = "board not found in either image";
    } else if (!report.board_in_left) {
      report.skip_reason = "board not found in the left image";
    } else if (!report.board_in_right) {
      report.skip_reason = "board not found in the right image";
    } else {
      internal::AlignCornerOrder(corners.left, &corners.right);
      d.found.push_back(std::move(corners));
    }
    d.reports.push_back(std::move(report));
  }
  return d;
}

/// Marks the outliers of `search` in `reports`; with drop_outliers also takes them out of
/// `found` and keeps in their report the errors of the solve they were taken out of.
void ApplyOutliers(const OutlierSearch& search, const StereoCalibratorOptions& o,
                   std::vector<CalibrationPairReport>* reports, std::vector<PairCorners>* found) {
  for (const RemovedPair& removed : search.removed) {
    CalibrationPairReport& r = (*reports)[removed.index];
    r.outlier = true;
    if (!o.drop_outliers) continue;
    r.dropped = true;
    r.skip_reason = "dropped as an outlier";
    r.left_mono_rms_px = removed.left_mono;
    r.right_mono_rms_px = removed.right_mono;
    r.left_stereo_rms_px = removed.left_stereo;
    r.right_stereo_rms_px = removed.right_stereo;
  }
  // Pairs still above the threshold when the search had to stop at min_pairs.
  for (std::size_t j = 0; j < search.kept.size(); ++j) {
    if (std::max(search.remaining.left_stereo[j], search.remaining.right_stereo[j]) > o.outlier_px) {
      (*reports)[search.kept[j]].outlier = true;
    }
  }
  if (o.drop_outliers) {
    found->erase(std::remove_if(found->begin(), found->end(),
                                [&](const PairCorners& p) { return (*reports)[p.index].dropped; }),
                 found->end());
  }
}

/// Fills the rig (cameras, T_BS, baseline), the RMS figures and the coverage of `summary` from
/// `solution`, solved over `used`. Throws when the rig cannot be right (cam1 left of cam0).
void FillRig(const Solution& solution, const std::vector<PairCorners>& used, const cv::Size& size,
             StereoCalibrationSummary* summary) {
  const StereoCalibratorOptions& o = summary->options;
  // OpenCV: p_cam1 = R * p_cam0 + T, i.e. (R, T) is cam1_T_cam0.
  Eigen::Matrix3d r;
  Eigen::Vector3d t;
  cv::cv2eigen(solution.r, r);
  cv::cv2eigen(solution.t, t);
  Eigen::Isometry3d cam1_T_cam0 = Eigen::Isometry3d::Identity();
  cam1_T_cam0.linear() = Eigen::Quaterniond(r).normalized().toRotationMatrix();
  cam1_T_cam0.translation() = t;
  summary->cam0_T_cam1 = cam1_T_cam0.inverse();
  summary->baseline_m = t.norm();
  summary->calibration.left = ToCamera(solution.k_left, solution.d_left, size, o.body_T_cam0);
  summary->calibration.right =
      ToCamera(solution.k_right, solution.d_right, size, o.body_T_cam0 * summary->cam0_T_cam1);
  summary->pairs_used = static_cast<int>(used.size());
  summary->left_mono_rms_px = solution.left_mono_rms;
  summary->right_mono_rms_px = solution.right_mono_rms;
  summary->stereo_rms_px = solution.stereo_rms;
  std::vector<const std::vector<cv::Point2f>*> left_views, right_views;
  for (const PairCorners& p : used) {
    left_views.push_back(&p.left);
    right_views.push_back(&p.right);
  }
  summary->left_coverage = Coverage(left_views, size, o.coverage_cols, o.coverage_rows);
  summary->right_coverage = Coverage(right_views, size, o.coverage_cols, o.coverage_rows);

  std::string error;
  if (!summary->calibration.IsValid(&error)) {
    const Eigen::Vector3d p = summary->cam0_T_cam1.translation();
    std::ostringstream m;
    m << "--left/--right: the calibrated rig is not usable (" << error << "); cam1 sits at ["
      << p.x() << ", " << p.y() << ", " << p.z()
      << "] m in cam0, so check that --left holds the left camera's images";
    throw Error(m.str());
  }
}

}  // namespace

bool StereoCalibratorOptions::IsValid(std::string* error) const {
  if (board_cols < 2 || board_rows < 2) return Fail(error, "board: needs at least 2x2 inner corners");
  if (board_cols == board_rows) {
    return Fail(error, "board: a square corner grid (" + SizeText(board_cols, board_rows) +
                ") has no defined orientation; use a board with different inner corner counts");
  }
  if (!(std::isfinite(square_m) && square_m > 0.0)) return Fail(error, "square: must be a positive length [m]");
  if (!(std::isfinite(outlier_px) && outlier_px > 0.0)) return Fail(error, "outlier-px: must be positive [px]");
  if (min_pairs < 3) return Fail(error, "min-pairs: must be at least 3 (the fewest boards that fix the intrinsics)");
  if (coverage_cols < 1 || coverage_rows < 1) return Fail(error, "coverage-grid: needs at least 1x1 cells");
  const Eigen::Matrix4d m = body_T_cam0.matrix();
  const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
  if (!m.allFinite() || !(r * r.transpose()).isApprox(Eigen::Matrix3d::Identity(), 1e-6) ||
      std::abs(r.determinant() - 1.0) > 1e-6) {
    return Fail(error, "body-T-cam0: not a rigid transform (rotation not orthonormal with determinant +1)");
  }
  std::string rectification_error;
  if (!rectification.IsValid(&rectification_error)) return Fail(error, "rectification." + rectification_error);
  return true;
}

StereoCalibrator::StereoCalibrator(const StereoCalibratorOptions& options) : options_(options) {
  std::string error;
  if (!options_.IsValid(&error)) throw Error(error);
}

StereoCalibrationSummary StereoCalibrator::Calibrate(const std::vector<std::string>& left_paths,
                                                     const std::vector<std::string>& right_paths) const {
  const StereoCalibratorOptions& o = options_;
  if (left_paths.size() != right_paths.size()) {
    throw Error("--left/--right: " + std::to_string(left_paths.size()) + " left images but " +
                std::to_string(right_paths.size()) +
                " right images; pairs are made by sorted order, so the counts must match");
  }
  if (left_paths.empty()) throw Error("--left/--right: no images given");

  StereoCalibrationSummary summary;
  summary.options = o;
  Detections detections = DetectBoards(left_paths, right_paths, o);
  summary.pairs = std::move(detections.reports);
  std::vector<PairCorners>& found = detections.found;
  if (static_cast<int>(found.size()) < o.min_pairs) {
    throw Error(TooFewPairsMessage(summary.pairs, found, o));
  }

  const Solution all = Solve(found, detections.size, o);
  const OutlierSearch search = FindOutliers(found, all, detections.size, o);
  const Solution& solution = o.drop_outliers ? search.remaining : all;
  ApplyOutliers(search, o, &summary.pairs, &found);
  for (std::size_t j = 0; j < found.size(); ++j) {
    CalibrationPairReport& r = summary.pairs[found[j].index];
    r.left_mono_rms_px = solution.left_mono[j];
    r.right_mono_rms_px = solution.right_mono[j];
    r.left_stereo_rms_px = solution.left_stereo[j];
    r.right_stereo_rms_px = solution.right_stereo[j];
  }
  FillRig(solution, found, detections.size, &summary);
  return summary;
}

}  // namespace ssta
