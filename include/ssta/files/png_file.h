#pragma once

#include <string>

#include "ssta/core/image.h"

namespace ssta {

/// Writes `image` as an 8-bit grey PNG (one byte per pixel, as stored: class ids and costs keep
/// their values, no colour space is claimed), atomically (a temporary file renamed over `path`).
/// Through libpng, with its fast setting: these are the map's exports, written again and again.
/// Throws ssta::Error naming the file on failure (empty image, unwritable folder, full disk).
void WritePng(const ImageU8& image, const std::string& path);

/// As above, an 8-bit sRGB colour PNG of the pixels in R, G, B order.
void WritePng(const ImageRgb& image, const std::string& path);

}  // namespace ssta
