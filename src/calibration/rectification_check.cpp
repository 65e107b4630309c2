// The check of a written calibration through the project's own Rectifier, and the whole
// calibrate-stereo flow that writes the files.

#include <cmath>
#include <filesystem>

#include <opencv2/imgproc.hpp>

#include "calibration/board_detection.h"
#include "ssta/calibration/stereo_calibrator.h"
#include "ssta/core/error.h"
#include "ssta/files/file_util.h"
#include "ssta/io/image_io.h"
#include "ssta/stereo/rectifier.h"

namespace ssta {
namespace {

constexpr int kLineSpacingPx = 20;  ///< rows between the epipolar lines of the picture

cv::Mat Wrap(ImageU8& image) {
  return cv::Mat(image.height(), image.width(), CV_8UC1, image.data());
}

/// Left | right side by side in colour, horizontal lines every kLineSpacingPx rows (cycling
/// through three colours so a line can be followed across), corners marked when found.
ImageRgb DrawPicture(RectifiedPair& pair, const std::vector<cv::Point2f>& left_corners,
                     const std::vector<cv::Point2f>& right_corners) {
  const int w = pair.left.width();
  const int h = pair.left.height();
  ImageRgb picture(2 * w, h);
  cv::Mat canvas(h, 2 * w, CV_8UC3, picture.data());  // R, G, B channel order
  cv::Mat grey_left = Wrap(pair.left), grey_right = Wrap(pair.right);
  cv::cvtColor(grey_left, canvas(cv::Rect(0, 0, w, h)), cv::COLOR_GRAY2RGB);
  cv::cvtColor(grey_right, canvas(cv::Rect(w, 0, w, h)), cv::COLOR_GRAY2RGB);
  const cv::Scalar colours[] = {{0, 220, 0}, {0, 160, 255}, {255, 200, 0}};
  for (int v = kLineSpacingPx / 2, k = 0; v < h; v += kLineSpacingPx, ++k) {
    cv::line(canvas, cv::Point(0, v), cv::Point(2 * w - 1, v), colours[k % 3], 1);
  }
  for (const cv::Point2f& p : left_corners) cv::circle(canvas, p, 2, cv::Scalar(255, 0, 0), 1, cv::LINE_AA);
  for (const cv::Point2f& p : right_corners) {
    cv::circle(canvas, p + cv::Point2f(static_cast<float>(w), 0.0f), 2, cv::Scalar(255, 0, 0), 1, cv::LINE_AA);
  }
  cv::line(canvas, cv::Point(w, 0), cv::Point(w, h - 1), cv::Scalar(255, 255, 255), 1);
  return picture;
}

}  // namespace

RectificationCheck CheckRectification(const StereoCalibration& calibration,
                                      const StereoCalibrationSummary& summary, ImageRgb* picture) {
  const Rectifier rectifier(calibration, summary.options.rectification);
  const RectifiedGeometry& g = rectifier.geometry();
  RectificationCheck check;
  check.rectified_f_px = g.f;
  check.crop_width = g.crop_width;
  check.crop_height = g.crop_height;
  double sum_dv = 0.0;
  bool picture_has_board = false;
  for (const CalibrationPairReport& p : summary.pairs) {
    if (!p.used()) continue;
    RectifiedPair pair = rectifier.Rectify(ReadGreyImage(p.left_path), ReadGreyImage(p.right_path));
    std::vector<cv::Point2f> left, right;
    const bool found =
        internal::DetectChessboard(Wrap(pair.left), summary.options.board_cols,
                                   summary.options.board_rows, &left) &&
        internal::DetectChessboard(Wrap(pair.right), summary.options.board_cols,
                                   summary.options.board_rows, &right);
    if (found) {
      internal::AlignCornerOrder(left, &right);
      for (std::size_t i = 0; i < left.size(); ++i) {
        const double dv = std::abs(static_cast<double>(left[i].y) - right[i].y);
        sum_dv += dv;
        check.max_abs_dv_px = std::max(check.max_abs_dv_px, dv);
      }
      check.corners_checked += static_cast<int>(left.size());
      ++check.pairs_checked;
    }
    // The picture shows the first pair whose board was found again, or else the first pair.
    if (picture != nullptr && (check.picture_pair.empty() || (found && !picture_has_board))) {
      const std::vector<cv::Point2f> none;
      *picture = DrawPicture(pair, found ? left : none, found ? right : none);
      check.picture_pair = p.left_path;
      picture_has_board = found;
    }
  }
  if (check.corners_checked > 0) check.mean_abs_dv_px = sum_dv / check.corners_checked;
  return check;
}

StereoCalibrationSummary CalibrateStereoRig(const StereoCalibratorOptions& options,
                                            const std::vector<std::string>& left_paths,
                                            const std::vector<std::string>& right_paths,
                                            const std::string& out_dir) {
  const StereoCalibrator calibrator(options);
  StereoCalibrationSummary summary = calibrator.Calibrate(left_paths, right_paths);

  const std::string cam0 = out_dir + "/cam0/sensor.yaml";
  const std::string cam1 = out_dir + "/cam1/sensor.yaml";
  MakeDirectories(out_dir + "/cam0");
  MakeDirectories(out_dir + "/cam1");
  char comment[160];
  std::snprintf(comment, sizeof(comment),
                "ssta calibrate-stereo: %d chessboard pairs, stereo RMS %.3f px, baseline %.4f m",
                summary.pairs_used, summary.stereo_rms_px, summary.baseline_m);
  SaveCameraCalibration(summary.calibration.left, cam0, std::string("cam0, ") + comment);
  SaveCameraCalibration(summary.calibration.right, cam1, std::string("cam1, ") + comment);

  // Check what the rest of the project will read, not the numbers held in memory.
  const StereoCalibration written = LoadStereoCalibration(cam0, cam1);
  ImageRgb picture;
  summary.rectification = CheckRectification(written, summary, &picture);
  if (!picture.empty()) WriteImage(picture, out_dir + "/rectified_pair.png");
  WriteTextAtomically(out_dir + "/calibration_report.json", summary.ToJson());
  return summary;
}

}  // namespace ssta
