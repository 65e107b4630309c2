#include "ros_messages.h"

#include <cmath>
#include <cstring>

#include "ssta/core/error.h"

namespace ssta::internal {
namespace {

/// Reads the fields of one serialized message in order. ROS 1 fields are packed; CDR fields
/// are aligned to their size, counted from the end of the 4-byte encapsulation header.
class FieldReader {
 public:
  FieldReader(const std::vector<std::uint8_t>& bytes, RosEncoding encoding, const std::string& where)
      : bytes_(bytes), cdr_(encoding == RosEncoding::kCdr), where_(where) {
    if (!cdr_) return;
    if (bytes_.size() < 4) Fail("shorter than the 4-byte CDR encapsulation header");
    // 00 01: CDR little endian; 00 03: parameter-list CDR little endian (same body for these
    // types). 00 00 and 00 02 are big endian, which no ROS 2 middleware on x86 or ARM writes.
    if (bytes_[0] != 0 || (bytes_[1] != 1 && bytes_[1] != 3)) {
      Fail("CDR encapsulation " + std::to_string(bytes_[0]) + " " + std::to_string(bytes_[1]) +
           " is not read (plain little-endian CDR is 00 01; big-endian and XCDR2 are not read)");
    }
    pos_ = origin_ = 4;
  }

  std::uint8_t U8() { return Scalar<std::uint8_t>(); }
  std::uint32_t U32() { return Scalar<std::uint32_t>(); }
  std::int32_t I32() { return Scalar<std::int32_t>(); }
  double F64() { return Scalar<double>(); }

  std::int64_t Time() {
    if (cdr_) {
      const std::int64_t sec = I32();
      const std::int64_t nsec = U32();
      return sec * 1'000'000'000 + nsec;
    }
    const std::int64_t sec = U32();
    const std::int64_t nsec = U32();
    return sec * 1'000'000'000 + nsec;
  }

  std::string String() {
    const std::uint32_t n = U32();
    Need(n, "string");
    std::string s(reinterpret_cast<const char*>(bytes_.data() + pos_), n);
    pos_ += n;
    // CDR counts the terminating NUL; ROS 1 does not write one.
    if (cdr_ && !s.empty() && s.back() == '\0') s.pop_back();
    return s;
  }

  std::vector<std::uint8_t> Bytes() {
    const std::uint32_t n = U32();
    Need(n, "byte array");
    std::vector<std::uint8_t> out(bytes_.begin() + static_cast<std::ptrdiff_t>(pos_),
                                  bytes_.begin() + static_cast<std::ptrdiff_t>(pos_ + n));
    pos_ += n;
    return out;
  }

  std::vector<double> Doubles() {
    const std::uint32_t n = U32();
    Need(static_cast<std::uint64_t>(n) * 8, "float64 array");
    std::vector<double> out(n);
    for (auto& v : out) v = F64();
    return out;
  }

  template <std::size_t N>
  std::array<double, N> FixedDoubles() {
    std::array<double, N> out{};
    for (auto& v : out) v = F64();
    return out;
  }

  /// A sequence's element count, checked against the bytes left (each element >= min_bytes).
  std::uint32_t Count(std::size_t min_bytes, const char* what) {
    const std::uint32_t n = U32();
    Need(static_cast<std::uint64_t>(n) * min_bytes, what);
    return n;
  }

  RosHeader Header() {
    RosHeader h;
    if (!cdr_) U32();  // seq
    h.stamp_ns = Time();
    h.frame_id = String();
    return h;
  }

  [[noreturn]] void Fail(const std::string& what) const { throw Error(where_ + ": " + what); }

 private:
  template <typename T>
  T Scalar() {
    if (cdr_) pos_ = origin_ + (pos_ - origin_ + sizeof(T) - 1) / sizeof(T) * sizeof(T);
    Need(sizeof(T), "value");
    T value;
    std::memcpy(&value, bytes_.data() + pos_, sizeof(T));  // both encodings: little endian
    pos_ += sizeof(T);
    return value;
  }

  void Need(std::uint64_t n, const char* what) const {
    if (pos_ > bytes_.size() || n > bytes_.size() - pos_) {
      Fail(std::string("message ends early (a ") + what + " of " + std::to_string(n) + " bytes at byte " +
           std::to_string(pos_) + " of " + std::to_string(bytes_.size()) + ")");
    }
  }

