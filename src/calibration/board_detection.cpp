#include "calibration/board_detection.h"

#include <algorithm>
#include <cmath>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace ssta::internal {
namespace {

/// Smallest distance between neighbouring corners along the rows and columns [px].
double SmallestCornerSpacing(const std::vector<cv::Point2f>& corners, int cols, int rows) {
  double spacing = 1e9;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const cv::Point2f& p = corners[static_cast<std::size_t>(r * cols + c)];
      if (c + 1 < cols) spacing = std::min(spacing, cv::norm(p - corners[static_cast<std::size_t>(r * cols + c + 1)]));
      if (r + 1 < rows) spacing = std::min(spacing, cv::norm(p - corners[static_cast<std::size_t>((r + 1) * cols + c)]));
    }
  }
  return spacing;
}

}  // namespace

bool DetectChessboard(const cv::Mat& grey, int cols, int rows, std::vector<cv::Point2f>* corners) {
  corners->clear();
  const cv::Size pattern(cols, rows);
  if (!cv::findChessboardCorners(grey, pattern, *corners,
                                 cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE)) {
    corners->clear();
    return false;
  }
  // The refinement window must not reach the neighbouring corners (it would average two
  // saddle points): its half size stays below a third of the corner spacing, at most 11 px
  // (OpenCV's sample value for 640x480 boards) and at least 2 px.
  const double spacing = SmallestCornerSpacing(*corners, cols, rows);
  const int half = std::clamp(static_cast<int>(spacing / 3.0), 2, 11);
  cv::cornerSubPix(grey, *corners, cv::Size(half, half), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 40, 0.001));
  return true;
}

void AlignCornerOrder(const std::vector<cv::Point2f>& left, std::vector<cv::Point2f>* right) {
  if (left.size() < 2 || right->size() != left.size()) return;
  const cv::Point2f dl = left.back() - left.front();
  const cv::Point2f dr = right->back() - right->front();
  if (dl.dot(dr) < 0.0f) std::reverse(right->begin(), right->end());
}

}  // namespace ssta::internal
