#include "bags/mcap_bag.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <deque>
#include <map>
#include <mutex>
#include <set>
#include <tuple>
#include <utility>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "bags/chunk_decompression.h"
#include "mcap/crc32.h"
#include "mcap/mcap_records.h"
#include "ssta/core/error.h"

namespace ssta::internal {
namespace {

using namespace mcap;  // NOLINT: the record opcodes and magic

constexpr std::uint64_t kMagicBytes = 8;
constexpr std::uint64_t kRecordHeaderBytes = 9;  // opcode uint8 + content length uint64
constexpr std::uint64_t kFooterBytes = kRecordHeaderBytes + 20;
constexpr std::uint64_t kMessageFixedBytes = 22;  // channel_id, sequence, log_time, publish_time
// A chunk's fields before its records: 28 bytes of sizes and times, the compression name (a
// few letters; 4 KiB is far more) and the records' length.
constexpr std::uint64_t kChunkHeadBytes = 4096;
/// BagMessageRef::offset of a Message record that sits in the data section, outside any chunk.
constexpr std::uint64_t kOutsideChunks = ~std::uint64_t{0};
constexpr std::size_t kCachedChunks = 2;

const char* RecordName(std::uint8_t opcode) {
  switch (opcode) {
    case kHeader: return "Header";
    case kFooter: return "Footer";
    case kSchema: return "Schema";
    case kChannel: return "Channel";
    case kMessage: return "Message";
    case kChunk: return "Chunk";
    case kMessageIndex: return "Message Index";
    case kChunkIndex: return "Chunk Index";
    case kStatistics: return "Statistics";
    case kDataEnd: return "Data End";
    default: return "record";
  }
}

/// Where an MCAP file's bytes come from: a file (pread, safe from several threads) or memory.
class ByteSource {
 public:
  virtual ~ByteSource() = default;
  virtual std::uint64_t size() const = 0;
  /// Copies [offset, offset + n); the caller has checked that the range lies inside size().
  virtual void ReadAt(std::uint64_t offset, std::uint8_t* out, std::size_t n) const = 0;
};

class FileSource : public ByteSource {
 public:
  explicit FileSource(const std::string& path) : path_(path) {
    fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd_ < 0) throw Error(path + ": cannot open: " + std::strerror(errno));
    struct stat st {};
    if (::fstat(fd_, &st) != 0 || !S_ISREG(st.st_mode)) {
      ::close(fd_);
      throw Error(path + ": not a regular file");
    }
    size_ = static_cast<std::uint64_t>(st.st_size);
  }
  ~FileSource() override { ::close(fd_); }
  FileSource(const FileSource&) = delete;
  FileSource& operator=(const FileSource&) = delete;

  std::uint64_t size() const override { return size_; }
  void ReadAt(std::uint64_t offset, std::uint8_t* out, std::size_t n) const override {
    while (n > 0) {
      const ssize_t got = ::pread(fd_, out, n, static_cast<off_t>(offset));
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) {
        throw Error(path_ + ": read error at offset " + std::to_string(offset) + ": " +
                    (got < 0 ? std::strerror(errno) : "the file shrank while open"));
      }
      out += got;
      offset += static_cast<std::uint64_t>(got);
      n -= static_cast<std::size_t>(got);
    }
  }

 private:
  std::string path_;
  int fd_ = -1;
  std::uint64_t size_ = 0;
};

class MemorySource : public ByteSource {
 public:
  explicit MemorySource(std::vector<std::uint8_t> bytes) : bytes_(std::move(bytes)) {}
  std::uint64_t size() const override { return bytes_.size(); }
  void ReadAt(std::uint64_t offset, std::uint8_t* out, std::size_t n) const override {
    if (n == 0) return;
    std::memcpy(out, bytes_.data() + offset, n);
  }

 private:
  std::vector<std::uint8_t> bytes_;
};

/// Little-endian fields of one record's content. Every read is checked against the content's
/// end; a failed check throws ssta::Error starting with `where`.
class Cursor {
 public:
  Cursor(const std::uint8_t* data, std::size_t size, std::string where)
      : data_(data), size_(size), where_(std::move(where)) {}

