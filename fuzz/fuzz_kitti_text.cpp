// The KITTI raw text readers: calib_*.txt, timestamps.txt, an OXTS row. Every reader sees
// every input.

#include "fuzz_util.h"
#include "io/text_parsers.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text = ssta::fuzz::AsText(data, size);
  using namespace ssta::internal;
  ssta::fuzz::ExpectParsedOrError([&] { ParseKittiCalib(text); });
  ssta::fuzz::ExpectParsedOrError([&] { ParseKittiTimestamps(text, "image_00/timestamps.txt"); });
  ssta::fuzz::ExpectParsedOrError([&] { ParseOxtsRow(text, "oxts/data/0000000000.txt"); });
  return 0;
}
