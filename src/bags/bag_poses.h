#pragma once

// Private: what a bag says about where things are: the /tf tree, the body's poses (Odometry or
// /tf) and the camera and IMU mounts in the body frame (docs/bags.md).

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "bags/tf_tree.h"
#include "bags/topic_choice.h"
#include "ssta/io/sequence.h"

namespace ssta::internal {

/// Every transform on /tf_static and /tf. A transform whose rotation is not a quaternion (a
/// misconfigured static_transform_publisher's 0 0 0 0) is left out with a note in `notes`, as
/// tf2 ignores it: it breaks only the chains through its link, which then report their absence.
TfTree ReadTf(const Topics& topics, std::vector<std::string>* notes);

/// Reads the poses T_WB the chosen pose source gives into `seq->poses` (Odometry carried to the
/// body frame through /tf_static when they differ; /tf when chosen, or when it moves the body
/// frame in a bag without Odometry) and returns the body frame: --pose-frame, else the
/// Odometry's child frame, else base_link or base_footprint when /tf has them ("" when none).
/// `first_stamp_ns` is when the static mounts are looked up. Throws ssta::Error naming the bag
/// and topic.
std::string ReadPoses(const Topics& topics, const ChosenTopics& chosen, const TfTree& tf, std::int64_t first_stamp_ns,
                      SequenceData* seq);

/// Where the left camera sits in the body frame.
struct CameraMount {
  /// The raw left camera's optical frame in the body frame; assumed looking along body x at the
  /// body origin when /tf has no transform to it.
  Eigen::Isometry3d body_T_optical = Eigen::Isometry3d::Identity();
  bool from_tf = false;  ///< `body_T_optical` came from /tf (else it is the assumed one)
  /// The frame other mounts are looked up in: the body frame, or the camera frame when the
  /// mount is assumed (they are then carried through the assumed mount).
  std::string frame;
};

/// The left camera's mount: /tf's transform from `body` to `camera_frame` at `stamp_ns`, else
/// the assumed one with a note in `notes`.
CameraMount FindCameraMount(const TfTree& tf, const std::string& body, const std::string& camera_frame,
                            std::int64_t stamp_ns, std::vector<std::string>* notes);

/// Sets `seq->body_T_imu` from /tf (the IMU's frame `imu_frame` in the mount's frame, or in the
/// body frame /tf knows); notes in `seq->notes` when /tf has none and the IMU axes are taken as
/// the body axes.
void SetImuMount(const TfTree& tf, const CameraMount& mount, const std::string& body, const std::string& imu_frame,
                 std::int64_t stamp_ns, SequenceData* seq);

}  // namespace ssta::internal
