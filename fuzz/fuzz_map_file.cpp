// The map loader (TraversabilityMap::Load). Each input is tried twice: as it is, and "resealed"
// with a correct end marker (byte count and FNV-1a hash, maps/README.md) so that the mutations
// reach the header, metadata and node stream checks behind the checksum, and OctoMap's reader.

#include <cinttypes>
#include <cstdio>

#include "fuzz_util.h"
#include "mapping/map_impl.h"

namespace {

constexpr char kTrailerTag[] = "\n# ssta-map-end bytes ";

std::string Reseal(std::string bytes) {
  const std::size_t tag = bytes.rfind(kTrailerTag);
  if (tag != std::string::npos) bytes.resize(tag);
  std::uint64_t hash = 14695981039346656037ull;
  for (const char c : bytes) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 1099511628211ull;
  }
  char trailer[96];
  std::snprintf(trailer, sizeof(trailer), "%s%zu fnv1a64 %016" PRIx64 "\n", kTrailerTag, bytes.size(), hash);
  return bytes + trailer;
}

void TryLoad(const std::string& bytes) {
  ssta::fuzz::ExpectParsedOrError([&] {
    const ssta::TraversabilityMap map = ssta::internal::TraversabilityMapAccess::LoadFromBytes(bytes, "map.ot");
    // A loaded map answers queries.
    (void)map.NumNodes();
    (void)map.CellAt(Eigen::Vector3d(0.1, 0.1, 0.1));
    (void)map.TopSurfaceAt(0.1, 0.1);
  });
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes = ssta::fuzz::AsText(data, size);
  TryLoad(bytes);
  TryLoad(Reseal(bytes));
  return 0;
}
