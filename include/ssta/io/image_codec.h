#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "ssta/core/image.h"

namespace ssta {

/// Image files in memory, through libpng and libjpeg directly. The decoders give the values
/// OpenCV's imdecode gives for the same flags (IMREAD_GRAYSCALE, IMREAD_UNCHANGED); going
/// around OpenCV's imgcodecs spares every process its start-up (imgcodecs links GDAL and its
/// hundred libraries: 0.15 s per process on a 2-core machine). Errors are ssta::Error naming
/// `where` (a file or a bag message).

/// Whether `data` starts with the PNG or the JPEG signature.
bool IsPng(const void* data, std::size_t size);
bool IsJpeg(const void* data, std::size_t size);

/// A PNG, JPEG or 8-bit binary PGM (the map's grid export) as 8-bit grey: 16-bit samples keep
/// their high byte, a palette is expanded, alpha dropped, and colour weighted 0.299 R + 0.587 G
/// + 0.114 B (as OpenCV's IMREAD_GRAYSCALE). Anything else, or data that cannot be decoded, is
/// an error. Unlike OpenCV, an EXIF orientation tag is not applied (the pixels come as stored)
/// and CMYK or YCCK JPEGs are not read.
ImageU8 DecodeGrey(const void* data, std::size_t size, const std::string& where);

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
/// zlib `level` (0-9: 1 is fast, 9 small).
std::vector<unsigned char> EncodePng(const ImageU8& image, int level, const std::string& where);
std::vector<unsigned char> EncodePng(const ImageU16& image, int level, const std::string& where);
std::vector<unsigned char> EncodePng(const ImageRgb& image, int level, const std::string& where);

}  // namespace ssta
