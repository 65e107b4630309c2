#include "bags/support/ros2_bag_writer.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>

#include <lz4frame.h>
#include <sqlite3.h>
#include <zstd.h>

#include "mcap/crc32.h"

namespace fs = std::filesystem;

namespace ssta::testing {

class Ros2BagWriter::StorageFile {
 public:
  virtual ~StorageFile() = default;
  /// `id` is the topic's index in the writer, the same in every file.
  virtual void AddTopic(int id, const std::string& name, const std::string& type) = 0;
  virtual void Write(int id, std::int64_t log_time_ns, const std::vector<std::uint8_t>& cdr) = 0;
  virtual void Finish() = 0;
};

namespace {

[[noreturn]] void Fail(const std::string& what) { throw std::runtime_error("Ros2BagWriter: " + what); }

/// Little-endian MCAP fields appended to a buffer.
class Bytes {
 public:
  Bytes& U8(std::uint8_t v) { return Le(v, 1); }
  Bytes& U16(std::uint16_t v) { return Le(v, 2); }
  Bytes& U32(std::uint32_t v) { return Le(v, 4); }
  Bytes& U64(std::uint64_t v) { return Le(v, 8); }
  Bytes& String(const std::string& s) {
    U32(static_cast<std::uint32_t>(s.size()));
    data.insert(data.end(), s.begin(), s.end());
    return *this;
  }
  Bytes& Raw(const std::vector<std::uint8_t>& bytes) {
    data.insert(data.end(), bytes.begin(), bytes.end());
    return *this;
  }
  std::vector<std::uint8_t> data;

 private:
  Bytes& Le(std::uint64_t v, int n) {
    for (int i = 0; i < n; ++i) data.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
    return *this;
  }
};

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

std::vector<std::uint8_t> Record(std::uint8_t opcode, const Bytes& content) {
  Bytes r;
  r.U8(opcode).U64(content.data.size()).Raw(content.data);
  return r.data;
}

std::vector<std::uint8_t> Compress(McapCompression compression, const std::vector<std::uint8_t>& in) {
  if (compression == McapCompression::kNone) return in;
  std::vector<std::uint8_t> out;
  if (compression == McapCompression::kZstd) {
    out.resize(ZSTD_compressBound(in.size()));
    const std::size_t n = ZSTD_compress(out.data(), out.size(), in.data(), in.size(), 1);
    if (ZSTD_isError(n)) Fail("zstd compression failed");
    out.resize(n);
  } else {
    out.resize(LZ4F_compressFrameBound(in.size(), nullptr));
    const std::size_t n = LZ4F_compressFrame(out.data(), out.size(), in.data(), in.size(), nullptr);
    if (LZ4F_isError(n)) Fail("lz4 compression failed");
    out.resize(n);
  }
  return out;
}

const char* CompressionName(McapCompression compression) {
  switch (compression) {
    case McapCompression::kZstd: return "zstd";
    case McapCompression::kLz4: return "lz4";
    case McapCompression::kNone: break;
  }
  return "";
}

/// An MCAP file as rosbag2's MCAP plugin writes it: Schema and Channel records inside the chunks,
/// Message Index records after each chunk, the summary (optional here) at the end.
class McapFile : public Ros2BagWriter::StorageFile {
 public:
  McapFile(std::string path, const Ros2BagWriterOptions& options, std::vector<McapChunkSpan>* spans)
      : path_(std::move(path)), options_(options), spans_(spans), out_(path_, std::ios::binary) {
    if (!out_) Fail("cannot create " + path_);
    static const std::vector<std::uint8_t> kMagic = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};
    Put(kMagic);
    Put(Record(kHeader, Bytes().String("ros2").String("ssta test writer")));
  }

  void AddTopic(int id, const std::string& name, const std::string& type) override {
    // Ids start at 1 (0 is no schema); topic index 0 is channel 1, schema 1.
    const auto channel = static_cast<std::uint16_t>(id + 1);
    Bytes schema;
    schema.U16(channel).String(type).String("ros2msg").String("# " + type);  // data: a uint32-prefixed text
    Bytes ch;
    ch.U16(channel).U16(channel).String(name).String("cdr");
    Bytes metadata;
    metadata.String("offered_qos_profiles").String("");
    ch.U32(static_cast<std::uint32_t>(metadata.data.size())).Raw(metadata.data);
    schemas_.push_back(Record(kSchema, schema));
    channels_.push_back(Record(kChannel, ch));
    Append(schemas_.back());
    Append(channels_.back());
  }

