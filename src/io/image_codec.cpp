#include "ssta/io/image_codec.h"

#include <cctype>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <new>

// clang-format off: jpeglib.h needs <cstdio> first, jerror.h jpeglib.h.
#include <jpeglib.h>
#include <jerror.h>
// clang-format on

#include "ssta/core/error.h"

namespace ssta {
namespace {

// libjpeg reports errors by longjmp out of the decoder. DecodeJpegGrey holds no object with a
// destructor between setjmp and the calls, keeps what it writes in the caller's image, and turns
// a failure into a message the caller throws.

struct JpegFailure {
  jpeg_error_mgr manager;  // first: libjpeg's error pointer is this struct's address
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

/// Sets the failure's message to `text` and says that decoding failed.
bool Failed(JpegFailure* failure, const char* text) {
  std::snprintf(failure->message, sizeof failure->message, "%s", text);
  return false;
}

void JpegFail(j_common_ptr codec) {
  auto* failure = reinterpret_cast<JpegFailure*>(codec->err);
  (*codec->err->format_message)(codec, failure->message);
  std::longjmp(failure->jump, 1);
}

void JpegQuiet(j_common_ptr) {}

/// libjpeg's warnings, which it would print and go on from. A scan that ends early is an error
/// here, whether the data stops (a file cut short by a full disk) or a marker comes before the
/// scan's data is complete (a cut file whose end marker a writer appended): libjpeg would fill
/// the missing rows with grey, which would reach the matcher as flat ground. Other warnings
/// (extraneous bytes between markers, which some cameras write) are let through, as OpenCV does.
void JpegWarn(j_common_ptr codec, int level) {
  if (level >= 0) return;
  const int code = codec->err->msg_code;
  if (code == JWRN_JPEG_EOF || code == JWRN_HIT_MARKER) {
    auto* failure = reinterpret_cast<JpegFailure*>(codec->err);
    std::snprintf(failure->message, sizeof failure->message, "%s",
                  code == JWRN_JPEG_EOF ? "the data ends early (truncated)"
                                        : "the scan ends early at a marker (damaged or truncated)");
    std::longjmp(failure->jump, 1);
  }
}

/// To 8-bit grey through libjpeg's own colour conversion, as OpenCV's IMREAD_GRAYSCALE.
bool DecodeJpegGrey(const unsigned char* data, std::size_t size, ImageU8* out, JpegFailure* failure) {
  jpeg_decompress_struct codec;
  codec.err = jpeg_std_error(&failure->manager);
  failure->manager.error_exit = JpegFail;
  failure->manager.output_message = JpegQuiet;
  failure->manager.emit_message = JpegWarn;
  if (setjmp(failure->jump)) {
    jpeg_destroy_decompress(&codec);
    return false;
  }
  jpeg_create_decompress(&codec);
  jpeg_mem_src(&codec, data, static_cast<unsigned long>(size));
  jpeg_read_header(&codec, TRUE);
  codec.out_color_space = JCS_GRAYSCALE;
  if (TooLargeToDecode(codec.image_width, codec.image_height)) {
    jpeg_destroy_decompress(&codec);
    return Failed(failure, "the image is larger than 2^30 pixels");
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
    return Failed(failure, "out of memory");
  }
  while (codec.output_scanline < codec.output_height) {
    JSAMPROW row = out->row(static_cast<int>(codec.output_scanline));
    jpeg_read_scanlines(&codec, &row, 1);
  }
  jpeg_finish_decompress(&codec);
  jpeg_destroy_decompress(&codec);
  return true;
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
  if (width <= 0 || height <= 0 || TooLargeToDecode(width, height) || maxval <= 0 || maxval > 255 || pos >= size ||
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

bool IsJpeg(const void* data, std::size_t size) {
  const auto* p = static_cast<const unsigned char*>(data);
  return size >= 3 && p[0] == 0xff && p[1] == 0xd8 && p[2] == 0xff;
}

ImageU8 DecodeGrey(const void* data, std::size_t size, const std::string& where) {
  const auto* bytes = static_cast<const unsigned char*>(data);
  if (IsPng(data, size)) return DecodePngGrey(data, size, where);
  if (IsJpeg(data, size)) {
    ImageU8 image;
    JpegFailure failure{};
    if (!DecodeJpegGrey(bytes, size, &image, &failure)) {
      throw Error(where + ": cannot decode JPEG: " + failure.message);
    }
    return image;
  }
  if (size >= 2 && bytes[0] == 'P' && bytes[1] == '5') return DecodePgm(bytes, size, where);
  throw Error(where + ": not a PNG, JPEG or PGM image (the formats read: PNG, JPEG, 8-bit binary PGM)");
}

}  // namespace ssta
