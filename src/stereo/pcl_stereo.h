#pragma once

#include "ssta/core/image.h"
#include "ssta/stereo/stereo_matcher.h"

namespace ssta::internal {

/// Runs PCL's BlockBasedStereoMatching or AdaptiveCostSOStereoMatching (options.algorithm) on a
/// rectified pair of equal size. Returns disparity [px], 0 where invalid, before speckle
/// filtering. Columns u < min_disparity + num_disparities (the search range leaves the right
/// image) are invalid. Thread-safe: each call builds its own PCL matcher.
/// Precondition (SSTA_CHECK): options are valid, images have the same size.
ImageF ComputePclDisparity(const ImageU8& left, const ImageU8& right,
                           const StereoMatcherOptions& options);

}  // namespace ssta::internal
