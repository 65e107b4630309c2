#include "ssta/files/png_file.h"

#include <cmath>
#include <csetjmp>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <new>
#include <utility>
#include <vector>

#include <png.h>
#include <zlib.h>

#include "ssta/core/error.h"
#include "ssta/files/file_util.h"

namespace ssta {
namespace {

// libpng reports errors by longjmp out of its functions. The functions that call them below
// hold no object with a destructor between setjmp and the calls, keep what they write in the
// caller's objects, and turn a failure into a message the caller throws; no exception crosses
// libpng's frames.

/// PNG stores 16-bit samples big-endian; libpng hands them over as stored unless swapped.
const bool kLittleEndian = [] {
  const std::uint16_t one = 1;
  unsigned char first = 0;
  std::memcpy(&first, &one, 1);
  return first == 1;
}();

/// The most bytes deflate can expand one byte to: a 258-byte match in two bits.
constexpr double kDeflateMaxRatio = 1032.0;

struct PngSource {
  const unsigned char* data;
  std::size_t size;
  std::size_t pos;
};

struct CodecMessage {
  char text[256];
};

void PngRead(png_structp png, png_bytep out, png_size_t n) {
  auto* source = static_cast<PngSource*>(png_get_io_ptr(png));
  if (n > source->size - source->pos) png_error(png, "the data ends early (truncated)");
  std::memcpy(out, source->data + source->pos, n);
  source->pos += n;
}

void PngFail(png_structp png, png_const_charp message) {
  auto* out = static_cast<CodecMessage*>(png_get_error_ptr(png));
  std::snprintf(out->text, sizeof out->text, "%s", message);
  png_longjmp(png, 1);
}

void PngWarn(png_structp, png_const_charp) {}  // libpng's warnings would go to stderr

/// Sets `message` to `text` and says that the coding failed.
bool Failed(CodecMessage* message, const char* text) {
  std::snprintf(message->text, sizeof message->text, "%s", text);
  return false;
}

/// What DecodePngPixels read: the layout before any transform, then the pixels after, written
/// straight into `u8` or `u16` (by the depth after the transforms).
struct PngPixels {
  int color_type = 0;
  int stored_depth = 0;
  bool decoded = false;
  ImageU8 u8;
  ImageU16 u16;
  std::vector<png_bytep> rows;  // here, not in DecodePngPixels' frame: it changes after setjmp
};

/// `grey8`: to 8-bit grey as OpenCV's IMREAD_GRAYSCALE. Else as stored, one-channel images
/// only (others leave `decoded` false, their layout filled in).
bool DecodePngPixels(const unsigned char* data, std::size_t size, bool grey8, PngPixels* out, CodecMessage* message) {
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, message, PngFail, PngWarn);
  if (png == nullptr) return Failed(message, "libpng cannot start");
  png_infop info = png_create_info_struct(png);
  if (info == nullptr) {
    png_destroy_read_struct(&png, nullptr, nullptr);
    return Failed(message, "out of memory");
  }
  PngSource source{data, size, 0};
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    return false;
  }
  png_set_read_fn(png, &source, PngRead);
  png_read_info(png, info);
  out->color_type = png_get_color_type(png, info);
  out->stored_depth = png_get_bit_depth(png, info);
  {
    // Deflate packs at most 1032 bytes into one, so the rows a header claims cannot come from
    // fewer bytes than this: a damaged header is refused before its pixels are allocated.
    const double width = png_get_image_width(png, info), height = png_get_image_height(png, info);
    if (TooLargeToDecode(width, height)) png_error(png, "the image is larger than 2^30 pixels");
    const double row_bytes = std::ceil(width * png_get_channels(png, info) * out->stored_depth / 8.0);
    if (height * (row_bytes + 1.0) > kDeflateMaxRatio * static_cast<double>(size)) {
      png_error(png, "the data is far too short for the size its header claims (damaged or truncated)");
    }
  }
  const bool colour = (out->color_type & PNG_COLOR_MASK_COLOR) != 0;
  if (grey8) {
    if (out->stored_depth == 16) png_set_strip_16(png);
    // Also the alpha a palette's transparency (tRNS) expands to.
    png_set_strip_alpha(png);
    if (out->color_type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
    if (colour) png_set_rgb_to_gray(png, 1, 0.299, 0.587);
  } else if (colour || (out->color_type & PNG_COLOR_MASK_ALPHA)) {
    png_destroy_read_struct(&png, &info, nullptr);
    return true;  // layout only
  } else if (out->stored_depth == 16 && kLittleEndian) {
    png_set_swap(png);  // host byte order (the file's is big-endian)
  }
  if (!colour && out->stored_depth < 8) png_set_expand_gray_1_2_4_to_8(png);
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  const png_uint_32 width = png_get_image_width(png, info), height = png_get_image_height(png, info);
  const int depth = png_get_bit_depth(png, info);
  const std::size_t row_bytes = png_get_rowbytes(png, info);
  if (png_get_channels(png, info) != 1 || row_bytes != static_cast<std::size_t>(width) * (depth / 8)) {
    png_error(png, "unexpected layout after conversion to one channel");
  }
  bool allocated = true;
  try {
    if (depth == 16) {
      out->u16 = ImageU16(static_cast<int>(width), static_cast<int>(height));
    } else {
      out->u8 = ImageU8(static_cast<int>(width), static_cast<int>(height));
    }
    out->rows.resize(height);
  } catch (const std::bad_alloc&) {
    allocated = false;
  }
  if (!allocated) png_error(png, "out of memory");
  auto* base = depth == 16 ? reinterpret_cast<unsigned char*>(out->u16.data()) : out->u8.data();
  for (png_uint_32 v = 0; v < height; ++v) out->rows[v] = base + row_bytes * v;
  png_read_image(png, out->rows.data());
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  out->decoded = true;
  return true;
}

void PngWrite(png_structp png, png_bytep data, png_size_t n) {
  auto* sink = static_cast<std::vector<unsigned char>*>(png_get_io_ptr(png));
  bool stored = true;
  try {  // no exception may pass through libpng's C frames
    sink->insert(sink->end(), data, data + n);
  } catch (const std::bad_alloc&) {
    stored = false;
  }
  if (!stored) png_error(png, "out of memory");
}

void PngFlush(png_structp) {}

/// Encodes rows of `width` pixels (`bit_depth` 8 or 16 per sample, `color_type` GRAY or RGB)
/// into `sink`. Level 1 takes OpenCV's fast setting (the SUB filter and zlib's run-length
/// strategy), other levels libpng's adaptive filters.
bool EncodePngPixels(const unsigned char* pixels, int width, int height, int bit_depth, int color_type, int level,
                     std::vector<unsigned char>* sink, CodecMessage* message) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, message, PngFail, PngWarn);
  if (png == nullptr) return Failed(message, "libpng cannot start");
  png_infop info = png_create_info_struct(png);
  if (info == nullptr) {
    png_destroy_write_struct(&png, nullptr);
    return Failed(message, "out of memory");
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return false;
  }
  png_set_write_fn(png, sink, PngWrite, PngFlush);
  png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), bit_depth, color_type,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_compression_level(png, level);
  png_set_compression_strategy(png, level == 1 ? Z_RLE : Z_DEFAULT_STRATEGY);
  if (level == 1) png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB);
  png_write_info(png, info);
  if (bit_depth == 16 && kLittleEndian) png_set_swap(png);  // the rows are in host byte order
  const int channels = color_type == PNG_COLOR_TYPE_RGB ? 3 : 1;
  const std::size_t row_bytes = static_cast<std::size_t>(width) * channels * (bit_depth / 8);
  for (int v = 0; v < height; ++v) png_write_row(png, pixels + row_bytes * v);
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return true;
}

