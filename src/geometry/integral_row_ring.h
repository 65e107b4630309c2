#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace ssta {
namespace internal {

/// The rows of a C-channel integral image (summed-area table) that a sweep over output rows
/// needs, kept in a ring instead of the whole table: output row v with window radii <= R
/// reads integral rows v - R .. v + R + 1, so 2R + 2 rows suffice. At 640 px, 13 x 13 windows
/// and 10 channels that is ~0.7 MB (cache-resident) instead of ~25 MB for the whole table.
///
/// Integral row j (0 <= j <= height) holds, at column i (0 <= i <= width), the sums over image
/// rows < j and columns < i, channel-planar: channel k of column i is at Row(j)[k * plane() + i]
/// (so strips and boxes of one channel are contiguous and vectorise). T is an unsigned integer
/// type: sums wrap modulo 2^bits and box differences are still exact as long as the box's true sum
/// fits the signed type (callers choose their fixed-point scale for that), whatever the magnitude
/// of the running totals.
template <typename T, int C>
class IntegralRowRing {
 public:
  void Reset(int width, int height, int max_radius) {
    width_ = width;
    height_ = height;
    plane_ = static_cast<std::size_t>(width) + 1;
    stride_ = plane_ * C;
    slots_ = std::min(2 * max_radius + 2, height + 1);
    data_.resize(stride_ * slots_);
    next_row_ = 0;
  }

  /// Builds integral rows up to `row` (clamped to height). `add(v, u, acc)` adds pixel (v, u)'s
  /// C channel values to acc[0..C); rows are built in order, each once.
  template <typename AddPixel>
  void BuildUpTo(int row, AddPixel&& add) {
    row = std::min(row, height_);
    for (; next_row_ <= row; ++next_row_) {
      T* cur = Slot(next_row_);
      if (next_row_ == 0) {
        std::fill(cur, cur + stride_, T{0});
        continue;
      }
      const T* prev = Slot(next_row_ - 1);
      const int v = next_row_ - 1;
      T acc[C] = {};
      for (int k = 0; k < C; ++k) cur[k * plane_] = T{0};
      for (int u = 0; u < width_; ++u) {
        add(v, u, acc);
        const std::size_t i = static_cast<std::size_t>(u) + 1;
        for (int k = 0; k < C; ++k)
          cur[k * plane_ + i] = static_cast<T>(prev[k * plane_ + i] + acc[k]);
      }
    }
  }

  /// Distance between the channel planes of a row (width + 1).
  std::size_t plane() const { return plane_; }
  /// Values per integral row (all channels).
  std::size_t row_size() const { return stride_; }

  /// Integral row j; it must have been built and not yet overwritten (j > last built - slots).
  const T* Row(int j) const {
    return data_.data() + stride_ * static_cast<std::size_t>(j % slots_);
  }

 private:
  T* Slot(int j) { return data_.data() + stride_ * static_cast<std::size_t>(j % slots_); }

  int width_ = 0;
  int height_ = 0;
  std::size_t plane_ = 0;
  std::size_t stride_ = 0;
  int slots_ = 1;
  int next_row_ = 0;
  std::vector<T> data_;
};

}  // namespace internal
}  // namespace ssta
