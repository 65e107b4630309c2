#include "ssta/io/image_codec.h"

#include <cctype>
#include <csetjmp>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <new>

// clang-format off: jpeglib.h needs <cstdio> first.
#include <jpeglib.h>
// clang-format on
#include <png.h>
#include <zlib.h>

#include "ssta/core/error.h"

namespace ssta {
namespace {

// libpng and libjpeg report errors by longjmp out of the decoder. The functions that call them
// below hold no object with a destructor between setjmp and the calls, keep what they write in
// the caller's objects, and turn a failure into a message the caller throws.

/// PNG stores 16-bit samples big-endian; libpng hands them over as stored unless swapped.
const bool kLittleEndian = [] {
  const std::uint16_t one = 1;
  unsigned char first = 0;
  std::memcpy(&first, &one, 1);
  return first == 1;
}();

/// Larger images are refused before their pixels are allocated (a damaged header can claim
/// billions).
constexpr double kMaxPixels = 1073741824.0;

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

/// What DecodePngPixels read: the layout before any transform, then the pixels after.
struct PngPixels {
  int color_type = 0;
  int stored_depth = 0;
  int width = 0;
  int height = 0;
  int depth = 0;  ///< 8 or 16 after the transforms
  bool decoded = false;
  std::vector<unsigned char> bytes;
  std::vector<png_bytep> rows;
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
  if (static_cast<double>(png_get_image_width(png, info)) * png_get_image_height(png, info) > kMaxPixels) {
    png_error(png, "the image is larger than 2^30 pixels");
  }
  out->width = static_cast<int>(png_get_image_width(png, info));
  out->height = static_cast<int>(png_get_image_height(png, info));
  out->depth = png_get_bit_depth(png, info);
  const std::size_t row_bytes = png_get_rowbytes(png, info);
  if (png_get_channels(png, info) != 1 || row_bytes != static_cast<std::size_t>(out->width) * (out->depth / 8)) {
    png_error(png, "unexpected layout after conversion to one channel");
  }
  bool allocated = true;
  try {
    out->bytes.resize(row_bytes * static_cast<std::size_t>(out->height));
    out->rows.resize(static_cast<std::size_t>(out->height));
  } catch (const std::bad_alloc&) {
    allocated = false;
  }
  if (!allocated) png_error(png, "out of memory");
  for (int v = 0; v < out->height; ++v) out->rows[static_cast<std::size_t>(v)] = out->bytes.data() + row_bytes * v;
  png_read_image(png, out->rows.data());
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  out->decoded = true;
  return true;
}

struct JpegFailure {
  jpeg_error_mgr manager;  // first: libjpeg's error pointer is this struct's address
  std::jmp_buf jump;
  CodecMessage message;
};

void JpegFail(j_common_ptr codec) {
  auto* failure = reinterpret_cast<JpegFailure*>(codec->err);
  char text[JMSG_LENGTH_MAX];
  (*codec->err->format_message)(codec, text);
  std::snprintf(failure->message.text, sizeof failure->message.text, "%s", text);
  std::longjmp(failure->jump, 1);
}

void JpegQuiet(j_common_ptr) {}

/// To 8-bit grey through libjpeg's own colour conversion, as OpenCV's IMREAD_GRAYSCALE.
bool DecodeJpegGrey(const unsigned char* data, std::size_t size, ImageU8* out, JpegFailure* failure) {
  jpeg_decompress_struct codec;
  codec.err = jpeg_std_error(&failure->manager);
  failure->manager.error_exit = JpegFail;
  failure->manager.output_message = JpegQuiet;
  if (setjmp(failure->jump)) {
    jpeg_destroy_decompress(&codec);
    return false;
  }
  jpeg_create_decompress(&codec);
  jpeg_mem_src(&codec, data, static_cast<unsigned long>(size));
  jpeg_read_header(&codec, TRUE);
  codec.out_color_space = JCS_GRAYSCALE;
  if (static_cast<double>(codec.image_width) * codec.image_height > kMaxPixels) {
    jpeg_destroy_decompress(&codec);
    return Failed(&failure->message, "the image is larger than 2^30 pixels");
  }
  jpeg_start_decompress(&codec);
  bool allocated = true;
  try {
    *out = ImageU8(static_cast<int>(codec.output_width), static_cast<int>(codec.output_height));
  } catch (const std::bad_alloc&) {
    allocated = false;
  }
  if (!allocated) {
    jpeg_destroy_decompress(&codec);
    return Failed(&failure->message, "out of memory");
  }
  while (codec.output_scanline < codec.output_height) {
    JSAMPROW row = out->row(static_cast<int>(codec.output_scanline));
    jpeg_read_scanlines(&codec, &row, 1);
  }
  jpeg_finish_decompress(&codec);
  jpeg_destroy_decompress(&codec);
  return true;
}

template <typename T>
Image<T> ToImage(const PngPixels& pixels) {
  Image<T> image(pixels.width, pixels.height);
  std::memcpy(image.data(), pixels.bytes.data(), pixels.bytes.size());
  return image;
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

/// A binary PGM (P5, 8-bit): the map's `grid` export (map_server's format). Its header is
/// "P5", width, height and maxval, separated by whitespace and comments ('#' to the line's end),
/// then one whitespace byte before the pixels.
ImageU8 DecodePgm(const unsigned char* data, std::size_t size, const std::string& where) {
  std::size_t pos = 2;
  const auto number = [&]() {
    while (pos < size && (std::isspace(data[pos]) || data[pos] == '#')) {
      if (data[pos] == '#') {
        while (pos < size && data[pos] != '\n') ++pos;
      } else {
        ++pos;
      }
    }
    long value = -1;
    while (pos < size && std::isdigit(data[pos]) && value < 1000000) value = (value < 0 ? 0 : 10 * value) + (data[pos++] - '0');
    return pos < size && std::isdigit(data[pos]) ? -1L : value;  // more digits: far too large
  };
  const long width = number(), height = number(), maxval = number();
  if (width <= 0 || height <= 0 || static_cast<double>(width) * height > kMaxPixels || maxval <= 0 || maxval > 255 ||
      pos >= size ||
      !std::isspace(data[pos])) {
    throw Error(where + ": cannot decode PGM: a bad header (8-bit binary P5 is read)");
  }
  ++pos;
  const std::size_t count = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  if (size - pos < count) throw Error(where + ": cannot decode PGM: the data ends early (truncated)");
  ImageU8 image(static_cast<int>(width), static_cast<int>(height));
  std::memcpy(image.data(), data + pos, count);
  return image;
}

}  // namespace

bool IsPng(const void* data, std::size_t size) {
  static const unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  return size >= 8 && std::memcmp(data, kSignature, 8) == 0;
}

bool IsJpeg(const void* data, std::size_t size) {
  const auto* p = static_cast<const unsigned char*>(data);
  return size >= 3 && p[0] == 0xff && p[1] == 0xd8 && p[2] == 0xff;
}

ImageU8 DecodeGrey(const void* data, std::size_t size, const std::string& where) {
  const auto* bytes = static_cast<const unsigned char*>(data);
  if (IsPng(data, size)) {
    PngPixels pixels;
    CodecMessage message{};
    if (!DecodePngPixels(bytes, size, true, &pixels, &message)) {
      throw Error(where + ": cannot decode PNG: " + message.text);
    }
    return ToImage<std::uint8_t>(pixels);
  }
  if (IsJpeg(data, size)) {
    ImageU8 image;
    JpegFailure failure{};
    if (!DecodeJpegGrey(bytes, size, &image, &failure)) {
      throw Error(where + ": cannot decode JPEG: " + failure.message.text);
    }
    return image;
  }
  if (size >= 2 && bytes[0] == 'P' && bytes[1] == '5') return DecodePgm(bytes, size, where);
  throw Error(where + ": not a PNG, JPEG or PGM image (the formats read: PNG, JPEG, 8-bit binary PGM)");
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
  if (pixels.decoded && out.bit_depth == 16) out.u16 = ToImage<std::uint16_t>(pixels);
  if (pixels.decoded && out.bit_depth == 8) out.u8 = ToImage<std::uint8_t>(pixels);
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

}  // namespace ssta
