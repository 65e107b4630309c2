#pragma once

// Private: a bag's stereo calibration from its two CameraInfo topics, and each camera's
// rectification when the images must be rectified on read (docs/bags.md).

#include <array>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "bags/ros_messages.h"
#include "bags/topic_choice.h"
#include "ssta/io/sequence.h"

namespace ssta::internal {

/// One camera's rectification from its CameraInfo, as ROS's image_proc does it: the raw image
/// through K and D, rotated by R, reprojected with P. Used only for the distortion models the
/// Rectifier does not take (RectifierTakes); the others reach the pipeline's Rectifier raw.
struct CameraModel {
  RosCameraInfo info;
  bool remap = false;  ///< the images are raw: rectify them with `map1`, `map2`
  cv::Mat map1, map2;
};

/// The stereo pair as its CameraInfo messages describe it.
struct StereoCameraInfo {
  RosCameraInfo left, right;           ///< the first message of each CameraInfo topic
  std::array<CameraModel, 2> cameras;  ///< left, right: how images are rectified on read
  /// The images go to the pipeline raw with K, D and the relative pose (the Rectifier rectifies
  /// them as it does a folder's); else they are rectified ones, described by P.
  bool raw_pair = false;
  double baseline_m = 0.0;  ///< from the right camera's P (-fx * baseline in P[3]) [m]
};

/// Reads the first CameraInfo of each camera (drivers repeat the same one) and decides how the
/// images are rectified. Throws ssta::Error naming the bag and topic for an uncalibrated camera,
/// a distortion model SSTA cannot rectify, different image sizes or a P without a baseline.
StereoCameraInfo ReadStereoCameraInfo(const Topics& topics, const ChosenTopics& chosen);

/// Sets `seq->calibration` from the CameraInfo: the raw cameras (K, D, the pair's relative pose
/// from R and P) or the rectified ones (P), the left optical frame at `body_T_optical` (the raw
/// camera's frame as /tf names it). Notes in `seq->notes` when the images are rectified with P.
void SetStereoCalibration(const StereoCameraInfo& info, const Eigen::Isometry3d& body_T_optical,
                          double left_rate_hz, double right_rate_hz, SequenceData* seq);

}  // namespace ssta::internal
