#pragma once

// Private helper: validation of class-id images at the door of every scorer.

#include <string>

#include "ssta/core/image.h"

namespace ssta::internal {

/// Throws ssta::Error "`name`: value V at (v R, u C) is not a class id (0..4 or 255 = don't
/// care)" on the first pixel that is neither 0..4 nor 255.
void CheckTruthIds(const ImageU8& truth, const std::string& name);

/// Throws ssta::Error "`name`: value V at (v R, u C) is not a class id 0..4" on the first
/// pixel above 4.
void CheckPredictedIds(const ImageU8& predicted, const std::string& name);

}  // namespace ssta::internal
