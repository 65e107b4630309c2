#pragma once

#include <string>

#include "ssta/core/option_fields.h"
#include "ssta/core/image.h"
#include "ssta/stereo/rectifier.h"

namespace ssta {

/// YAML section `triangulation`.
struct TriangulationOptions {
  double min_range_m = 0.3;   ///< points nearer than this (depth Z) become NaN [m]
  double max_range_m = 25.0;  ///< points farther than this (depth Z) become NaN [m]
  /// Every field: its key, unit, range and meaning (reading, writing and IsValid come from it).
  static const OptionFields<TriangulationOptions>& Fields();
  /// The first field out of its range, as "key: requirement" in `*error`.
  bool IsValid(std::string* error) const;
};

/// Organized point cloud of the left (cropped, rectified) image in the rectified camera frame:
/// Z = f*b/d, X = (u-cu)*Z/f, Y = (v-cv)*Z/f; NaN where d <= 0 or Z is out of range.
/// Units: disparity [px], points [m]. One pass, no per-pixel allocation; pure function,
/// thread-safe. Preconditions (SSTA_CHECK, a programmer error): disparity has the geometry's
/// crop size, f > 0, baseline_m > 0, and options are valid.
Image3f Triangulate(const ImageF& disparity, const RectifiedGeometry& geometry,
                    const TriangulationOptions& options);

}  // namespace ssta
