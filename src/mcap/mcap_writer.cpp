#include "mcap/mcap_writer.h"

#include <zstd.h>

#include "mcap/crc32.h"
#include "mcap/mcap_records.h"
#include "ssta/core/error.h"

namespace ssta::internal {
namespace {

using namespace mcap;  // NOLINT: the record opcodes and magic


/// Little-endian MCAP fields appended to a buffer.
class Fields {
 public:
  Fields& U8(std::uint8_t v) { return Le(v, 1); }
  Fields& U16(std::uint16_t v) { return Le(v, 2); }
  Fields& U32(std::uint32_t v) { return Le(v, 4); }
  Fields& U64(std::uint64_t v) { return Le(v, 8); }
  /// uint32 byte count, then the bytes.
  Fields& String(const std::string& s) {
    U32(static_cast<std::uint32_t>(s.size()));
    bytes.insert(bytes.end(), s.begin(), s.end());
    return *this;
  }
  Fields& Raw(const std::vector<std::uint8_t>& v) {
    bytes.insert(bytes.end(), v.begin(), v.end());
    return *this;
  }
  /// A map or array field: uint32 byte count, then its entries.
  Fields& Prefixed(const Fields& entries) {
    U32(static_cast<std::uint32_t>(entries.bytes.size()));
    return Raw(entries.bytes);
  }
  std::vector<std::uint8_t> bytes;

 private:
  Fields& Le(std::uint64_t v, int n) {
    for (int i = 0; i < n; ++i) bytes.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
    return *this;
  }
};

/// opcode, uint64 content length, content.
std::vector<std::uint8_t> Record(std::uint8_t opcode, const Fields& content) {
  Fields r;
  r.U8(opcode).U64(content.bytes.size()).Raw(content.bytes);
  return r.bytes;
}

}  // namespace

const char* McapCompressionName(McapCompression compression) {
  return compression == McapCompression::kZstd ? "zstd" : "";
}

McapWriter::McapWriter(std::ostream* out, std::string name, McapWriterOptions options)
    : out_(out), name_(std::move(name)), options_(std::move(options)) {
  Put(std::vector<std::uint8_t>(std::begin(kMagic), std::end(kMagic)));
  Put(Record(kHeader, Fields().String(options_.profile).String(options_.library)));
}

std::uint16_t McapWriter::AddSchema(const std::string& name, const std::string& encoding, const std::string& data) {
  const auto id = static_cast<std::uint16_t>(schemas_.size() + 1);
  Fields schema;
  schema.U16(id).String(name).String(encoding).String(data);
  schemas_.push_back(Record(kSchema, schema));
  chunk_.insert(chunk_.end(), schemas_.back().begin(), schemas_.back().end());
  return id;
}

std::uint16_t McapWriter::AddChannel(std::uint16_t schema_id, const std::string& topic,
                                     const std::string& message_encoding,
                                     const std::map<std::string, std::string>& metadata) {
  const auto id = static_cast<std::uint16_t>(channels_.size());
  Fields entries;
  for (const auto& [key, value] : metadata) entries.String(key).String(value);
  Fields channel;
  channel.U16(id).U16(schema_id).String(topic).String(message_encoding).Prefixed(entries);
  channels_.push_back(Record(kChannel, channel));
  chunk_.insert(chunk_.end(), channels_.back().begin(), channels_.back().end());
  return id;
}

void McapWriter::Write(std::uint16_t channel_id, std::uint64_t log_time_ns, std::uint64_t publish_time_ns,
                       const std::vector<std::uint8_t>& data) {
  if (finished_ || channel_id >= channels_.size()) throw InternalError(name_ + ": MCAP message on an unknown channel");
  if (chunk_messages_ == 0 || log_time_ns < chunk_start_) chunk_start_ = log_time_ns;
  if (chunk_messages_ == 0 || log_time_ns > chunk_end_) chunk_end_ = log_time_ns;
  if (messages_ == 0 || log_time_ns < first_) first_ = log_time_ns;
  if (messages_ == 0 || log_time_ns > last_) last_ = log_time_ns;
  index_[channel_id].emplace_back(log_time_ns, chunk_.size());
  Fields message;
  message.U16(channel_id).U32(sequence_++).U64(log_time_ns).U64(publish_time_ns).Raw(data);
  const std::vector<std::uint8_t> record = Record(kMessage, message);
  chunk_.insert(chunk_.end(), record.begin(), record.end());
  ++chunk_messages_;
  ++messages_;
  ++channel_counts_[channel_id];
  if (chunk_.size() >= options_.chunk_bytes) FlushChunk();
}

void McapWriter::Put(const std::vector<std::uint8_t>& bytes) {
  if (!finished_) data_crc_ = Crc32(bytes.data(), bytes.size(), data_crc_);
  out_->write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!*out_) throw Error(name_ + ": write failed (disk full?)");
  offset_ += bytes.size();
}

