#pragma once

#include <cstdint>

namespace ssta::internal::mcap {

/// The 8 bytes that open and close every MCAP file.
constexpr std::uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};

/// The record opcodes SSTA reads (mcap_bag.cpp) and writes (mcap_writer.cpp).
enum Opcode : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kStatistics = 0x0B,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

}  // namespace ssta::internal::mcap