  std::uint8_t U8() { return static_cast<std::uint8_t>(Le(1)); }
  std::uint16_t U16() { return static_cast<std::uint16_t>(Le(2)); }
  std::uint32_t U32() { return static_cast<std::uint32_t>(Le(4)); }
  std::uint64_t U64() { return Le(8); }
  std::string String() {
    const std::uint32_t n = U32();
    const std::uint8_t* p = Take(n, "a string");
    return std::string(reinterpret_cast<const char*>(p), n);
  }
  /// `n` bytes in place; valid while the record's buffer lives.
  const std::uint8_t* Take(std::uint64_t n, const char* what) {
    if (n > size_ - pos_) {
      Fail(std::string(what) + " of " + std::to_string(n) + " bytes runs past the record's end (" +
           std::to_string(size_ - pos_) + " bytes left)");
    }
    const std::uint8_t* p = data_ + pos_;
    pos_ += static_cast<std::size_t>(n);
    return p;
  }
  std::size_t remaining() const { return size_ - pos_; }
  [[noreturn]] void Fail(const std::string& what) const { throw Error(where_ + ": " + what); }

 private:
  std::uint64_t Le(int bytes) {
    const std::uint8_t* p = Take(static_cast<std::uint64_t>(bytes), "a field");
    std::uint64_t v = 0;
    for (int i = bytes - 1; i >= 0; --i) v = (v << 8) | p[i];
    return v;
  }

  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
  std::string where_;
};

struct RecordHeader {
  std::uint64_t offset = 0;  ///< of the opcode byte
  std::uint8_t opcode = 0;
  std::uint64_t length = 0;  ///< of the content
  std::uint64_t content() const { return offset + kRecordHeaderBytes; }
  std::uint64_t end() const { return content() + length; }
};

/// What a Chunk Index record says about one chunk.
struct IndexedChunk {
  std::uint64_t offset = 0;
  std::uint64_t uncompressed_size = 0;
  std::vector<std::pair<std::uint16_t, std::uint64_t>> message_index_offsets;  ///< channel -> file offset
};

struct RawChannel {
  std::uint16_t schema_id = 0;
  std::string topic;
  std::string encoding;
};

/// (id, name) of a Schema record.
std::pair<std::uint16_t, std::string> ParseSchema(Cursor& c) {
  const std::uint16_t id = c.U16();
  return {id, c.String()};
}

std::pair<std::uint16_t, RawChannel> ParseChannel(Cursor& c) {
  const std::uint16_t id = c.U16();
  RawChannel channel;
  channel.schema_id = c.U16();
  channel.topic = c.String();
  channel.encoding = c.String();
  return {id, std::move(channel)};
}

/// The records of one decompressed chunk that a reader needs; the messages' `connection` holds
/// their channel id.
struct ChunkRecords {
  std::vector<std::pair<std::uint16_t, std::string>> schemas;
  std::vector<std::pair<std::uint16_t, RawChannel>> channels;
  std::vector<BagMessageRef> messages;
};

ChunkRecords ParseChunkRecords(const std::vector<std::uint8_t>& records, std::uint64_t chunk_offset,
                               const std::string& where) {
  ChunkRecords out;
  std::size_t pos = 0;
  while (pos < records.size()) {
    Cursor c(records.data() + pos, records.size() - pos, where + ", inner record at offset " + std::to_string(pos));
    const std::uint8_t opcode = c.U8();
    const std::uint64_t length = c.U64();
    const std::uint8_t* content = c.Take(length, "the record's content");
    Cursor r(content, static_cast<std::size_t>(length),
             where + ", inner " + RecordName(opcode) + " at offset " + std::to_string(pos));
    if (opcode == kSchema) {
      out.schemas.push_back(ParseSchema(r));
    } else if (opcode == kChannel) {
      out.channels.push_back(ParseChannel(r));
    } else if (opcode == kMessage) {
      BagMessageRef ref;
      ref.connection = r.U16();
      r.U32();  // sequence
      ref.log_time_ns = static_cast<std::int64_t>(r.U64());
      r.U64();  // publish_time
      ref.position = chunk_offset;
      ref.offset = pos;
      out.messages.push_back(ref);
    }
    pos += static_cast<std::size_t>(kRecordHeaderBytes + length);
  }
  return out;
}

