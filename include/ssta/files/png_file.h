#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "ssta/core/image.h"

namespace ssta {

/// PNG through libpng: the map's exports and every image file the pipeline reads or writes
/// (ssta/io/image_codec.h adds JPEG and PGM). Errors are ssta::Error naming `where` (a file or
/// a bag message).

/// Whether an image of `width` x `height` pixels is larger than the decoders accept (2^30
/// pixels): such a header is refused before its pixels are allocated, for a damaged one can
/// claim billions.
inline bool TooLargeToDecode(double width, double height) { return width * height > 1073741824.0; }

/// Whether `data` starts with the PNG signature.
bool IsPng(const void* data, std::size_t size);

/// A PNG as 8-bit grey, as OpenCV's IMREAD_GRAYSCALE decodes it: 16-bit samples keep their high
/// byte, a palette is expanded, alpha (and a palette's transparency) dropped, and colour
/// weighted 0.299 R + 0.587 G + 0.114 B.
ImageU8 DecodePngGrey(const void* data, std::size_t size, const std::string& where);

/// A PNG with its samples as stored: `channels` is 1 (grey), 2 (grey and alpha), 3 (colour or
/// palette) or 4 (colour and alpha); `bit_depth` 8 or 16 (1, 2 and 4-bit grey are widened to
/// 8). Only one-channel images are decoded (into `u8` or `u16`, by depth): the others report
/// their layout, so that a caller expecting one channel can say what it got.
struct StoredPng {
  int channels = 0;
  int bit_depth = 0;
  ImageU8 u8;
  ImageU16 u16;
};
StoredPng DecodePngAsStored(const void* data, std::size_t size, const std::string& where);

/// PNG bytes of a grey (8 or 16-bit) or an RGB (R, G, B bytes per pixel) image, compressed at
/// zlib `level` (0-9). Level 1 is OpenCV's fast setting (the SUB filter and zlib's run-length
/// strategy), for files written again and again; 9 is zlib's strongest, for pictures.
std::vector<unsigned char> EncodePng(const ImageU8& image, int level, const std::string& where);
std::vector<unsigned char> EncodePng(const ImageU16& image, int level, const std::string& where);
std::vector<unsigned char> EncodePng(const ImageRgb& image, int level, const std::string& where);

/// Writes `image` as an 8-bit grey PNG (one byte per pixel, as stored: class ids and costs keep
/// their values, no colour space is claimed), atomically (a temporary file renamed over `path`),
/// at level 1: these are the map's exports, written again and again.
/// Throws ssta::Error naming the file on failure (empty image, unwritable folder, full disk).
void WritePng(const ImageU8& image, const std::string& path);

/// As above, an 8-bit colour PNG of the pixels in R, G, B order.
void WritePng(const ImageRgb& image, const std::string& path);

}  // namespace ssta
