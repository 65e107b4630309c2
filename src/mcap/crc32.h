#pragma once

// Private: the CRC-32 MCAP uses for its chunk and section checksums (the zlib / PNG one,
// reflected polynomial 0xEDB88320).

#include <cstddef>
#include <cstdint>

namespace ssta::internal {

/// CRC-32 of `size` bytes, continuing from `crc` (0 to start). Crc32("123456789") = 0xCBF43926.
std::uint32_t Crc32(const std::uint8_t* data, std::size_t size, std::uint32_t crc = 0);

}  // namespace ssta::internal