/// How a scan treats the end of its range: a complete file's records must fit exactly; a file
/// cut off by a crash ends wherever its last complete record ends.
enum class ScanEnd { kExact, kMayBeCut };

class McapBag : public BagReader {
 public:
  McapBag(std::unique_ptr<ByteSource> source, std::string path);

  const std::string& path() const override { return path_; }
  std::string format() const override { return "ros2 mcap"; }
  const std::vector<BagConnection>& connections() const override { return connections_; }
  std::vector<BagMessageRef> List(const std::vector<int>& connections) const override;
  std::vector<std::uint8_t> Read(const BagMessageRef& ref) const override;
  std::string Truncation() const override { return truncation_; }

 private:
  std::string Where(const char* record, std::uint64_t offset) const {
    return path_ + ": " + record + " record at offset " + std::to_string(offset);
  }
  std::vector<std::uint8_t> Bytes(std::uint64_t offset, std::uint64_t n) const;
  /// The record header at `offset`, its content checked to end by `end`.
  RecordHeader HeaderAt(std::uint64_t offset, std::uint64_t end) const;
  std::vector<std::uint8_t> Content(const RecordHeader& h) const { return Bytes(h.content(), h.length); }

  std::uint64_t ReadHeaderRecord() const;
  void ReadSummary(std::uint64_t begin, std::uint64_t end, std::uint64_t data_begin);
  void ScanData(std::uint64_t begin, std::uint64_t end, ScanEnd scan_end);
  /// True when the record at `pos` does not fit before `end` (or is a crash's zero tail).
  bool IsCutAt(std::uint64_t pos, std::uint64_t end) const;
  void AddSchema(std::pair<std::uint16_t, std::string> schema);
  void AddChannel(std::pair<std::uint16_t, RawChannel> channel);
  void ResolveConnections();

  /// The decompressed records of the chunk at `offset`, from the cache when there. Lock held.
  std::shared_ptr<const std::vector<std::uint8_t>> ChunkAt(std::uint64_t offset) const;
  std::vector<std::uint8_t> DecodeChunk(const RecordHeader& h) const;
  void AppendIndexed(const IndexedChunk& chunk, const std::set<std::uint16_t>& channels,
                     std::vector<BagMessageRef>* out) const;
  std::vector<std::uint8_t> MessageData(const std::uint8_t* content, std::size_t size, const BagMessageRef& ref,
                                        const std::string& where) const;
  int ConnectionOfChannel(std::uint16_t channel, const std::string& where) const;

  std::unique_ptr<ByteSource> source_;
  std::string path_;
  std::vector<BagConnection> connections_;
  std::map<std::uint16_t, std::string> schema_names_;
  std::map<std::uint16_t, RawChannel> channels_;
  std::map<std::uint16_t, int> channel_connection_;
  // Either the index (a complete file's summary) or every message found by the scan.
  bool indexed_ = false;
  std::vector<IndexedChunk> chunks_;
  std::vector<BagMessageRef> scanned_;  ///< `connection` holds the channel id until ResolveConnections
  std::string truncation_;              ///< BagReader::Truncation

  mutable std::mutex mutex_;
  mutable std::deque<std::pair<std::uint64_t, std::shared_ptr<const std::vector<std::uint8_t>>>> cache_;
};

