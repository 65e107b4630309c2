#pragma once

// Private: the compressions an MCAP chunk may use ("" none, "zstd", "lz4" frame format).

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace ssta::internal {

/// The largest chunk the MCAP reader accepts, uncompressed [bytes]: a 4K image is 25 MB, a dense
/// cloud 64 MB; more is a damaged or hostile header.
constexpr std::uint64_t kMaxChunkBytes = std::uint64_t{256} << 20;

/// Decompresses `size` bytes to exactly `uncompressed_size` bytes. Memory grows with the output
/// actually produced, never with the announced size alone, so a lying header cannot make it
/// allocate gigabytes. Throws ssta::Error starting with `where` for an unknown compression, a
/// corrupt or cut stream, or an output of another size than announced.
std::vector<std::uint8_t> DecompressChunk(const std::string& compression, const std::uint8_t* data,
                                          std::size_t size, std::uint64_t uncompressed_size,
                                          const std::string& where);

}  // namespace ssta::internal
