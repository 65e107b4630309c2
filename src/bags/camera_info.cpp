#include "bags/camera_info.h"

#include <algorithm>
#include <cmath>

#include <opencv2/calib3d.hpp>

#include "ssta/core/error.h"

namespace ssta::internal {
namespace {

bool AllZero(const std::vector<double>& v) { return std::all_of(v.begin(), v.end(), [](double d) { return d == 0.0; }); }

/// R as recorded, or identity for the all-zero R of a driver that leaves it unset.
Eigen::Matrix3d RectificationRotation(const RosCameraInfo& info) {
  if (std::all_of(info.r.begin(), info.r.end(), [](double v) { return v == 0.0; })) return Eigen::Matrix3d::Identity();
  Eigen::Matrix3d r;
  for (int i = 0; i < 9; ++i) r(i / 3, i % 3) = info.r[static_cast<std::size_t>(i)];
  return r;
}

/// Whether a raw image differs from the rectified one CameraInfo describes: distortion, a
/// rotation R, or P's intrinsics other than K's.
bool NeedsRectification(const RosCameraInfo& info) {
  const bool distorted = !AllZero(info.d);
  const bool rotated = !RectificationRotation(info).isIdentity(1e-12);
  bool k_is_p = true;
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 3; ++col) {
      k_is_p &= std::abs(info.k[static_cast<std::size_t>(3 * row + col)] - info.p[static_cast<std::size_t>(4 * row + col)]) < 1e-9;
    }
  }
  return distorted || rotated || !k_is_p;
}

/// Whether SSTA's Rectifier (CameraCalibration: pinhole K without skew, radial-tangential k1 k2
/// p1 p2) describes the raw camera: plumb_bob (or no model) whose further coefficients are 0.
bool RectifierTakes(const RosCameraInfo& info) {
  const std::string& m = info.distortion_model;
  if (!(m == "plumb_bob" || m == "rational_polynomial" || m.empty() || m == "Brown Conrady")) return false;
  const std::size_t n = info.d.size();
  if (n != 0 && n != 4 && n != 5 && n != 8 && n != 12 && n != 14) return false;  // MakeCameraModel says why
  for (std::size_t i = 4; i < info.d.size(); ++i) {
    if (info.d[i] != 0.0) return false;
  }
  return info.k[0] > 0 && info.k[4] > 0 && info.k[1] == 0.0 && info.k[3] == 0.0 && info.k[6] == 0.0 &&
         info.k[7] == 0.0 && info.k[8] == 1.0;
}

CameraModel MakeCameraModel(const RosCameraInfo& info, bool remap, const std::string& where) {
  if (info.width == 0 || info.height == 0) throw Error(where + ": the image size is 0 (an uncalibrated camera?)");
  if (!(info.p[0] > 0 && info.p[5] > 0)) {
    throw Error(where + ": P has no focal length (P[0] = " + std::to_string(info.p[0]) +
                "): the camera is not calibrated");
  }
  CameraModel model;
  model.info = info;
  model.remap = remap;
  if (!model.remap) return model;
  if (!(info.k[0] > 0 && info.k[4] > 0)) throw Error(where + ": K has no focal length: the camera is not calibrated");
  const bool all_zero_r = std::all_of(info.r.begin(), info.r.end(), [](double v) { return v == 0.0; });
  const cv::Mat k(3, 3, CV_64F, const_cast<double*>(info.k.data()));
  const cv::Mat r = all_zero_r ? cv::Mat::eye(3, 3, CV_64F) : cv::Mat(3, 3, CV_64F, const_cast<double*>(info.r.data()));
  const cv::Mat p(3, 4, CV_64F, const_cast<double*>(info.p.data()));
  const cv::Size size(static_cast<int>(info.width), static_cast<int>(info.height));
  const std::string& m = info.distortion_model;
  if (m == "equidistant" || m == "fisheye") {
    if (info.d.size() != 4) throw Error(where + ": the equidistant model needs 4 coefficients in D");
    cv::fisheye::initUndistortRectifyMap(k, cv::Mat(info.d), r, p.colRange(0, 3), size, CV_16SC2, model.map1, model.map2);
  } else if (m == "plumb_bob" || m == "rational_polynomial" || m.empty() || (m == "Brown Conrady" && info.d.size() == 5)) {
    const std::size_t n = info.d.size();
    if (n != 0 && n != 4 && n != 5 && n != 8 && n != 12 && n != 14) {
      throw Error(where + ": D has " + std::to_string(n) + " coefficients; OpenCV takes 4, 5, 8, 12 or 14");
    }
    cv::initUndistortRectifyMap(k, cv::Mat(info.d), r, p, size, CV_16SC2, model.map1, model.map2);
  } else {
    throw Error(where + ": distortion model '" + m +
                "' is not one SSTA rectifies (plumb_bob, rational_polynomial, equidistant)");
  }
  return model;
}

/// The raw camera as the Rectifier takes it: K and the first four coefficients of D.
CameraCalibration RawCamera(const RosCameraInfo& info, double rate_hz) {
  CameraCalibration c;
  c.width = static_cast<int>(info.width);
  c.height = static_cast<int>(info.height);
  c.fu = info.k[0];
  c.fv = info.k[4];
  c.cu = info.k[2];
  c.cv = info.k[5];
  for (std::size_t i = 0; i < 4 && i < info.d.size(); ++i) c.distortion[i] = info.d[i];
  c.rate_hz = rate_hz;
  return c;
}

