#include "ssta/stereo/rectifier.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>

#include "ssta/core/error.h"

namespace ssta {

/// Per-camera remap tables (fixed-point CV_16SC2 + CV_16UC1, the fast form of cv::remap).
/// Read-only after construction, so concurrent Rectify() calls share them safely.
struct Rectifier::Maps {
  cv::Mat left_map1, left_map2;
  cv::Mat right_map1, right_map2;
};

namespace {

std::string SizeText(int width, int height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

cv::Mat CameraMatrix(const CameraCalibration& c) {
  return (cv::Mat_<double>(3, 3) << c.fu, 0.0, c.cu, 0.0, c.fv, c.cv, 0.0, 0.0, 1.0);
}

cv::Mat DistortionVector(const CameraCalibration& c) {
  return (cv::Mat_<double>(1, 4) << c.distortion[0], c.distortion[1], c.distortion[2],
          c.distortion[3]);
}

/// Wraps an ImageU8 as a cv::Mat header without copying. The Mat must not be written to.
cv::Mat WrapConst(const ImageU8& image) {
  return cv::Mat(image.height(), image.width(), CV_8UC1,
                 const_cast<std::uint8_t*>(image.data()));
}

ImageU8 CopyRect(const cv::Mat& full, const cv::Rect& rect) {
  ImageU8 out(rect.width, rect.height);
  for (int v = 0; v < rect.height; ++v) {
    const std::uint8_t* src = full.ptr<std::uint8_t>(rect.y + v) + rect.x;
    std::copy(src, src + rect.width, out.row(v));
  }
  return out;
}

ImageU8 CopyRect(const ImageU8& full, const cv::Rect& rect) { return CopyRect(WrapConst(full), rect); }

void CheckSize(const ImageU8& image, const char* which, int width, int height) {
  if (image.width() != width || image.height() != height) {
    throw Error("Rectifier: the " + std::string(which) + " image is " +
                SizeText(image.width(), image.height()) + " but the calibration expects " +
                SizeText(width, height));
  }
}

}  // namespace

const OptionFields<RectifierOptions>& RectifierOptions::Fields() {
  using O = RectifierOptions;
  static const OptionFields<O> fields = [] {
    OptionFields<O> f;
    f.push_back(Flag<O>("crop_to_common_area", &O::crop_to_common_area,
                        "crop both images to the area valid in both (paper III-A)"));
    f.push_back(Real<O>("alpha", &O::alpha, Closed(0, 1), "",
                        "cv::stereoRectify free scaling: 1 keeps every source pixel (wider view, "
                        "smaller f), 0 only valid pixels (larger f)"));
    return f;
  }();
  return fields;
}

bool RectifierOptions::IsValid(std::string* error) const { return CheckOptions(*this, Fields(), error); }

Rectifier::Rectifier(const StereoCalibration& calibration, const RectifierOptions& options)
    : maps_(std::make_unique<Maps>()) {
  std::string why;
  if (!options.IsValid(&why)) throw Error(why);
  if (!calibration.IsValid(&why)) throw Error("Rectifier: invalid stereo calibration: " + why);

  const int width = calibration.left.width;
  const int height = calibration.left.height;
  geometry_.full_width = width;
  geometry_.full_height = height;

  if (calibration.IsRectified()) {
    passes_through_ = true;
    geometry_.crop_width = width;
    geometry_.crop_height = height;
    geometry_.f = calibration.left.fu;
    geometry_.cu = calibration.left.cu;
    geometry_.cv = calibration.left.cv;
    geometry_.baseline_m = calibration.LeftTRight().translation().norm();
    geometry_.rectified_R_camera.setIdentity();
    return;
  }

  // OpenCV wants the motion from cam0 to cam1 coordinates: p_right = R * p_left + T.
  const Eigen::Isometry3d right_T_left = calibration.LeftTRight().inverse();
  cv::Mat r, t;
  cv::eigen2cv(Eigen::Matrix3d(right_T_left.rotation()), r);
  cv::eigen2cv(Eigen::Vector3d(right_T_left.translation()), t);

  const cv::Size size(width, height);
  cv::Mat r1, r2, p1, p2, q;
  cv::Rect roi_left, roi_right;
  try {
    cv::stereoRectify(CameraMatrix(calibration.left), DistortionVector(calibration.left),
                      CameraMatrix(calibration.right), DistortionVector(calibration.right), size,
                      r, t, r1, r2, p1, p2, q, cv::CALIB_ZERO_DISPARITY, options.alpha, size,
                      &roi_left, &roi_right);
  } catch (const cv::Exception& e) {
    throw Error(std::string("Rectifier: cv::stereoRectify failed on the calibration: ") +
                e.what());
  }
  const double f = p1.at<double>(0, 0);
  // With CALIB_ZERO_DISPARITY, P2(0,3) = -f * baseline (cam1 to the right of cam0).
  const double baseline_m = -p2.at<double>(0, 3) / p2.at<double>(0, 0);
  if (!(std::isfinite(f) && f > 0.0 && std::isfinite(baseline_m) && baseline_m > 0.0)) {
    throw Error("Rectifier: the calibration gives a degenerate rectification (focal length " +
                std::to_string(f) + " px, baseline " + std::to_string(baseline_m) + " m)");
  }

  cv::Rect crop(0, 0, width, height);
  if (options.crop_to_common_area) crop = roi_left & roi_right;
  if (crop.area() <= 0) {
    throw Error("Rectifier: the rectified left and right images have no common valid area "
                "(left ROI " + SizeText(roi_left.width, roi_left.height) + ", right ROI " +
                SizeText(roi_right.width, roi_right.height) + "); check the calibration");
  }

  cv::initUndistortRectifyMap(CameraMatrix(calibration.left), DistortionVector(calibration.left),
                              r1, p1, size, CV_16SC2, maps_->left_map1, maps_->left_map2);
  cv::initUndistortRectifyMap(CameraMatrix(calibration.right),
                              DistortionVector(calibration.right), r2, p2, size, CV_16SC2,
                              maps_->right_map1, maps_->right_map2);

  geometry_.crop_u0 = crop.x;
  geometry_.crop_v0 = crop.y;
  geometry_.crop_width = crop.width;
  geometry_.crop_height = crop.height;
  geometry_.f = f;
  geometry_.cu = p1.at<double>(0, 2) - crop.x;
  geometry_.cv = p1.at<double>(1, 2) - crop.y;
  geometry_.baseline_m = baseline_m;
  cv::cv2eigen(r1, geometry_.rectified_R_camera);
}

Rectifier::~Rectifier() = default;
Rectifier::Rectifier(Rectifier&&) noexcept = default;
Rectifier& Rectifier::operator=(Rectifier&&) noexcept = default;

RectifiedPair Rectifier::Rectify(const ImageU8& left, const ImageU8& right) const {
  CheckSize(left, "left", geometry_.full_width, geometry_.full_height);
  CheckSize(right, "right", geometry_.full_width, geometry_.full_height);
  const cv::Rect crop(geometry_.crop_u0, geometry_.crop_v0, geometry_.crop_width,
                      geometry_.crop_height);
  RectifiedPair out;
  if (passes_through_) {
    out.left_full = left;
    out.left = left;
    out.right = right;
    return out;
  }
  out.left_full = ImageU8(geometry_.full_width, geometry_.full_height);
  cv::Mat left_full(out.left_full.height(), out.left_full.width(), CV_8UC1, out.left_full.data());
  cv::remap(WrapConst(left), left_full, maps_->left_map1, maps_->left_map2, cv::INTER_LINEAR,
            cv::BORDER_CONSTANT, cv::Scalar(0));
  cv::Mat right_full;
  cv::remap(WrapConst(right), right_full, maps_->right_map1, maps_->right_map2,
            cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0));
  out.left = CopyRect(out.left_full, crop);
  out.right = CopyRect(right_full, crop);
  return out;
}

}  // namespace ssta
