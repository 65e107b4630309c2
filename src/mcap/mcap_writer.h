#pragma once

// Private: writes one MCAP file (https://mcap.dev/spec, version 0) as rosbag2's MCAP storage does:
// a Header, the Schema and Channel records and the messages in chunks (each followed by its
// Message Index records), Data End with the data section's CRC, then a summary section (Schema,
// Channel, Statistics and Chunk Index records, grouped by Summary Offset records) and a Footer
// with the summary's CRC.

#include <cstdint>
#include <map>
#include <ostream>
#include <string>
#include <vector>

namespace ssta::internal {

enum class McapCompression { kNone, kZstd };

/// "" or "zstd" (the Chunk record's compression field).
const char* McapCompressionName(McapCompression compression);

struct McapWriterOptions {
  McapCompression compression = McapCompression::kZstd;
  /// A chunk is closed once its uncompressed records reach this many bytes [bytes]; a larger
  /// message gets a chunk of its own.
  std::uint64_t chunk_bytes = std::uint64_t{1} << 20;
  std::string profile = "ros2";  ///< the Header's profile
  std::string library;           ///< the Header's library ("ssta 1.2.0")
};

/// What Finish wrote.
struct McapWriteSummary {
  std::uint64_t bytes = 0;     ///< the file's size [bytes]
  std::uint64_t messages = 0;  ///< Message records
  std::uint32_t chunks = 0;    ///< Chunk records
};

/// Writes records to `out` as they come (one open chunk is kept in memory). Not thread-safe.
/// Throws ssta::Error naming `name` when the stream fails or compression fails.
class McapWriter {
 public:
  /// Writes the magic and the Header record.
  McapWriter(std::ostream* out, std::string name, McapWriterOptions options);

  /// Registers a schema (ids from 1); `data` is the schema text, e.g. a ros2msg definition.
  std::uint16_t AddSchema(const std::string& name, const std::string& encoding, const std::string& data);
  /// Registers a channel on `schema_id` (ids from 0) with its metadata (rosbag2's
  /// "offered_qos_profiles").
  std::uint16_t AddChannel(std::uint16_t schema_id, const std::string& topic, const std::string& message_encoding,
                           const std::map<std::string, std::string>& metadata);
  /// Appends one message (for ROS 2: CDR bytes with their encapsulation header) to the open chunk.
  void Write(std::uint16_t channel_id, std::uint64_t log_time_ns, std::uint64_t publish_time_ns,
             const std::vector<std::uint8_t>& data);
  /// Closes the last chunk and writes Data End, the summary section, the Footer and the closing
  /// magic, then flushes. Call once; the writer takes no more records after it.
  McapWriteSummary Finish();

 private:
  void Put(const std::vector<std::uint8_t>& bytes);
  void FlushChunk();

  std::ostream* out_;
  std::string name_;
  McapWriterOptions options_;
  std::uint64_t offset_ = 0;
  std::uint32_t data_crc_ = 0;  // of every byte written before Data End
  bool finished_ = false;
  std::vector<std::vector<std::uint8_t>> schemas_, channels_, chunk_indexes_;
  // The open chunk: its records, each channel's (log time, offset in the chunk), its time range.
  std::vector<std::uint8_t> chunk_;
  std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> index_;
  std::uint64_t chunk_start_ = 0, chunk_end_ = 0;
  std::uint64_t chunk_messages_ = 0;
  // The whole file.
  std::uint32_t sequence_ = 0;
  std::uint64_t messages_ = 0, first_ = 0, last_ = 0;
  std::map<std::uint16_t, std::uint64_t> channel_counts_;
};

}  // namespace ssta::internal