McapBag::McapBag(std::unique_ptr<ByteSource> source, std::string path)
    : source_(std::move(source)), path_(std::move(path)) {
  const std::uint64_t size = source_->size();
  if (size < kMagicBytes || Bytes(0, kMagicBytes) != std::vector<std::uint8_t>(kMagic, kMagic + kMagicBytes)) {
    throw Error(path_ + ": not an MCAP file (it does not start with the MCAP magic bytes)");
  }
  const std::uint64_t data_begin = ReadHeaderRecord();

  // A complete file ends with a Footer record and the magic; a recording cut off by a crash
  // does not, and is read up to its last complete record.
  const bool complete = size >= data_begin + kFooterBytes + kMagicBytes &&
                        Bytes(size - kMagicBytes, kMagicBytes) == std::vector<std::uint8_t>(kMagic, kMagic + kMagicBytes);
  if (!complete) {
    ScanData(data_begin, size, ScanEnd::kMayBeCut);
    ResolveConnections();
    return;
  }
  const std::uint64_t footer_offset = size - kMagicBytes - kFooterBytes;
  const RecordHeader footer = HeaderAt(footer_offset, size - kMagicBytes);
  if (footer.opcode != kFooter || footer.length != kFooterBytes - kRecordHeaderBytes) {
    throw Error(Where("Footer", footer_offset) + ": no Footer record before the closing magic bytes");
  }
  const std::vector<std::uint8_t> footer_content = Content(footer);
  Cursor f(footer_content.data(), footer_content.size(), Where("Footer", footer_offset));
  const std::uint64_t summary_start = f.U64();
  const std::uint64_t summary_offset_start = f.U64();
  if (summary_start != 0) {
    const std::uint64_t summary_end = summary_offset_start != 0 ? summary_offset_start : footer_offset;
    if (summary_start < data_begin || summary_start > summary_end || summary_end > footer_offset) {
      f.Fail("summary section [" + std::to_string(summary_start) + ", " + std::to_string(summary_end) +
             ") lies outside the file's " + std::to_string(size) + " bytes");
    }
    ReadSummary(summary_start, summary_end, data_begin);
  }
  if (!indexed_) ScanData(data_begin, summary_start != 0 ? summary_start : footer_offset, ScanEnd::kExact);
  ResolveConnections();
}

std::vector<std::uint8_t> McapBag::Bytes(std::uint64_t offset, std::uint64_t n) const {
  // Every length comes from the file: it is checked against the file's size before anything is
  // allocated for it.
  if (offset > source_->size() || n > source_->size() - offset) {
    throw Error(path_ + ": " + std::to_string(n) + " bytes at offset " + std::to_string(offset) +
                " run past the end of the file (" + std::to_string(source_->size()) + " bytes)");
  }
  std::vector<std::uint8_t> out(static_cast<std::size_t>(n));
  source_->ReadAt(offset, out.data(), out.size());
  return out;
}

RecordHeader McapBag::HeaderAt(std::uint64_t offset, std::uint64_t end) const {
  if (offset > end || end - offset < kRecordHeaderBytes) {
    throw Error(path_ + ": record at offset " + std::to_string(offset) + " is cut off (its header runs past " +
                std::to_string(end) + ")");
  }
  const std::vector<std::uint8_t> raw = Bytes(offset, kRecordHeaderBytes);
  RecordHeader h;
  h.offset = offset;
  h.opcode = raw[0];
  for (int i = 8; i >= 1; --i) h.length = (h.length << 8) | raw[static_cast<std::size_t>(i)];
  if (h.length > end - offset - kRecordHeaderBytes) {
    throw Error(Where(RecordName(h.opcode), offset) + ": length " + std::to_string(h.length) + " runs past " +
                std::to_string(end) + " (the end of its section or file)");
  }
  return h;
}

std::uint64_t McapBag::ReadHeaderRecord() const {
  const std::uint64_t size = source_->size();
  if (size - kMagicBytes < kRecordHeaderBytes) {
    throw Error(path_ + ": cut off at offset " + std::to_string(size) + ", before its Header record");
  }
  const RecordHeader h = HeaderAt(kMagicBytes, size);
  if (h.opcode != kHeader) {
    throw Error(Where(RecordName(h.opcode), kMagicBytes) + ": the first record must be a Header (opcode " +
                std::to_string(h.opcode) + ")");
  }
  return h.end();
}

