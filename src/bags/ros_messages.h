#pragma once

// Private: the ROS messages a stereo sequence is made of, decoded from their serialized bytes
// (ROS 1 serialization or CDR, the two differ in alignment, the time type and the header's seq).
// Only the fields SSTA uses are kept. Each Decode throws ssta::Error naming `where` (a file and
// message) when the bytes end early, a length is impossible, or a value is not finite.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "ssta/core/image.h"

namespace ssta::internal {

/// How a message's bytes are laid out.
enum class RosEncoding {
  kRos1,  ///< ROS 1: little-endian, packed, time as uint32 sec + uint32 nsec, Header has seq
  kCdr,   ///< ROS 2: 4-byte encapsulation header, then CDR (aligned), time as int32 + uint32
};

struct RosHeader {
  std::int64_t stamp_ns = 0;
  std::string frame_id;
};

/// sensor_msgs/Image.
struct RosImage {
  RosHeader header;
  std::uint32_t height = 0;
  std::uint32_t width = 0;
  std::string encoding;  ///< "mono8", "mono16", "rgb8", "bgr8", "bgra8", "bayer_bggr8", ...
  bool big_endian = false;
  std::uint32_t step = 0;  ///< bytes per row
  std::vector<std::uint8_t> data;
};

/// sensor_msgs/CompressedImage.
struct RosCompressedImage {
  RosHeader header;
  std::string format;  ///< "jpeg", "png", "rgb8; jpeg compressed bgr8", ...
  std::vector<std::uint8_t> data;
};

/// sensor_msgs/CameraInfo (the ROS 2 field names d, k, r, p are ROS 1's D, K, R, P).
struct RosCameraInfo {
  RosHeader header;
  std::uint32_t height = 0;
  std::uint32_t width = 0;
  std::string distortion_model;  ///< "plumb_bob", "rational_polynomial", "equidistant", ...
  std::vector<double> d;
  std::array<double, 9> k{};
  std::array<double, 9> r{};
  std::array<double, 12> p{};
};

/// sensor_msgs/Imu (covariances dropped).
struct RosImu {
  RosHeader header;
  std::array<double, 4> orientation_xyzw{0, 0, 0, 1};
  std::array<double, 3> angular_velocity{};     ///< [rad/s]
  std::array<double, 3> linear_acceleration{};  ///< [m/s^2]
};

/// geometry_msgs/TransformStamped (one element of tf2_msgs/TFMessage).
struct RosTransform {
  RosHeader header;  ///< frame_id: the parent frame
  std::string child_frame_id;
  std::array<double, 3> translation{};
  std::array<double, 4> rotation_xyzw{0, 0, 0, 1};
};

/// nav_msgs/Odometry (the pose part; covariance and twist dropped).
struct RosOdometry {
  RosHeader header;  ///< frame_id: the world (odom) frame
  std::string child_frame_id;  ///< the body frame
  std::array<double, 3> position{};
  std::array<double, 4> orientation_xyzw{0, 0, 0, 1};
};

RosImage DecodeImage(const std::vector<std::uint8_t>& bytes, RosEncoding encoding, const std::string& where);
RosCompressedImage DecodeCompressedImage(const std::vector<std::uint8_t>& bytes, RosEncoding encoding,
                                         const std::string& where);
RosCameraInfo DecodeCameraInfo(const std::vector<std::uint8_t>& bytes, RosEncoding encoding, const std::string& where);
RosImu DecodeImu(const std::vector<std::uint8_t>& bytes, RosEncoding encoding, const std::string& where);
RosOdometry DecodeOdometry(const std::vector<std::uint8_t>& bytes, RosEncoding encoding, const std::string& where);
/// tf2_msgs/TFMessage (the /tf and /tf_static topics).
std::vector<RosTransform> DecodeTfMessage(const std::vector<std::uint8_t>& bytes, RosEncoding encoding,
                                          const std::string& where);
/// Only the header at the start of any stamped message (cheap: the payload is not read).
RosHeader DecodeHeader(const std::vector<std::uint8_t>& bytes, RosEncoding encoding, const std::string& where);

}  // namespace ssta::internal