  const std::vector<std::uint8_t>& bytes_;
  bool cdr_;
  const std::string& where_;
  std::size_t pos_ = 0;
  std::size_t origin_ = 0;
};

template <typename Array>
void RequireFinite(const Array& values, const char* field, const FieldReader& in) {
  for (double v : values) {
    if (!std::isfinite(v)) in.Fail(std::string(field) + " holds NaN or infinity");
  }
}

std::array<double, 4> Quaternion(FieldReader& in) { return in.FixedDoubles<4>(); }  // x, y, z, w

}  // namespace

RosHeader DecodeHeader(const std::vector<std::uint8_t>& bytes, RosEncoding encoding, const std::string& where) {
  FieldReader in(bytes, encoding, where);
  return in.Header();
}

RosImage DecodeImage(const std::vector<std::uint8_t>& bytes, RosEncoding encoding, const std::string& where) {
  FieldReader in(bytes, encoding, where);
  RosImage m;
  m.header = in.Header();
  m.height = in.U32();
  m.width = in.U32();
  m.encoding = in.String();
  m.big_endian = in.U8() != 0;
  m.step = in.U32();
  m.data = in.Bytes();
  return m;
}

RosCompressedImage DecodeCompressedImage(const std::vector<std::uint8_t>& bytes, RosEncoding encoding,
                                         const std::string& where) {
  FieldReader in(bytes, encoding, where);
  RosCompressedImage m;
  m.header = in.Header();
  m.format = in.String();
  m.data = in.Bytes();
  return m;
}

RosCameraInfo DecodeCameraInfo(const std::vector<std::uint8_t>& bytes, RosEncoding encoding,
                               const std::string& where) {
  FieldReader in(bytes, encoding, where);
  RosCameraInfo m;
  m.header = in.Header();
  m.height = in.U32();
  m.width = in.U32();
  m.distortion_model = in.String();
  m.d = in.Doubles();
  m.k = in.FixedDoubles<9>();
  m.r = in.FixedDoubles<9>();
  m.p = in.FixedDoubles<12>();
  // binning and region of interest follow; SSTA reads full-resolution images only.
  RequireFinite(m.d, "D", in);
  RequireFinite(m.k, "K", in);
  RequireFinite(m.r, "R", in);
  RequireFinite(m.p, "P", in);
  return m;
}

RosImu DecodeImu(const std::vector<std::uint8_t>& bytes, RosEncoding encoding, const std::string& where) {
  FieldReader in(bytes, encoding, where);
  RosImu m;
  m.header = in.Header();
  m.orientation_xyzw = Quaternion(in);
  in.FixedDoubles<9>();
  m.angular_velocity = in.FixedDoubles<3>();
  in.FixedDoubles<9>();
  m.linear_acceleration = in.FixedDoubles<3>();
  RequireFinite(m.angular_velocity, "angular_velocity", in);
  RequireFinite(m.linear_acceleration, "linear_acceleration", in);
  return m;
}

RosOdometry DecodeOdometry(const std::vector<std::uint8_t>& bytes, RosEncoding encoding, const std::string& where) {
  FieldReader in(bytes, encoding, where);
  RosOdometry m;
  m.header = in.Header();
  m.child_frame_id = in.String();
  m.position = in.FixedDoubles<3>();
  m.orientation_xyzw = Quaternion(in);
  RequireFinite(m.position, "pose.position", in);
  RequireFinite(m.orientation_xyzw, "pose.orientation", in);
  return m;  // covariance and twist follow, unused
}

std::vector<RosTransform> DecodeTfMessage(const std::vector<std::uint8_t>& bytes, RosEncoding encoding,
                                          const std::string& where) {
  FieldReader in(bytes, encoding, where);
  // Each TransformStamped holds at least a time, two string lengths and seven float64.
  const std::uint32_t n = in.Count(8 + 4 + 4 + 7 * 8, "transforms array");
  std::vector<RosTransform> out(n);
  for (auto& t : out) {
    t.header = in.Header();
    t.child_frame_id = in.String();
    t.translation = in.FixedDoubles<3>();
    t.rotation_xyzw = Quaternion(in);
    RequireFinite(t.translation, "transform.translation", in);
    RequireFinite(t.rotation_xyzw, "transform.rotation", in);
  }
  return out;
}

}  // namespace ssta::internal
