#pragma once

// Private helper: chessboard corner detection shared by the calibrator and the rectification
// check. OpenCV types stay inside src/calibration.

#include <vector>

#include <opencv2/core.hpp>

namespace ssta::internal {

/// Detects the inner corners of a `cols` x `rows` chessboard in an 8-bit grey image and refines
/// them to sub-pixel accuracy. Returns false when the board is not found. Corners come in
/// OpenCV's order (row by row).
bool DetectChessboard(const cv::Mat& grey, int cols, int rows, std::vector<cv::Point2f>* corners);

/// OpenCV may return a board's corners starting from either end (a 180 degree ambiguity).
/// Reverses `right` when its first-to-last direction opposes `left`'s, so that corner i is the
/// same physical corner in both views of a stereo pair (the cameras of a rig look the same way).
void AlignCornerOrder(const std::vector<cv::Point2f>& left, std::vector<cv::Point2f>* right);

}  // namespace ssta::internal