  void Write(int id, std::int64_t log_time_ns, const std::vector<std::uint8_t>& cdr) override {
    const auto channel = static_cast<std::uint16_t>(id + 1);
    const auto t = static_cast<std::uint64_t>(log_time_ns);
    Bytes m;
    m.U16(channel).U32(sequence_++).U64(t).U64(t).Raw(cdr);
    if (chunk_messages_ == 0 || t < chunk_start_) chunk_start_ = t;
    if (chunk_messages_ == 0 || t > chunk_end_) chunk_end_ = t;
    index_[channel].emplace_back(t, chunk_.size());
    Append(Record(kMessage, m));
    ++chunk_messages_;
    ++message_count_;
    ++channel_counts_[channel];
    if (message_count_ == 1 || t < first_) first_ = t;
    if (message_count_ == 1 || t > last_) last_ = t;
    if (chunk_.size() >= options_.chunk_bytes) FlushChunk();
  }

  void Finish() override {
    FlushChunk();
    Put(Record(kDataEnd, Bytes().U32(0)));
    std::uint64_t summary_start = 0;
    std::uint64_t summary_offset_start = 0;
    if (options_.summary) {
      summary_start = offset_;
      std::vector<std::uint8_t> offsets;
      auto group = [&](std::uint8_t opcode, const std::vector<std::vector<std::uint8_t>>& records) {
        const std::uint64_t start = offset_;
        for (const auto& r : records) Put(r);
        Bytes so;
        so.U8(opcode).U64(start).U64(offset_ - start);
        const std::vector<std::uint8_t> record = Record(kSummaryOffset, so);
        offsets.insert(offsets.end(), record.begin(), record.end());
      };
      group(kSchema, schemas_);
      group(kChannel, channels_);
      group(kStatistics, {Record(kStatistics, Statistics())});
      group(kChunkIndex, chunk_indexes_);
      summary_offset_start = offset_;
      Put(offsets);
    }
    Put(Record(kFooter, Bytes().U64(summary_start).U64(summary_offset_start).U32(0)));
    static const std::vector<std::uint8_t> kMagic = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};
    Put(kMagic);
    out_.close();
    if (!out_) Fail("cannot write " + path_);
  }

 private:
  void Put(const std::vector<std::uint8_t>& bytes) {
    out_.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    offset_ += bytes.size();
  }
  void Append(const std::vector<std::uint8_t>& record) { chunk_.insert(chunk_.end(), record.begin(), record.end()); }

  void FlushChunk() {
    if (chunk_.empty()) return;
    const std::vector<std::uint8_t> records = Compress(options_.compression, chunk_);
    const std::uint32_t crc = options_.chunk_crc ? internal::Crc32(chunk_.data(), chunk_.size()) : 0;
    Bytes c;
    c.U64(chunk_start_).U64(chunk_end_).U64(chunk_.size()).U32(crc).String(CompressionName(options_.compression));
    const std::uint64_t records_field = c.data.size() + 8;
    c.U64(records.size()).Raw(records);
    const std::uint64_t chunk_offset = offset_;
    Put(Record(kChunk, c));
    spans_->push_back(McapChunkSpan{path_, chunk_offset, offset_ - chunk_offset, chunk_offset + 9 + records_field,
                                    records.size(), chunk_messages_, static_cast<std::int64_t>(chunk_end_)});

    const std::uint64_t index_start = offset_;
    Bytes index_offsets;
    for (const auto& [channel, entries] : index_) {
      Bytes entry_bytes;
      for (const auto& [t, at] : entries) entry_bytes.U64(t).U64(at);
      Bytes mi;
      mi.U16(channel).U32(static_cast<std::uint32_t>(entry_bytes.data.size())).Raw(entry_bytes.data);
      index_offsets.U16(channel).U64(offset_);
      Put(Record(kMessageIndex, mi));
    }
    Bytes ci;
    ci.U64(chunk_start_).U64(chunk_end_).U64(chunk_offset).U64(index_start - chunk_offset);
    ci.U32(static_cast<std::uint32_t>(index_offsets.data.size())).Raw(index_offsets.data);
    ci.U64(offset_ - index_start).String(CompressionName(options_.compression)).U64(records.size()).U64(chunk_.size());
    chunk_indexes_.push_back(Record(kChunkIndex, ci));

    chunk_.clear();
    index_.clear();
    chunk_messages_ = 0;
  }