void McapWriter::FlushChunk() {
  if (chunk_.empty()) return;
  std::vector<std::uint8_t> records;
  if (options_.compression == McapCompression::kZstd) {
    records.resize(ZSTD_compressBound(chunk_.size()));
    const std::size_t n = ZSTD_compress(records.data(), records.size(), chunk_.data(), chunk_.size(), 3);
    if (ZSTD_isError(n)) throw Error(name_ + ": zstd compression failed: " + ZSTD_getErrorName(n));
    records.resize(n);
  } else {
    records = chunk_;
  }
  const char* compression = McapCompressionName(options_.compression);
  Fields chunk;
  chunk.U64(chunk_start_).U64(chunk_end_).U64(chunk_.size()).U32(Crc32(chunk_.data(), chunk_.size()));
  chunk.String(compression).U64(records.size()).Raw(records);
  const std::uint64_t chunk_offset = offset_;
  const std::vector<std::uint8_t> chunk_record = Record(kChunk, chunk);
  Put(chunk_record);

  const std::uint64_t index_start = offset_;
  Fields index_offsets;
  for (const auto& [channel, entries] : index_) {
    Fields records_of_channel;
    for (const auto& [t, at] : entries) records_of_channel.U64(t).U64(at);
    Fields index;
    index.U16(channel).Prefixed(records_of_channel);
    index_offsets.U16(channel).U64(offset_);
    const std::vector<std::uint8_t> index_record = Record(kMessageIndex, index);
    Put(index_record);
  }
  Fields chunk_index;
  chunk_index.U64(chunk_start_).U64(chunk_end_).U64(chunk_offset).U64(index_start - chunk_offset);
  chunk_index.Prefixed(index_offsets).U64(offset_ - index_start);
  chunk_index.String(compression).U64(records.size()).U64(chunk_.size());
  chunk_indexes_.push_back(Record(kChunkIndex, chunk_index));

  chunk_.clear();
  index_.clear();
  chunk_messages_ = 0;
}

McapWriteSummary McapWriter::Finish() {
  if (finished_) throw InternalError(name_ + ": McapWriter::Finish called twice");
  FlushChunk();
  finished_ = true;  // from here on Put no longer adds to the data section's CRC
  Put(Record(kDataEnd, Fields().U32(data_crc_)));

  // The summary section and its offsets; the footer's CRC covers them and the footer's first
  // two fields.
  const std::uint64_t summary_start = offset_;
  std::uint32_t summary_crc = 0;
  auto put_summary = [&](const std::vector<std::uint8_t>& bytes) {
    summary_crc = Crc32(bytes.data(), bytes.size(), summary_crc);
    Put(bytes);
  };
  Fields counts;
  for (const auto& [channel, n] : channel_counts_) counts.U16(channel).U64(n);
  Fields statistics;
  statistics.U64(messages_).U16(static_cast<std::uint16_t>(schemas_.size()));
  statistics.U32(static_cast<std::uint32_t>(channels_.size())).U32(0).U32(0);
  statistics.U32(static_cast<std::uint32_t>(chunk_indexes_.size())).U64(first_).U64(last_).Prefixed(counts);
  const std::vector<std::vector<std::uint8_t>> statistics_records = {Record(kStatistics, statistics)};

  std::vector<std::uint8_t> offsets;
  auto group = [&](std::uint8_t opcode, const std::vector<std::vector<std::uint8_t>>& records) {
    if (records.empty()) return;
    const std::uint64_t start = offset_;
    for (const auto& r : records) put_summary(r);
    const std::vector<std::uint8_t> so = Record(kSummaryOffset, Fields().U8(opcode).U64(start).U64(offset_ - start));
    offsets.insert(offsets.end(), so.begin(), so.end());
  };
  group(kSchema, schemas_);
  group(kChannel, channels_);
  group(kStatistics, statistics_records);
  group(kChunkIndex, chunk_indexes_);
  const std::uint64_t summary_offset_start = offset_;
  put_summary(offsets);

  Fields footer_head;
  footer_head.U8(kFooter).U64(8 + 8 + 4).U64(summary_start).U64(summary_offset_start);
  summary_crc = Crc32(footer_head.bytes.data(), footer_head.bytes.size(), summary_crc);
  Put(footer_head.U32(summary_crc).bytes);
  Put(std::vector<std::uint8_t>(std::begin(kMagic), std::end(kMagic)));
  out_->flush();
  if (!*out_) throw Error(name_ + ": write failed (disk full?)");
  return McapWriteSummary{offset_, messages_, static_cast<std::uint32_t>(chunk_indexes_.size())};
}

}  // namespace ssta::internal
