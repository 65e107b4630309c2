#pragma once

// Private: ROS 2 messages serialized as CDR (XCDR1, little endian), as rosbag2 stores them: the
// 4-byte encapsulation header 00 01 00 00, then the fields, each primitive aligned to its size
// counted from after that header; a string is a uint32 length counting its NUL, the bytes and the
// NUL; a sequence a uint32 count and its elements; a fixed array its elements only.

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace ssta::internal {

class CdrWriter {
 public:
  CdrWriter() : bytes_{0x00, 0x01, 0x00, 0x00} {}

  void U8(std::uint8_t v) { bytes_.push_back(v); }
  void I8(std::int8_t v) { bytes_.push_back(static_cast<std::uint8_t>(v)); }
  void U16(std::uint16_t v) { Primitive(v); }
  void U32(std::uint32_t v) { Primitive(v); }
  void I32(std::int32_t v) { Primitive(v); }
  void F32(float v) { Primitive(v); }
  void F64(double v) { Primitive(v); }
  void String(const std::string& s) {
    U32(static_cast<std::uint32_t>(s.size() + 1));
    bytes_.insert(bytes_.end(), s.begin(), s.end());
    bytes_.push_back(0);
  }
  /// builtin_interfaces/Time from nanoseconds: int32 sec (floor) + uint32 nanosec in [0, 1e9).
  void Time(std::int64_t ns) {
    std::int64_t sec = ns / 1000000000;
    std::int64_t nsec = ns % 1000000000;
    if (nsec < 0) {
      nsec += 1000000000;
      sec -= 1;
    }
    I32(static_cast<std::int32_t>(sec));
    U32(static_cast<std::uint32_t>(nsec));
  }
  /// std_msgs/Header.
  void Header(std::int64_t stamp_ns, const std::string& frame_id) {
    Time(stamp_ns);
    String(frame_id);
  }
  /// Raw bytes (the elements of a uint8 / int8 sequence after its count).
  void Bytes(const std::uint8_t* data, std::size_t n) { bytes_.insert(bytes_.end(), data, data + n); }
  /// The elements of a float32 sequence after its count (aligned once, then packed).
  void F32s(const float* data, std::size_t n) {
    Align(4);
    const std::size_t at = bytes_.size();
    bytes_.resize(at + 4 * n);
    if (n > 0) std::memcpy(bytes_.data() + at, data, 4 * n);  // little-endian hosts, as CDR LE
  }
  std::vector<std::uint8_t> Take() { return std::move(bytes_); }

 private:
  void Align(std::size_t n) {
    while ((bytes_.size() - 4) % n != 0) bytes_.push_back(0);
  }
  template <typename T>
  void Primitive(T v) {
    static_assert(sizeof(T) <= 8, "CDR primitives are at most 8 bytes");
    Align(sizeof(T));
    std::uint8_t raw[sizeof(T)];
    std::memcpy(raw, &v, sizeof(T));  // little-endian hosts, as CDR LE
    bytes_.insert(bytes_.end(), raw, raw + sizeof(T));
  }

  std::vector<std::uint8_t> bytes_;
};

}  // namespace ssta::internal
