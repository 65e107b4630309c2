#pragma once

#include <memory>
#include <string>

#include <Eigen/Core>

#include "ssta/core/option_fields.h"
#include "ssta/core/image.h"
#include "ssta/io/camera_calibration.h"

namespace ssta {

/// YAML section `rectification`.
struct RectifierOptions {
  /// Crop to the area valid in both rectified images (the paper's "common area"): the
  /// intersection of the two valid-pixel rectangles that cv::stereoRectify reports.
  bool crop_to_common_area = true;
  /// cv::stereoRectify's free scaling, in [0, 1]. 0 zooms in until every rectified pixel has a
  /// source pixel (the valid rectangles then cover the whole image, so there is nothing left to
  /// crop, and the image corners of the field of view are lost); 1 keeps every source pixel
  /// (black borders, smaller focal length). The default keeps every source pixel so that the
  /// common-area crop, not the zoom, decides what is kept, as the paper does. On EuRoC
  /// (k1 = -0.28): alpha 1 gives f = 313 px and a 645x348 common area (a wider view than alpha
  /// 0's), alpha 0.5 f = 375 px and 752x416, alpha 0 f = 436 px and no crop at all.
  double alpha = 1.0;
  /// Every field: its key, unit, range and meaning (reading, writing and IsValid come from it).
  static const OptionFields<RectifierOptions>& Fields();
  /// The first field out of its range, as "key: requirement" in `*error`.
  bool IsValid(std::string* error) const;
};

/// Geometry of the rectified, cropped left camera: everything triangulation and the analysis
/// need. Pixel coordinates (cu, cv) refer to the cropped image.
struct RectifiedGeometry {
  int full_width = 0, full_height = 0;  ///< size of the rectified image (= input size) [px]
  int crop_u0 = 0, crop_v0 = 0;         ///< top-left of the common area in the full image [px]
  int crop_width = 0, crop_height = 0;  ///< size of the common area [px]
  double f = 0.0;            ///< focal length of the rectified pair [px]
  double cu = 0.0, cv = 0.0; ///< principal point in cropped-image coordinates [px]
  double baseline_m = 0.0;   ///< distance between the two optical centres [m]
  /// Rotation taking vectors from the original cam0 frame into the rectified cam0 frame.
  Eigen::Matrix3d rectified_R_camera = Eigen::Matrix3d::Identity();
};

/// A rectified pair cropped to the common area, plus the full rectified left image (for
/// overlays that keep the rectified size).
struct RectifiedPair {
  ImageU8 left;       ///< cropped, crop_width x crop_height
  ImageU8 right;      ///< cropped, same size
  ImageU8 left_full;  ///< full rectified left image
};

/// Rectifies raw stereo pairs (cv::stereoRectify + remap) and crops them to the common valid
/// area. A rig that is already rectified (StereoCalibration::IsRectified) passes through
/// untouched. Thread-safe for concurrent Rectify() calls once constructed.
class Rectifier {
 public:
  /// Computes the rectification and the remap tables once (cv::stereoRectify with
  /// CALIB_ZERO_DISPARITY, rectified size = input size). Throws ssta::Error when the options or
  /// the calibration are invalid or the rectified images have no common valid area.
  Rectifier(const StereoCalibration& calibration, const RectifierOptions& options);
  ~Rectifier();
  Rectifier(Rectifier&&) noexcept;
  Rectifier& operator=(Rectifier&&) noexcept;

  /// Geometry of the rectified, cropped left camera.
  const RectifiedGeometry& geometry() const { return geometry_; }
  /// True for an already rectified rig: Rectify() copies the images unchanged, crop = full.
  bool passes_through() const { return passes_through_; }

  /// Rectifies (bilinear remap, black outside the source) and crops a raw pair.
  /// Precondition (checked, ssta::Error naming the image and both sizes): both images have the
  /// calibrated size. Thread-safe: the remap tables are read-only.
  RectifiedPair Rectify(const ImageU8& left, const ImageU8& right) const;

 private:
  struct Maps;
  RectifiedGeometry geometry_;
  bool passes_through_ = false;
  std::unique_ptr<Maps> maps_;
};

}  // namespace ssta