  Bytes Statistics() const {
    Bytes counts;
    for (const auto& [channel, n] : channel_counts_) counts.U16(channel).U64(n);
    Bytes s;
    s.U64(message_count_).U16(static_cast<std::uint16_t>(schemas_.size())).U32(static_cast<std::uint32_t>(channels_.size()));
    s.U32(0).U32(0).U32(static_cast<std::uint32_t>(chunk_indexes_.size()));
    s.U64(first_).U64(last_).U32(static_cast<std::uint32_t>(counts.data.size())).Raw(counts.data);
    return s;
  }

  std::string path_;
  Ros2BagWriterOptions options_;
  std::vector<McapChunkSpan>* spans_;
  std::ofstream out_;
  std::uint64_t offset_ = 0;
  std::vector<std::vector<std::uint8_t>> schemas_, channels_, chunk_indexes_;
  // The open chunk.
  std::vector<std::uint8_t> chunk_;
  std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> index_;
  std::uint64_t chunk_start_ = 0, chunk_end_ = 0;
  std::size_t chunk_messages_ = 0;
  // The whole file.
  std::uint32_t sequence_ = 0;
  std::uint64_t message_count_ = 0, first_ = 0, last_ = 0;
  std::map<std::uint16_t, std::uint64_t> channel_counts_;
};

/// A .db3 file with rosbag2's (Humble) tables.
class Db3File : public Ros2BagWriter::StorageFile {
 public:
  explicit Db3File(const std::string& path) {
    if (sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) != SQLITE_OK) {
      Fail("cannot create " + path);
    }
    Exec("CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);"
         "INSERT INTO schema VALUES(3, 'humble');"
         "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL,"
         " serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);"
         "CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL,"
         " timestamp INTEGER NOT NULL, data BLOB NOT NULL);"
         "CREATE INDEX timestamp_idx ON messages (timestamp ASC);"
         "BEGIN;");
    if (sqlite3_prepare_v2(db_, "INSERT INTO messages(topic_id, timestamp, data) VALUES(?, ?, ?)", -1, &insert_,
                           nullptr) != SQLITE_OK) {
      Fail(sqlite3_errmsg(db_));
    }
  }
  ~Db3File() override {
    sqlite3_finalize(insert_);
    sqlite3_close(db_);
  }

  void AddTopic(int id, const std::string& name, const std::string& type) override {
    sqlite3_stmt* s = nullptr;
    sqlite3_prepare_v2(db_, "INSERT INTO topics VALUES(?, ?, ?, 'cdr', '')", -1, &s, nullptr);
    sqlite3_bind_int(s, 1, id + 1);
    sqlite3_bind_text(s, 2, name.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(s, 3, type.c_str(), -1, SQLITE_TRANSIENT);
    const int rc = sqlite3_step(s);
    sqlite3_finalize(s);
    if (rc != SQLITE_DONE) Fail(sqlite3_errmsg(db_));
  }

  void Write(int id, std::int64_t log_time_ns, const std::vector<std::uint8_t>& cdr) override {
    sqlite3_reset(insert_);
    sqlite3_bind_int(insert_, 1, id + 1);
    sqlite3_bind_int64(insert_, 2, log_time_ns);
    sqlite3_bind_blob(insert_, 3, cdr.data(), static_cast<int>(cdr.size()), SQLITE_TRANSIENT);
    if (sqlite3_step(insert_) != SQLITE_DONE) Fail(sqlite3_errmsg(db_));
  }

  void Finish() override { Exec("COMMIT;"); }

 private:
  void Exec(const char* sql) {
    char* message = nullptr;
    if (sqlite3_exec(db_, sql, nullptr, nullptr, &message) != SQLITE_OK) {
      const std::string what = message ? message : "sqlite error";
      sqlite3_free(message);
      Fail(what);
    }
  }

  sqlite3* db_ = nullptr;
  sqlite3_stmt* insert_ = nullptr;
};

}  // namespace

Ros2BagWriter::Ros2BagWriter(std::string folder, Ros2BagWriterOptions options)
    : folder_(std::move(folder)), options_(options) {
  if (fs::exists(folder_)) Fail(folder_ + " exists already");
  fs::create_directories(folder_);
  StartFile();
}

Ros2BagWriter::~Ros2BagWriter() {
  try {
    Close();
  } catch (...) {
  }
}

