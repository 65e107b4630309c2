#pragma once

// Test support: a sequence as the ROS messages a stereo robot records, written as a ROS 1 bag
// with rosbag's own C++ API and the ROS message packages, or as a ROS 2 bag with the tests'
// rosbag2 writer (independent writers for the readers in src/bags).

#include <array>
#include <string>
#include <vector>

#include "bags/ros_messages.h"
#include "bags/support/ros2_bag_writer.h"
#include "ssta/io/sequence.h"

namespace ssta::testing {

/// Frame names the bags of these tests use.
inline constexpr const char* kBodyFrame = "base_link";
inline constexpr const char* kWorldFrame = "odom";
inline constexpr const char* kLeftFrame = "left_camera_optical_frame";
inline constexpr const char* kRightFrame = "right_camera_optical_frame";
inline constexpr const char* kImuFrame = "imu_link";

/// Topic names (a typical stereo driver's).
inline constexpr const char* kLeftImage = "/stereo/left/image_raw";
inline constexpr const char* kRightImage = "/stereo/right/image_raw";
inline constexpr const char* kLeftInfo = "/stereo/left/camera_info";
inline constexpr const char* kRightInfo = "/stereo/right/camera_info";
inline constexpr const char* kImu = "/imu/data";
inline constexpr const char* kOdometry = "/odom";

struct BagContent {
  std::vector<internal::RosImage> left, right;  ///< mono8
  internal::RosCameraInfo left_info, right_info;
  std::vector<internal::RosImu> imu;
  std::vector<internal::RosOdometry> odometry;   ///< odom -> base_link
  std::vector<internal::RosTransform> tf_static;  ///< base_link -> left camera, base_link -> imu
};

/// An ASL sequence as messages: mono8 images as the files hold them, CameraInfo with the ROS
/// stereo convention (P[3] = -fx * baseline on the right; a raw pair's K, D, and R, P as ROS's
/// camera_calibration computes them), IMU, Odometry, the mounts on /tf_static.
BagContent ContentFromSequence(const Sequence& asl);

/// The CameraInfo of both cameras of a raw (distorted, unrectified) pair: K, plumb_bob D, and
/// R, P from cv::stereoRectify (zero disparity, alpha 0), as camera_calibration writes them.
std::array<internal::RosCameraInfo, 2> RawInfos(const StereoCalibration& c, std::int64_t stamp);

/// The CameraInfo of a rectified camera (D all zero, R identity, K = P's left 3x3).
internal::RosCameraInfo RectifiedInfo(const CameraCalibration& c, double tx, const std::string& frame, std::int64_t stamp);

enum class Ros1Compression { kNone, kBz2, kLz4 };

/// Writes `content` as a ROS 1 bag with rosbag::Bag (messages at their header stamps; each
/// CameraInfo written with every image, as drivers do).
void WriteRos1Bag(const BagContent& content, const std::string& path, Ros1Compression compression = Ros1Compression::kNone);

/// Writes `content` as a ROS 2 bag folder (Ros2BagWriter, messages as CDR), in the same order;
/// returns where the MCAP chunks landed (none for sqlite3).
std::vector<McapChunkSpan> WriteRos2Bag(const BagContent& content, const std::string& folder,
                                        const Ros2BagWriterOptions& options = {});

}  // namespace ssta::testing
