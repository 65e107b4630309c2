#pragma once

#include <string>

#include "ssta/core/image.h"

namespace ssta {

/// Reads an image file as 8-bit grey (colour images are converted).
/// Throws ssta::Error naming the file when it is missing or cannot be decoded.
ImageU8 ReadGreyImage(const std::string& path);

/// Reads an 8-bit single-channel PNG as it is (label images). Throws ssta::Error.
ImageU8 ReadLabelImage(const std::string& path);

/// Reads a 16-bit single-channel PNG (disparity * 256 in the KITTI convention). Throws.
ImageU16 ReadImageU16(const std::string& path);

/// Writers: PNG by the extension, written atomically (temporary file + rename).
/// Throw ssta::Error naming the file on failure (unwritable folder, full disk).
void WriteImage(const ImageU8& image, const std::string& path);
void WriteImage(const ImageU16& image, const std::string& path);
void WriteImage(const ImageRgb& image, const std::string& path);
/// As WriteImage, with zlib's strongest PNG compression: files several times smaller for
/// pictures with large flat areas, slower to write. For pictures people keep, not for
/// per-frame outputs.
void WriteImageCompact(const ImageRgb& image, const std::string& path);

}  // namespace ssta
