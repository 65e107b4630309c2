#include "ssta/files/png_file.h"

#include <cstdio>
#include <cstring>
#include <vector>

#include <png.h>

#include "ssta/core/error.h"
#include "ssta/files/file_util.h"

namespace ssta {
namespace {

static_assert(sizeof(Rgb8) == 3, "ImageRgb rows must be packed R, G, B bytes for libpng");

/// Encodes rows of `width` pixels of `format` (PNG_FORMAT_GRAY or PNG_FORMAT_RGB) into memory
/// with libpng's simplified API, which reports errors in `png_image::message` instead of a
/// longjmp.
std::vector<unsigned char> Encode(const void* pixels, int width, int height, png_uint_32 format, png_uint_32 flags,
                                  const std::string& path) {
  if (width <= 0 || height <= 0) throw Error(path + ": cannot write an empty image as PNG");
  png_image image;
  std::memset(&image, 0, sizeof image);
  image.version = PNG_IMAGE_VERSION;
  image.width = static_cast<png_uint_32>(width);
  image.height = static_cast<png_uint_32>(height);
  image.format = format;
  image.flags = flags | PNG_IMAGE_FLAG_FAST;
  png_alloc_size_t size = 0;
  if (!png_image_write_to_memory(&image, nullptr, &size, 0, pixels, 0, nullptr)) {
    throw Error(path + ": cannot encode image as PNG: " + image.message);
  }
  std::vector<unsigned char> bytes(size);
  if (!png_image_write_to_memory(&image, bytes.data(), &size, 0, pixels, 0, nullptr)) {
    throw Error(path + ": cannot encode image as PNG: " + image.message);
  }
  bytes.resize(size);
  return bytes;
}

}  // namespace

void WritePng(const ImageU8& image, const std::string& path) {
  WriteFileBytes(Encode(image.data(), image.width(), image.height(), PNG_FORMAT_GRAY, PNG_IMAGE_FLAG_COLORSPACE_NOT_sRGB,
                    path),
             path);
}

void WritePng(const ImageRgb& image, const std::string& path) {
  WriteFileBytes(Encode(image.data(), image.width(), image.height(), PNG_FORMAT_RGB, 0, path), path);
}

}  // namespace ssta