std::vector<unsigned char> Encode(const void* pixels, int width, int height, int bit_depth, int color_type, int level,
                                  const std::string& where) {
  if (width <= 0 || height <= 0) throw Error(where + ": cannot write an empty image as PNG");
  if (level < 0 || level > 9) throw InternalError(where + ": PNG compression level must be 0-9");
  std::vector<unsigned char> bytes;
  CodecMessage message{};
  if (!EncodePngPixels(static_cast<const unsigned char*>(pixels), width, height, bit_depth, color_type, level, &bytes,
                       &message)) {
    throw Error(where + ": cannot encode image as PNG: " + message.text);
  }
  return bytes;
}

}  // namespace

bool IsPng(const void* data, std::size_t size) {
  static const unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  return size >= 8 && std::memcmp(data, kSignature, 8) == 0;
}

ImageU8 DecodePngGrey(const void* data, std::size_t size, const std::string& where) {
  PngPixels pixels;
  CodecMessage message{};
  if (!DecodePngPixels(static_cast<const unsigned char*>(data), size, true, &pixels, &message)) {
    throw Error(where + ": cannot decode PNG: " + message.text);
  }
  return std::move(pixels.u8);
}

StoredPng DecodePngAsStored(const void* data, std::size_t size, const std::string& where) {
  if (!IsPng(data, size)) throw Error(where + ": not a PNG image");
  PngPixels pixels;
  CodecMessage message{};
  if (!DecodePngPixels(static_cast<const unsigned char*>(data), size, false, &pixels, &message)) {
    throw Error(where + ": cannot decode PNG: " + message.text);
  }
  StoredPng out;
  const int type = pixels.color_type;
  out.channels = type == PNG_COLOR_TYPE_GRAY ? 1 : type == PNG_COLOR_TYPE_GRAY_ALPHA ? 2
                 : type == PNG_COLOR_TYPE_RGB_ALPHA                                   ? 4
                                                                                      : 3;
  out.bit_depth = pixels.stored_depth == 16 ? 16 : 8;
  out.u8 = std::move(pixels.u8);
  out.u16 = std::move(pixels.u16);
  return out;
}

std::vector<unsigned char> EncodePng(const ImageU8& image, int level, const std::string& where) {
  return Encode(image.data(), image.width(), image.height(), 8, PNG_COLOR_TYPE_GRAY, level, where);
}

std::vector<unsigned char> EncodePng(const ImageU16& image, int level, const std::string& where) {
  return Encode(image.data(), image.width(), image.height(), 16, PNG_COLOR_TYPE_GRAY, level, where);
}

std::vector<unsigned char> EncodePng(const ImageRgb& image, int level, const std::string& where) {
  static_assert(sizeof(Rgb8) == 3, "ImageRgb rows must be packed R, G, B bytes for libpng");
  return Encode(image.data(), image.width(), image.height(), 8, PNG_COLOR_TYPE_RGB, level, where);
}

void WritePng(const ImageU8& image, const std::string& path) { WriteFileBytes(EncodePng(image, 1, path), path); }

void WritePng(const ImageRgb& image, const std::string& path) { WriteFileBytes(EncodePng(image, 1, path), path); }

}  // namespace ssta
