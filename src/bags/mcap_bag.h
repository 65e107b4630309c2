#pragma once

// Private: one MCAP file (https://mcap.dev/spec) as a BagReader, rosbag2's default storage.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "bags/bag_reader.h"

namespace ssta::internal {

/// Opens one MCAP file; format() is "ros2 mcap", a connection's type is its channel's schema name
/// and its encoding the channel's message encoding ("cdr").
///
/// A complete file with a summary section (Chunk Index records) is read through its index: List
/// reads the Message Index records and decompresses nothing. A file without a summary, or cut off
/// by a crash (no trailing magic), is scanned once here, decompressing every chunk; of a cut file
/// the complete records are kept. Read decompresses the message's chunk and keeps the last two
/// chunks, so reading messages in time order decompresses each chunk about once.
///
/// Throws ssta::Error naming the file and the record's offset: no MCAP magic, a record running
/// past the end, a cut file holding no complete message, an unknown compression, a corrupt
/// zstd / lz4 stream, a chunk whose CRC-32 does not match. Safe for concurrent List and Read.
std::unique_ptr<BagReader> OpenMcapFile(const std::string& path);

/// The same from bytes in memory; `name` stands for the file in messages (the fuzz target).
std::unique_ptr<BagReader> OpenMcapBytes(std::vector<std::uint8_t> bytes, const std::string& name);

}  // namespace ssta::internal