void Ros2BagWriter::AddTopic(const std::string& topic, const std::string& type) {
  for (const Topic& t : topics_) {
    if (t.name == topic) Fail("topic " + topic + " added twice");
  }
  topics_.push_back(Topic{topic, type, 0});
  file_->AddTopic(static_cast<int>(topics_.size()) - 1, topic, type);
}

void Ros2BagWriter::Write(const std::string& topic, std::int64_t log_time_ns, const std::vector<std::uint8_t>& cdr) {
  const auto it = std::find_if(topics_.begin(), topics_.end(), [&](const Topic& t) { return t.name == topic; });
  if (it == topics_.end()) Fail("Write on topic " + topic + " before AddTopic");
  file_->Write(static_cast<int>(it - topics_.begin()), log_time_ns, cdr);
  ++it->messages;
  FileStats& stats = files_.back();
  if (stats.messages == 0 || log_time_ns < stats.first_ns) stats.first_ns = log_time_ns;
  if (stats.messages == 0 || log_time_ns > stats.last_ns) stats.last_ns = log_time_ns;
  ++stats.messages;
}

void Ros2BagWriter::SplitFile() {
  EndFile();
  StartFile();
}

void Ros2BagWriter::Close() {
  if (closed_) return;
  closed_ = true;
  EndFile();
  WriteMetadata();
}

std::vector<std::string> Ros2BagWriter::files() const {
  std::vector<std::string> out;
  for (const FileStats& f : files_) out.push_back((fs::path(folder_) / f.name).string());
  return out;
}

void Ros2BagWriter::StartFile() {
  const bool mcap = options_.storage == Ros2Storage::kMcap;
  FileStats stats;
  stats.name = fs::path(folder_).filename().string() + "_" + std::to_string(files_.size()) + (mcap ? ".mcap" : ".db3");
  const std::string path = (fs::path(folder_) / stats.name).string();
  files_.push_back(stats);
  if (mcap) {
    file_ = std::make_unique<McapFile>(path, options_, &chunks_);
  } else {
    file_ = std::make_unique<Db3File>(path);
  }
  for (std::size_t i = 0; i < topics_.size(); ++i) file_->AddTopic(static_cast<int>(i), topics_[i].name, topics_[i].type);
}

void Ros2BagWriter::EndFile() {
  file_->Finish();
  file_.reset();
}

void Ros2BagWriter::WriteMetadata() const {
  // rosbag2 (Humble) metadata, version 5.
  std::int64_t first = 0;
  std::int64_t last = 0;
  std::uint64_t count = 0;
  for (const FileStats& f : files_) {
    if (f.messages == 0) continue;
    if (count == 0 || f.first_ns < first) first = f.first_ns;
    if (count == 0 || f.last_ns > last) last = f.last_ns;
    count += f.messages;
  }
  std::ofstream out(fs::path(folder_) / "metadata.yaml");
  out << "rosbag2_bagfile_information:\n"
      << "  version: 5\n"
      << "  storage_identifier: " << (options_.storage == Ros2Storage::kMcap ? "mcap" : "sqlite3") << "\n"
      << "  duration:\n    nanoseconds: " << (last - first) << "\n"
      << "  starting_time:\n    nanoseconds_since_epoch: " << first << "\n"
      << "  message_count: " << count << "\n"
      << "  topics_with_message_count:\n";
  for (const Topic& t : topics_) {
    out << "    - topic_metadata:\n"
        << "        name: " << t.name << "\n"
        << "        type: " << t.type << "\n"
        << "        serialization_format: cdr\n"
        << "        offered_qos_profiles: \"\"\n"
        << "      message_count: " << t.messages << "\n";
  }
  out << "  compression_format: \"\"\n"
      << "  compression_mode: \"\"\n"
      << "  relative_file_paths:\n";
  for (const FileStats& f : files_) out << "    - " << f.name << "\n";
  out << "  files:\n";
  for (const FileStats& f : files_) {
    out << "    - path: " << f.name << "\n"
        << "      starting_time:\n        nanoseconds_since_epoch: " << f.first_ns << "\n"
        << "      duration:\n        nanoseconds: " << (f.last_ns - f.first_ns) << "\n"
        << "      message_count: " << f.messages << "\n";
  }
  out.close();
  if (!out) Fail("cannot write " + folder_ + "/metadata.yaml");
}

}  // namespace ssta::testing
