#include "bags/support/ros_cdr_encoder.h"

#include <cstring>
#include <string>

namespace ssta::testing {
namespace {

using internal::RosHeader;

/// CDR little endian with its encapsulation header; alignment counts from after that header.
class CdrWriter {
 public:
  CdrWriter() : bytes_{0x00, 0x01, 0x00, 0x00} {}

  void U8(std::uint8_t v) { bytes_.push_back(v); }
  void U32(std::uint32_t v) { Primitive(v); }
  void I32(std::int32_t v) { Primitive(v); }
  void F64(double v) { Primitive(v); }
  void String(const std::string& s) {
    U32(static_cast<std::uint32_t>(s.size() + 1));
    bytes_.insert(bytes_.end(), s.begin(), s.end());
    bytes_.push_back(0);
  }
  void ByteSequence(const std::vector<std::uint8_t>& data) {
    U32(static_cast<std::uint32_t>(data.size()));
    bytes_.insert(bytes_.end(), data.begin(), data.end());
  }
  template <typename Doubles>
  void F64s(const Doubles& values) {
    for (double v : values) F64(v);
  }
  void Zeros(int count) {
    for (int i = 0; i < count; ++i) F64(0.0);
  }
  void Header(const RosHeader& header) {
    // builtin_interfaces/Time: floor division keeps nanosec in [0, 1e9) for times before 1970.
    std::int64_t sec = header.stamp_ns / 1000000000;
    std::int64_t nsec = header.stamp_ns % 1000000000;
    if (nsec < 0) {
      nsec += 1000000000;
      sec -= 1;
    }
    I32(static_cast<std::int32_t>(sec));
    U32(static_cast<std::uint32_t>(nsec));
    String(header.frame_id);
  }
  std::vector<std::uint8_t> Take() { return std::move(bytes_); }

 private:
  template <typename T>
  void Primitive(T v) {
    while ((bytes_.size() - 4) % sizeof(T) != 0) bytes_.push_back(0);
    std::uint8_t raw[sizeof(T)];
    std::memcpy(raw, &v, sizeof(T));  // the test machines are little endian, as CDR LE is
    bytes_.insert(bytes_.end(), raw, raw + sizeof(T));
  }

  std::vector<std::uint8_t> bytes_;
};

}  // namespace

std::vector<std::uint8_t> EncodeCdr(const internal::RosImage& image) {
  CdrWriter w;
  w.Header(image.header);
  w.U32(image.height);
  w.U32(image.width);
  w.String(image.encoding);
  w.U8(image.big_endian ? 1 : 0);
  w.U32(image.step);
  w.ByteSequence(image.data);
  return w.Take();
}

std::vector<std::uint8_t> EncodeCdr(const internal::RosCompressedImage& image) {
  CdrWriter w;
  w.Header(image.header);
  w.String(image.format);
  w.ByteSequence(image.data);
  return w.Take();
}

std::vector<std::uint8_t> EncodeCdr(const internal::RosCameraInfo& info) {
  CdrWriter w;
  w.Header(info.header);
  w.U32(info.height);
  w.U32(info.width);
  w.String(info.distortion_model);
  w.U32(static_cast<std::uint32_t>(info.d.size()));
  w.F64s(info.d);
  w.F64s(info.k);
  w.F64s(info.r);
  w.F64s(info.p);
  w.U32(0);  // binning_x
  w.U32(0);  // binning_y
  for (int i = 0; i < 4; ++i) w.U32(0);  // roi: x_offset, y_offset, height, width
  w.U8(0);                               // roi.do_rectify
  return w.Take();
}

std::vector<std::uint8_t> EncodeCdr(const internal::RosImu& imu) {
  CdrWriter w;
  w.Header(imu.header);
  w.F64s(imu.orientation_xyzw);
  w.Zeros(9);
  w.F64s(imu.angular_velocity);
  w.Zeros(9);
  w.F64s(imu.linear_acceleration);
  w.Zeros(9);
  return w.Take();
}

std::vector<std::uint8_t> EncodeCdr(const internal::RosOdometry& odometry) {
  CdrWriter w;
  w.Header(odometry.header);
  w.String(odometry.child_frame_id);
  w.F64s(odometry.position);
  w.F64s(odometry.orientation_xyzw);
  w.Zeros(36);     // pose.covariance
  w.Zeros(3 + 3);  // twist.twist: linear, angular
  w.Zeros(36);     // twist.covariance
  return w.Take();
}

std::vector<std::uint8_t> EncodeCdr(const std::vector<internal::RosTransform>& transforms) {
  CdrWriter w;
  w.U32(static_cast<std::uint32_t>(transforms.size()));
  for (const internal::RosTransform& t : transforms) {
    w.Header(t.header);
    w.String(t.child_frame_id);
    w.F64s(t.translation);
    w.F64s(t.rotation_xyzw);
  }
  return w.Take();
}

}  // namespace ssta::testing