void McapBag::ReadSummary(std::uint64_t begin, std::uint64_t end, std::uint64_t data_begin) {
  bool has_statistics = false;
  std::uint64_t message_count = 0;
  std::uint64_t chunk_count = 0;
  for (std::uint64_t pos = begin; pos < end;) {
    const RecordHeader h = HeaderAt(pos, end);
    pos = h.end();
    if (h.opcode != kSchema && h.opcode != kChannel && h.opcode != kChunkIndex && h.opcode != kStatistics) continue;
    const std::vector<std::uint8_t> content = Content(h);
    Cursor c(content.data(), content.size(), Where(RecordName(h.opcode), h.offset));
    if (h.opcode == kSchema) {
      AddSchema(ParseSchema(c));
    } else if (h.opcode == kChannel) {
      AddChannel(ParseChannel(c));
    } else if (h.opcode == kStatistics) {
      has_statistics = true;
      message_count = c.U64();
      c.U16();  // schema_count
      c.U32();  // channel_count
      c.U32();  // attachment_count
      c.U32();  // metadata_count
      chunk_count = c.U32();
    } else {
      IndexedChunk chunk;
      c.U64();  // message_start_time
      c.U64();  // message_end_time
      chunk.offset = c.U64();
      const std::uint64_t chunk_length = c.U64();
      if (chunk.offset < data_begin || chunk_length < kRecordHeaderBytes || chunk.offset > begin ||
          chunk_length > begin - chunk.offset) {
        c.Fail("chunk [" + std::to_string(chunk.offset) + ", +" + std::to_string(chunk_length) +
               ") lies outside the data section");
      }
      const std::uint32_t map_bytes = c.U32();
      Cursor map(c.Take(map_bytes, "message_index_offsets"), map_bytes, Where("Chunk Index", h.offset));
      while (map.remaining() > 0) {
        const std::uint16_t channel = map.U16();
        chunk.message_index_offsets.emplace_back(channel, map.U64());
      }
      c.U64();     // message_index_length
      c.String();  // compression, read again from the chunk itself
      c.U64();     // compressed_size
      chunk.uncompressed_size = c.U64();
      chunks_.push_back(std::move(chunk));
    }
  }
  // The index is used when it covers every chunk (or the file has no messages); a summary
  // without Chunk Index records leaves the data section to be scanned.
  if (!chunks_.empty()) {
    indexed_ = !has_statistics || chunk_count == chunks_.size();
  } else {
    indexed_ = has_statistics && message_count == 0;
  }
  if (!indexed_) chunks_.clear();
  std::sort(chunks_.begin(), chunks_.end(),
            [](const IndexedChunk& a, const IndexedChunk& b) { return a.offset < b.offset; });
}

void McapBag::ScanData(std::uint64_t begin, std::uint64_t end, ScanEnd scan_end) {
  const bool may_be_cut = scan_end == ScanEnd::kMayBeCut;
  std::uint64_t pos = begin;
  bool cut = false;
  std::string last_record;  // the record the file ends in or after
  while (pos < end) {
    if (may_be_cut && IsCutAt(pos, end)) {
      cut = true;
      break;
    }
    const RecordHeader h = HeaderAt(pos, end);
    pos = h.end();
    last_record = RecordName(h.opcode);
    // The data section ends here: every message is in the file, whatever follows it.
    if (h.opcode == kDataEnd || h.opcode == kFooter) return;
    if (h.opcode == kSchema || h.opcode == kChannel) {
      const std::vector<std::uint8_t> content = Content(h);
      Cursor c(content.data(), content.size(), Where(RecordName(h.opcode), h.offset));
      if (h.opcode == kSchema) {
        AddSchema(ParseSchema(c));
      } else {
        AddChannel(ParseChannel(c));
      }
    } else if (h.opcode == kMessage) {
      if (h.length < kMessageFixedBytes) throw Error(Where("Message", h.offset) + ": shorter than its fixed fields");
      const std::vector<std::uint8_t> fixed = Bytes(h.content(), kMessageFixedBytes);
      Cursor c(fixed.data(), fixed.size(), Where("Message", h.offset));
      BagMessageRef ref;
      ref.connection = c.U16();
      c.U32();  // sequence
      ref.log_time_ns = static_cast<std::int64_t>(c.U64());
      ref.position = h.offset;
      ref.offset = kOutsideChunks;
      scanned_.push_back(ref);
    } else if (h.opcode == kChunk) {
      ChunkRecords records = ParseChunkRecords(DecodeChunk(h), h.offset, Where("Chunk", h.offset));
      for (auto& schema : records.schemas) AddSchema(std::move(schema));
      for (auto& channel : records.channels) AddChannel(std::move(channel));
      scanned_.insert(scanned_.end(), records.messages.begin(), records.messages.end());
    }
  }
  if (!may_be_cut) return;
  // The file stops before its Data End record: the recording did not finish.
  std::string what = cut ? "the file ends inside a " + std::string(end - pos >= 1 ? RecordName(Bytes(pos, 1)[0]) : "record") +
                               " record at offset " + std::to_string(pos)
                         : "the file ends after a " + (last_record.empty() ? std::string("Header") : last_record) +
                               " record at offset " + std::to_string(pos);
  what += ", before the Data End record, the summary and the footer (the recording did not finish)";
  std::int64_t last = -1;
  for (const BagMessageRef& ref : scanned_) last = std::max(last, ref.log_time_ns);
  truncation_ = TruncationText(path_, what, last);
  if (scanned_.empty()) throw Error(truncation_);
}

