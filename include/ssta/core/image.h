#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Core>

#include "ssta/core/error.h"

namespace ssta {

/// A dense row-major image of `T`, stored contiguously (row v starts at data() + v * width()).
/// Indexing is `(v, u)`: row first, like cv::Mat and Eigen, with v down and u right.
/// A value type: copies are deep. Not thread-safe for concurrent writers.
template <typename T>
class Image {
 public:
  Image() = default;
  Image(int width, int height, const T& fill = T{})
      : width_(width), height_(height),
        data_(static_cast<std::size_t>(Checked(width) * Checked(height)), fill) {}

  int width() const { return width_; }
  int height() const { return height_; }
  std::size_t size() const { return data_.size(); }
  bool empty() const { return data_.empty(); }

  T& operator()(int v, int u) { return data_[Index(v, u)]; }
  const T& operator()(int v, int u) const { return data_[Index(v, u)]; }
  T& operator[](std::size_t i) { return data_[i]; }
  const T& operator[](std::size_t i) const { return data_[i]; }

  T* data() { return data_.data(); }
  const T* data() const { return data_.data(); }
  T* row(int v) { return data_.data() + static_cast<std::size_t>(v) * width_; }
  const T* row(int v) const { return data_.data() + static_cast<std::size_t>(v) * width_; }

  bool Contains(int v, int u) const { return v >= 0 && u >= 0 && v < height_ && u < width_; }
  void Fill(const T& value) { data_.assign(data_.size(), value); }

 private:
  static long Checked(int n) {
    SSTA_CHECK(n >= 0, "image dimensions must not be negative");
    return n;
  }
  std::size_t Index(int v, int u) const {
    return static_cast<std::size_t>(v) * static_cast<std::size_t>(width_) +
           static_cast<std::size_t>(u);
  }

  int width_ = 0;
  int height_ = 0;
  std::vector<T> data_;
};

/// 8-bit colour pixel in R, G, B order.
struct Rgb8 {
  std::uint8_t r = 0, g = 0, b = 0;
  friend bool operator==(const Rgb8& a, const Rgb8& b) {
    return a.r == b.r && a.g == b.g && a.b == b.b;
  }
};

using ImageU8 = Image<std::uint8_t>;
using ImageU16 = Image<std::uint16_t>;
using ImageI32 = Image<std::int32_t>;
using ImageF = Image<float>;
using ImageRgb = Image<Rgb8>;

/// An organized point cloud or normal field: one 3D vector per pixel, all-NaN where invalid.
using Image3f = Image<Eigen::Vector3f>;

/// The invalid 3D point / normal value used throughout.
inline Eigen::Vector3f NanVector3f() {
  return Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
}

/// True when all three coordinates are finite.
inline bool IsFinite(const Eigen::Vector3f& p) { return p.allFinite(); }

}  // namespace ssta
