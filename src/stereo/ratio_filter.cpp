#include "ratio_filter.h"

#include <algorithm>
#include <cstdlib>
#include <limits>
#include <vector>

#include "ssta/core/error.h"

namespace ssta::internal {
namespace {

/// Summed-area table with one row and column of zeros in front: table(v + 1, u + 1) holds the
/// sum of values(0..v, 0..u).
void BuildIntegral(const ImageI32& values, ImageI32* table) {
  const int w = values.width();
  for (int v = 0; v < values.height(); ++v) {
    const std::int32_t* src = values.row(v);
    const std::int32_t* above = table->row(v) ;
    std::int32_t* dst = table->row(v + 1);
    std::int32_t row_sum = 0;
    dst[0] = 0;
    for (int u = 0; u < w; ++u) {
      row_sum += src[u];
      dst[u + 1] = above[u + 1] + row_sum;
    }
  }
}

}  // namespace

void ApplyRatioFilter(const ImageU8& left, const ImageU8& right, int radius, int num_disparities,
                      int x_offset, int ratio_percent, ImageI32* index) {
  SSTA_CHECK(index != nullptr, "ApplyRatioFilter: index must not be null");
  SSTA_CHECK(left.width() == right.width() && left.height() == right.height() &&
                 index->width() == left.width() && index->height() == left.height(),
             "ApplyRatioFilter: images and index must have the same size");
  SSTA_CHECK(radius >= 0 && num_disparities > 0 && x_offset >= 0 && ratio_percent >= 0 &&
                 ratio_percent <= 100,
             "ApplyRatioFilter: bad parameters");
  const int w = left.width();
  const int h = left.height();
  if (w == 0 || h == 0) return;

  // Per pixel: cost at d_best and the smallest cost away from it.
  constexpr std::int64_t kNone = std::numeric_limits<std::int64_t>::max();
  std::vector<std::int64_t> best(left.size(), kNone);
  std::vector<std::int64_t> second(left.size(), kNone);

  ImageI32 diff(w, h);
  ImageI32 table(w + 1, h + 1);  // row 0 stays zero
  for (int d = 0; d < num_disparities; ++d) {
    const int shift = x_offset + d;
    if (shift >= w) break;
    for (int v = 0; v < h; ++v) {
      const std::uint8_t* l = left.row(v);
      const std::uint8_t* r = right.row(v);
      std::int32_t* out = diff.row(v);
      // Columns without a partner in the right image contribute nothing; pixels whose window
      // reaches them are skipped below.
      std::fill(out, out + std::min(shift, w), 0);
      for (int u = shift; u < w; ++u) out[u] = std::abs(int{l[u]} - int{r[u - shift]});
    }
    BuildIntegral(diff, &table);
    for (int v = 0; v < h; ++v) {
      const int v0 = std::max(0, v - radius);
      const int v1 = std::min(h - 1, v + radius);
      const std::int32_t* idx = index->row(v);
      for (int u = 0; u < w; ++u) {
        const int d_best = idx[u];
        if (d_best < 0 || std::abs(d - d_best) == 1) continue;
        const int u0 = std::max(0, u - radius);
        const int u1 = std::min(w - 1, u + radius);
        if (u0 < shift) continue;  // the window would leave the right image
        const std::int64_t cost = std::int64_t{table(v1 + 1, u1 + 1)} - table(v0, u1 + 1) -
                                  table(v1 + 1, u0) + table(v0, u0);
        const std::size_t i = static_cast<std::size_t>(v) * w + u;
        if (d == d_best) {
          best[i] = cost;
        } else {
          second[i] = std::min(second[i], cost);
        }
      }
    }
  }

  for (std::size_t i = 0; i < index->size(); ++i) {
    std::int32_t& d_best = (*index)[i];
    if (d_best < 0) continue;
    SSTA_CHECK(d_best < num_disparities, "ApplyRatioFilter: index outside the range");
    if (best[i] == kNone) {
      d_best = -1;  // the match itself leaves the right image: not a trustworthy disparity
    } else if (second[i] != kNone &&
               best[i] * 100 >= static_cast<std::int64_t>(100 - ratio_percent) * second[i]) {
      d_best = -1;
    }
  }
}

}  // namespace ssta::internal
