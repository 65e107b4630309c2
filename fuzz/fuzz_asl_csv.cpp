// The ASL / EuRoC CSV readers: a camera's data.csv, imu0/data.csv, pose0/data.csv (and the
// generic numeric reader under them). Every reader sees every input.

#include "fuzz_util.h"
#include "io/text_parsers.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text = ssta::fuzz::AsText(data, size);
  using namespace ssta::internal;
  ssta::fuzz::ExpectParsedOrError([&] { ParseAslImageList(text, "cam0/data.csv"); });
  ssta::fuzz::ExpectParsedOrError([&] { ParseAslImuCsv(text, "imu0/data.csv"); });
  ssta::fuzz::ExpectParsedOrError([&] { ParseAslPoseCsv(text, "pose0/data.csv"); });
  return 0;
}