bool McapBag::IsCutAt(std::uint64_t pos, std::uint64_t end) const {
  if (end - pos < kRecordHeaderBytes) return true;
  const std::vector<std::uint8_t> raw = Bytes(pos, kRecordHeaderBytes);
  std::uint64_t length = 0;
  for (int i = 8; i >= 1; --i) length = (length << 8) | raw[static_cast<std::size_t>(i)];
  // After a crash the file system may leave a tail of zeros: opcode 0 is no record.
  return raw[0] == 0 || length > end - pos - kRecordHeaderBytes;
}

void McapBag::AddSchema(std::pair<std::uint16_t, std::string> schema) {
  if (schema.first != 0) schema_names_[schema.first] = std::move(schema.second);  // id 0 is invalid: ignored
}

void McapBag::AddChannel(std::pair<std::uint16_t, RawChannel> channel) {
  channels_[channel.first] = std::move(channel.second);
}

void McapBag::ResolveConnections() {
  // One connection per (topic, type, encoding): channels of several publishers merge.
  std::map<std::tuple<std::string, std::string, std::string>, int> known;
  for (const auto& [id, channel] : channels_) {
    std::string type;
    if (channel.schema_id != 0) {
      const auto schema = schema_names_.find(channel.schema_id);
      if (schema == schema_names_.end()) {
        throw Error(path_ + ": channel " + std::to_string(id) + " (" + channel.topic + ") names schema " +
                    std::to_string(channel.schema_id) + ", which no Schema record defines");
      }
      type = schema->second;
    }
    const auto key = std::make_tuple(channel.topic, type, channel.encoding);
    auto it = known.find(key);
    if (it == known.end()) {
      it = known.emplace(key, static_cast<int>(connections_.size())).first;
      connections_.push_back(BagConnection{channel.topic, type, channel.encoding});
    }
    channel_connection_[id] = it->second;
  }
  for (BagMessageRef& ref : scanned_) {
    const std::string where =
        ref.offset == kOutsideChunks ? Where("Message", ref.position)
                                     : Where("Chunk", ref.position) + ", message at offset " + std::to_string(ref.offset);
    ref.connection = ConnectionOfChannel(static_cast<std::uint16_t>(ref.connection), where);
  }
}

int McapBag::ConnectionOfChannel(std::uint16_t channel, const std::string& where) const {
  const auto it = channel_connection_.find(channel);
  if (it == channel_connection_.end()) {
    throw Error(where + ": channel " + std::to_string(channel) + " has no Channel record");
  }
  return it->second;
}