/// The rectified camera the sequence's calibration describes (no distortion, intrinsics P).
CameraCalibration RectifiedCamera(const RosCameraInfo& info, double rate_hz) {
  CameraCalibration c;
  c.width = static_cast<int>(info.width);
  c.height = static_cast<int>(info.height);
  c.fu = info.p[0];
  c.fv = info.p[5];
  c.cu = info.p[2];
  c.cv = info.p[6];
  c.rate_hz = rate_hz;
  return c;
}

/// image_proc's outputs are image_rect, image_rect_color, image_rect_raw...: the topic's own
/// name, not a namespace that happens to hold "rect".
bool IsRectifiedTopic(std::string t) {
  if (t.size() > 11 && t.compare(t.size() - 11, 11, "/compressed") == 0) t.erase(t.size() - 11);
  return t.substr(t.rfind('/') + 1).rfind("image_rect", 0) == 0;
}

}  // namespace

StereoCameraInfo ReadStereoCameraInfo(const Topics& topics, const ChosenTopics& chosen) {
  const std::string& path = topics.bag().path();
  const auto decode_info = [](const std::vector<std::uint8_t>& b, RosEncoding e, const std::string& w) {
    return DecodeCameraInfo(b, e, w);
  };
  StereoCameraInfo out;
  out.left = FirstMessage(topics, chosen.left_info, decode_info);
  out.right = FirstMessage(topics, chosen.right_info, decode_info);
  // Raw images go to the pipeline raw, with K, D and the pair's relative pose from R and P, so
  // that the Rectifier rectifies and crops them as it does a folder's: the same recording gives
  // the same images in any container. Only distortion models it does not take are rectified
  // here, with P, as image_proc does.
  const bool left_rectified = IsRectifiedTopic(chosen.left);
  const bool right_rectified = IsRectifiedTopic(chosen.right);
  const std::array<bool, 2> needs = {!left_rectified && NeedsRectification(out.left),
                                     !right_rectified && NeedsRectification(out.right)};
  out.raw_pair = (needs[0] || needs[1]) && !left_rectified && !right_rectified && RectifierTakes(out.left) &&
                 RectifierTakes(out.right);
  out.cameras = {MakeCameraModel(out.left, needs[0] && !out.raw_pair, path + ": " + chosen.left_info),
                 MakeCameraModel(out.right, needs[1] && !out.raw_pair, path + ": " + chosen.right_info)};
  if (out.left.width != out.right.width || out.left.height != out.right.height) {
    throw Error(path + ": " + chosen.left_info + " and " + chosen.right_info + " give different image sizes");
  }
  // P of the right camera holds -fx * baseline (ROS's stereo convention).
  out.baseline_m = -out.right.p[3] / out.right.p[0];
  if (!(std::abs(out.baseline_m) > 1e-6)) {
    throw Error(path + ": " + chosen.right_info +
                ": P[3] is 0: not a stereo calibration (ROS puts -fx * baseline there; calibrate the pair with "
                "camera_calibration's stereo mode or ssta calibrate-stereo)");
  }
  return out;
}

void SetStereoCalibration(const StereoCameraInfo& info, const Eigen::Isometry3d& body_T_optical,
                          double left_rate_hz, double right_rate_hz, SequenceData* seq) {
  // The optical frame in /tf is the raw camera's; R turns it into the rectified one, and the
  // right rectified camera sits at +baseline along the left rectified x.
  const Eigen::Matrix3d left_R = RectificationRotation(info.left);
  const Eigen::Matrix3d right_R = RectificationRotation(info.right);
  if (info.raw_pair) {
    seq->calibration.left = RawCamera(info.left, left_rate_hz);
    seq->calibration.right = RawCamera(info.right, right_rate_hz);
    Eigen::Isometry3d left_T_right = Eigen::Isometry3d::Identity();
    left_T_right.linear() = left_R.transpose() * right_R;
    left_T_right.translation() = left_R.transpose() * Eigen::Vector3d(info.baseline_m, 0.0, 0.0);
    seq->calibration.left.body_T_camera = body_T_optical;
    seq->calibration.right.body_T_camera = body_T_optical * left_T_right;
    return;
  }
  Eigen::Isometry3d body_T_left = body_T_optical;
  body_T_left.linear() = body_T_optical.linear() * left_R.transpose();
  seq->calibration.left = RectifiedCamera(info.left, left_rate_hz);
  seq->calibration.right = RectifiedCamera(info.right, right_rate_hz);
  seq->calibration.left.body_T_camera = body_T_left;
  seq->calibration.right.body_T_camera = body_T_left * Eigen::Translation3d(info.baseline_m, 0.0, 0.0);
  if (info.cameras[0].remap || info.cameras[1].remap) {
    seq->notes.push_back("the '" + info.left.distortion_model + "' / '" + info.right.distortion_model +
                         "' distortion is rectified with CameraInfo's P as image_proc does, not by SSTA's "
                         "rectification: rectification.crop_to_common_area does not apply");
  }
}

}  // namespace ssta::internal
