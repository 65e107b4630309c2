#pragma once

#include <cstdint>

#include "ssta/core/image.h"

namespace ssta::internal {

/// A bounds-safe ratio (uniqueness) filter on the sum-of-absolute-differences cost of a square
/// window, the cost PCL's BlockBasedStereoMatching minimises.
///
/// For every pixel (v, u) with index(v, u) = d_best >= 0 (a disparity index: the match is
/// right(v, u - x_offset - d_best)), the cost curve C(d) = SAD over the (2*radius+1)^2 window
/// of left(v+j, u+i) against right(v+j, u+i - x_offset - d), d in [0, num_disparities), is
/// computed; C(d_best) is compared with the smallest cost outside {d_best-1, d_best, d_best+1}.
/// Where C(d_best) * 100 > (100 - ratio_percent) * second the pixel is rejected (index = -1).
/// Pixels with index < 0 are left alone. Windows are clipped at the image border; a column
/// u - x_offset - d outside the right image is skipped for that d. When every other candidate
/// is a neighbour (or outside the image) there is nothing to compare with and the pixel stays.
///
/// Unlike pcl::doStereoRatioFilter (PCL 1.13), this is defined for d_best at either end of the
/// range. Preconditions (SSTA_CHECK): equal image sizes, radius >= 0, num_disparities > 0,
/// x_offset >= 0, ratio_percent in [0, 100], indices inside [-inf, num_disparities).
/// Cost: O(num_disparities * width * height) time, O(width * height) memory.
void ApplyRatioFilter(const ImageU8& left, const ImageU8& right, int radius, int num_disparities,
                      int x_offset, int ratio_percent, ImageI32* index);

}  // namespace ssta::internal
