// The ROS 2 MCAP reader (src/bags/mcap_bag.h): the records, the summary index, zstd and lz4
// chunks, a file cut off by a crash. What opens is listed, and the first messages are read.
// The seeds include files whose chunks carry no CRC, so that mutations reach the records inside
// the chunks instead of stopping at the checksum.

#include <numeric>
#include <vector>

#include "fuzz_util.h"
#include "bags/mcap_bag.h"

namespace {
constexpr std::size_t kMaxReads = 64;  // enough to reach every chunk of a 16 KB input
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  ssta::fuzz::ExpectParsedOrError([&] {
    const auto bag = ssta::internal::OpenMcapBytes(std::vector<std::uint8_t>(data, data + size), "fuzz.mcap");
    std::vector<int> all(bag->connections().size());
    std::iota(all.begin(), all.end(), 0);
    const auto refs = bag->List(all);
    for (std::size_t i = 0; i < refs.size() && i < kMaxReads; ++i) {
      ssta::fuzz::ExpectParsedOrError([&] { bag->Read(refs[i]); });
    }
  });
  return 0;
}
