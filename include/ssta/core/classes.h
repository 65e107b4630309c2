#pragma once

#include <array>
#include <cstdint>
#include <string_view>

#include "ssta/core/image.h"

namespace ssta {

/// Traversability classes (docs/interfaces.md, section 3); the numeric value is the id written to label
/// images, maps and exports.
enum class TravClass : std::uint8_t {
  kUnknown = 0,          ///< no depth: no disparity, outside the common area, never observed
  kTraversable = 1,      ///< slope <= semi_slope_deg and step <= semi_step_m
  kSemiTraversable = 2,  ///< slope <= max_slope_deg and step <= max_step_m, not traversable
  kNonTraversable = 3,   ///< slope > max_slope_deg or step > max_step_m
  kUndecided = 4,        ///< depth exists but no verdict (segment too small, frame failed QC)
};

/// Label value in ground-truth images for "don't care" (not scored).
inline constexpr std::uint8_t kDontCare = 255;
inline constexpr int kNumClasses = 5;

/// Lower-case name as used in reports and JSON: "unknown", "traversable", ...
std::string_view ClassName(TravClass c);

/// Display colour of a class (docs/interfaces.md, section 3). Undecided has no colour; this returns
/// black for it and callers leave the image showing through.
Rgb8 ClassColour(TravClass c);

/// A class a vehicle may drive on: traversable or semi-traversable.
inline constexpr bool IsDrivable(TravClass c) {
  return c == TravClass::kTraversable || c == TravClass::kSemiTraversable;
}

/// The worse of two verdicts among traversable < semi-traversable < non-traversable.
/// Unknown and undecided are not ordered with these; precondition: both are 1..3.
TravClass Worse(TravClass a, TravClass b);

/// The left image tinted by labels: traversable green, semi blue, non-traversable red,
/// unknown black (darkened), undecided untinted. `alpha` is the tint weight in [0, 1].
/// Precondition: `grey` and `labels` have the same size.
ImageRgb MakeOverlay(const ImageU8& grey, const ImageU8& labels, float alpha = 0.45f);

/// Labels painted in class colours (undecided grey 128, don't-care white).
ImageRgb ColourizeLabels(const ImageU8& labels);

}  // namespace ssta
