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
  ///
  /// `first_row` lets a sweep over a band of output rows start part-way down the image: integral
  /// row `first_row` is taken as all zeros, i.e. every row holds its true sums minus those of
  /// integral row `first_row`. Box sums between rows >= first_row are differences, so they are
  /// exactly the same as from a ring started at row 0 (the offset cancels modulo 2^bits). A band
  /// of output rows [v0, v1) with radii <= R starts at first_row = max(0, v0 - R).
  void Reset(int width, int height, int max_radius, int first_row = 0) {
    width_ = width;
    height_ = height;
    plane_ = static_cast<std::size_t>(width) + 1;
    stride_ = plane_ * C;
    slots_ = std::min(2 * max_radius + 2, height + 1);
    data_.resize(stride_ * slots_);
    first_row_ = std::clamp(first_row, 0, height);
    next_row_ = first_row_;
  }

  /// Builds integral rows up to `row` (clamped to height). `add(v, u, acc)` adds pixel (v, u)'s
  /// C channel values to acc[0..C); rows are built in order, each once.
  template <typename AddPixel>
  void BuildUpTo(int row, AddPixel&& add) {
    row = std::min(row, height_);
    for (; next_row_ <= row; ++next_row_) {
      T* cur = Slot(next_row_);
      if (next_row_ == first_row_) {
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

  /// Integral row j; it must have been built and not yet overwritten (j > last built - slots),
  /// and j >= first_row.
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
  int first_row_ = 0;
  int next_row_ = 0;
  std::vector<T> data_;
};

}  // namespace internal
}  // namespace ssta