std::vector<BagMessageRef> McapBag::List(const std::vector<int>& connections) const {
  const std::set<int> wanted(connections.begin(), connections.end());
  std::vector<BagMessageRef> out;
  if (!indexed_) {
    for (const BagMessageRef& ref : scanned_) {
      if (wanted.count(ref.connection)) out.push_back(ref);
    }
  } else {
    std::set<std::uint16_t> channels;
    for (const auto& [channel, connection] : channel_connection_) {
      if (wanted.count(connection)) channels.insert(channel);
    }
    std::lock_guard<std::mutex> lock(mutex_);
    for (const IndexedChunk& chunk : chunks_) AppendIndexed(chunk, channels, &out);
  }
  std::sort(out.begin(), out.end(), [](const BagMessageRef& a, const BagMessageRef& b) {
    return std::tie(a.log_time_ns, a.position, a.offset) < std::tie(b.log_time_ns, b.position, b.offset);
  });
  return out;
}

void McapBag::AppendIndexed(const IndexedChunk& chunk, const std::set<std::uint16_t>& channels,
                            std::vector<BagMessageRef>* out) const {
  if (chunk.message_index_offsets.empty()) {
    // A chunk without Message Index records (the writer's choice): its messages are found by
    // decompressing it.
    if (chunk.uncompressed_size == 0) return;
    // Schema and Channel records inside it were copied to the summary (the spec requires it).
    const ChunkRecords records = ParseChunkRecords(*ChunkAt(chunk.offset), chunk.offset, Where("Chunk", chunk.offset));
    for (BagMessageRef ref : records.messages) {
      const auto channel = static_cast<std::uint16_t>(ref.connection);
      if (!channels.count(channel)) continue;
      ref.connection = ConnectionOfChannel(channel, Where("Chunk", chunk.offset));
      out->push_back(ref);
    }
    return;
  }
  for (const auto& [channel, index_offset] : chunk.message_index_offsets) {
    if (!channels.count(channel)) continue;
    const RecordHeader h = HeaderAt(index_offset, source_->size());
    const std::string where = Where("Message Index", index_offset);
    if (h.opcode != kMessageIndex) {
      throw Error(where + ": the Chunk Index points at a " + RecordName(h.opcode) + " (opcode " +
                  std::to_string(h.opcode) + ")");
    }
    const std::vector<std::uint8_t> content = Content(h);
    Cursor c(content.data(), content.size(), where);
    if (c.U16() != channel) c.Fail("indexes another channel than the Chunk Index says");
    const std::uint32_t array_bytes = c.U32();
    Cursor entries(c.Take(array_bytes, "the index entries"), array_bytes, where);
    const int connection = ConnectionOfChannel(channel, where);
    while (entries.remaining() > 0) {
      BagMessageRef ref;
      ref.log_time_ns = static_cast<std::int64_t>(entries.U64());
      ref.offset = entries.U64();
      if (ref.offset >= chunk.uncompressed_size) {
        entries.Fail("message offset " + std::to_string(ref.offset) + " lies past the chunk's " +
                     std::to_string(chunk.uncompressed_size) + " bytes");
      }
      ref.connection = connection;
      ref.position = chunk.offset;
      out->push_back(ref);
    }
  }
}

std::vector<std::uint8_t> McapBag::Read(const BagMessageRef& ref) const {
  SSTA_CHECK(ref.connection >= 0 && ref.connection < static_cast<int>(connections_.size()),
             "BagMessageRef of another bag");
  std::lock_guard<std::mutex> lock(mutex_);
  if (ref.offset == kOutsideChunks) {
    const RecordHeader h = HeaderAt(ref.position, source_->size());
    const std::string where = Where(RecordName(h.opcode), ref.position);
    if (h.opcode != kMessage) throw Error(where + ": expected a Message record");
    const std::vector<std::uint8_t> content = Content(h);
    return MessageData(content.data(), content.size(), ref, where);
  }
  const std::shared_ptr<const std::vector<std::uint8_t>> chunk = ChunkAt(ref.position);
  const std::string where = Where("Chunk", ref.position) + ", message at offset " + std::to_string(ref.offset);
  if (ref.offset >= chunk->size()) throw Error(where + ": past the chunk's end");
  Cursor c(chunk->data() + ref.offset, chunk->size() - static_cast<std::size_t>(ref.offset), where);
  if (c.U8() != kMessage) c.Fail("no Message record there");
  const std::uint64_t length = c.U64();
  const std::uint8_t* content = c.Take(length, "the Message record");
  return MessageData(content, static_cast<std::size_t>(length), ref, where);
}

