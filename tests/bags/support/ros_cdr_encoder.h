#pragma once

// Test support: CDR encoders for the ROS 2 messages of src/bags/ros_messages.h, so that tests write
// bags from known messages and the decoders are checked against an independent writer.
//
// The bytes are the ROS 2 Humble layouts: the 4-byte encapsulation header 00 01 00 00 (CDR, little
// endian), then the fields with each primitive aligned to its size, counted from after the
// encapsulation header; builtin_interfaces/Time is int32 sec + uint32 nanosec; a string is a
// uint32 length that counts its NUL terminator, the bytes and the NUL; a sequence is a uint32
// count and its elements; fixed arrays have no count. Fields that ros_messages.h drops are
// written as zeros (covariances, binning, region of interest, the twist).

#include <cstdint>
#include <vector>

#include "bags/ros_messages.h"

namespace ssta::testing {

/// sensor_msgs/msg/Image: header, uint32 height, uint32 width, string encoding,
/// uint8 is_bigendian, uint32 step, uint8[] data.
std::vector<std::uint8_t> EncodeCdr(const internal::RosImage& image);

/// sensor_msgs/msg/CompressedImage: header, string format, uint8[] data.
std::vector<std::uint8_t> EncodeCdr(const internal::RosCompressedImage& image);

/// sensor_msgs/msg/CameraInfo: header, uint32 height, uint32 width, string distortion_model,
/// float64[] d, float64[9] k, float64[9] r, float64[12] p, uint32 binning_x, uint32 binning_y,
/// RegionOfInterest roi (uint32 x_offset, y_offset, height, width, bool do_rectify) = zeros.
std::vector<std::uint8_t> EncodeCdr(const internal::RosCameraInfo& info);

/// sensor_msgs/msg/Imu: header, Quaternion orientation (x y z w), float64[9]
/// orientation_covariance, Vector3 angular_velocity, float64[9] angular_velocity_covariance,
/// Vector3 linear_acceleration, float64[9] linear_acceleration_covariance (covariances zero).
std::vector<std::uint8_t> EncodeCdr(const internal::RosImu& imu);

/// nav_msgs/msg/Odometry: header, string child_frame_id, PoseWithCovariance (Point position,
/// Quaternion orientation, float64[36] covariance = 0), TwistWithCovariance (Vector3 linear,
/// Vector3 angular, float64[36] covariance; all zero).
std::vector<std::uint8_t> EncodeCdr(const internal::RosOdometry& odometry);

/// tf2_msgs/msg/TFMessage: TransformStamped[] transforms, each header, string child_frame_id,
/// Transform (Vector3 translation, Quaternion rotation).
std::vector<std::uint8_t> EncodeCdr(const std::vector<internal::RosTransform>& transforms);

}  // namespace ssta::testing
