#pragma once

#include <cstddef>
#include <string>

#include "ssta/core/image.h"
#include "ssta/files/png_file.h"

namespace ssta {

/// Image files in memory through libpng (ssta/files/png_file.h) and libjpeg directly. The
/// decoders give the values OpenCV's imdecode gives for the same flags (IMREAD_GRAYSCALE,
/// IMREAD_UNCHANGED); going around OpenCV's imgcodecs spares every process its start-up
/// (imgcodecs links GDAL and its hundred libraries: 0.13 s per process on a 2-core machine).
/// Errors are ssta::Error naming `where` (a file or a bag message).

/// Whether `data` starts with the JPEG signature.
bool IsJpeg(const void* data, std::size_t size);

/// A PNG, JPEG or 8-bit binary PGM (the map's grid export) as 8-bit grey: PNGs as
/// DecodePngGrey, JPEGs through libjpeg's own grey output (as OpenCV's IMREAD_GRAYSCALE).
/// Anything else, or data that cannot be decoded, is an error. Unlike OpenCV, an EXIF
/// orientation tag is not applied (the pixels come as stored) and CMYK or YCCK JPEGs are not
/// read.
ImageU8 DecodeGrey(const void* data, std::size_t size, const std::string& where);

}  // namespace ssta