std::vector<std::uint8_t> McapBag::MessageData(const std::uint8_t* content, std::size_t size,
                                               const BagMessageRef& ref, const std::string& where) const {
  Cursor c(content, size, where);
  const std::uint16_t channel = c.U16();
  if (ConnectionOfChannel(channel, where) != ref.connection) {
    c.Fail("the message is on channel " + std::to_string(channel) + ", not on the topic its index names");
  }
  c.Take(kMessageFixedBytes - 2, "the Message's fixed fields");
  const std::size_t n = c.remaining();
  const std::uint8_t* data = c.Take(n, "the message data");
  return std::vector<std::uint8_t>(data, data + n);
}

std::shared_ptr<const std::vector<std::uint8_t>> McapBag::ChunkAt(std::uint64_t offset) const {
  for (const auto& [cached_offset, records] : cache_) {
    if (cached_offset == offset) return records;
  }
  const RecordHeader h = HeaderAt(offset, source_->size());
  if (h.opcode != kChunk) {
    throw Error(Where(RecordName(h.opcode), offset) + ": expected a Chunk record (opcode " +
                std::to_string(h.opcode) + ")");
  }
  auto records = std::make_shared<const std::vector<std::uint8_t>>(DecodeChunk(h));
  cache_.emplace_front(offset, records);
  if (cache_.size() > kCachedChunks) cache_.pop_back();
  return records;
}

std::vector<std::uint8_t> McapBag::DecodeChunk(const RecordHeader& h) const {
  const std::string where = Where("Chunk", h.offset);
  // The fields before the records first: the sizes they announce are checked before the
  // records are read into memory.
  const std::vector<std::uint8_t> head = Bytes(h.content(), std::min<std::uint64_t>(h.length, kChunkHeadBytes));
  Cursor c(head.data(), head.size(), where);
  c.U64();  // message_start_time
  c.U64();  // message_end_time
  const std::uint64_t uncompressed_size = c.U64();
  const std::uint32_t crc = c.U32();
  const std::string compression = c.String();
  const std::uint64_t records_bytes = c.U64();
  const std::uint64_t records_offset = head.size() - c.remaining();
  if (uncompressed_size > kMaxChunkBytes || records_bytes > 2 * kMaxChunkBytes) {
    throw Error(where + ": the chunk announces " + std::to_string(uncompressed_size) + " bytes (" +
                std::to_string(records_bytes) + " stored), more than the 256 MiB this reader accepts");
  }
  if (records_bytes > h.length - records_offset) {
    throw Error(where + ": the chunk's records (" + std::to_string(records_bytes) + " bytes) run past its record (" +
                std::to_string(h.length) + " bytes)");
  }
  const std::vector<std::uint8_t> records = Bytes(h.content() + records_offset, records_bytes);
  std::vector<std::uint8_t> out = DecompressChunk(compression, records.data(), records.size(), uncompressed_size, where);
  // A CRC of zero means the writer did not compute one.
  if (crc != 0 && Crc32(out.data(), out.size()) != crc) {
    throw Error(where + ": CRC-32 of the uncompressed records does not match (the chunk is corrupt)");
  }
  return out;
}

}  // namespace

std::unique_ptr<BagReader> OpenMcapFile(const std::string& path) {
  return std::make_unique<McapBag>(std::make_unique<FileSource>(path), path);
}

std::unique_ptr<BagReader> OpenMcapBytes(std::vector<std::uint8_t> bytes, const std::string& name) {
  return std::make_unique<McapBag>(std::make_unique<MemorySource>(std::move(bytes)), name);
}

}  // namespace ssta::internal
