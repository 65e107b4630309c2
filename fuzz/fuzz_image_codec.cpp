// The image decoders (ssta/io/image_codec.h, ssta/files/png_file.h): camera frames, bag
// messages and truth files. Whatever decodes must survive a PNG round trip unchanged.

#include <vector>

#include "fuzz_util.h"
#include "ssta/io/image_codec.h"

namespace {

template <typename T>
bool Same(const ssta::Image<T>& a, const ssta::Image<T>& b) {
  if (a.width() != b.width() || a.height() != b.height()) return false;
  for (int v = 0; v < a.height(); ++v) {
    for (int u = 0; u < a.width(); ++u) {
      if (a(v, u) != b(v, u)) return false;
    }
  }
  return true;
}

template <typename T>
void RoundTrip(const ssta::Image<T>& image) {
  if (image.empty()) return;
  const std::vector<unsigned char> png = ssta::EncodePng(image, 1, "round trip");
  const ssta::StoredPng back = ssta::DecodePngAsStored(png.data(), png.size(), "round trip");
  bool same = false;
  if constexpr (sizeof(T) == 2) {
    same = back.bit_depth == 16 && Same(back.u16, image);
  } else {
    same = back.bit_depth == 8 && Same(back.u8, image);
  }
  if (!same) __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  ssta::fuzz::ExpectParsedOrError([&] { RoundTrip(ssta::DecodeGrey(data, size, "image")); });
  ssta::fuzz::ExpectParsedOrError([&] {
    const ssta::StoredPng stored = ssta::DecodePngAsStored(data, size, "image");
    if (stored.channels == 1) {
      if (stored.bit_depth == 16) {
        RoundTrip(stored.u16);
      } else {
        RoundTrip(stored.u8);
      }
    }
  });
  return 0;
}
