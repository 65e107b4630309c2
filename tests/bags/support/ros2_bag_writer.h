#pragma once

// Test support: writes rosbag2 bags (a folder with metadata.yaml and its storage files, MCAP or
// sqlite3) from messages the test chooses, for the bag readers' tests and the integration tests.
// Link the CMake target ssta_test_ros2_writer; the messages' CDR bytes come from
// ros_cdr_encoder.h (same target).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace ssta::testing {

enum class Ros2Storage { kMcap, kSqlite3 };
enum class McapCompression { kNone, kZstd, kLz4 };

struct Ros2BagWriterOptions {
  Ros2Storage storage = Ros2Storage::kMcap;
  /// MCAP: how each chunk's records are compressed.
  McapCompression compression = McapCompression::kNone;
  /// MCAP: write the summary section (Schemas, Channels, Statistics, Chunk Indexes) and the
  /// summary offsets. Without it the file looks like a recording whose recorder did not finish
  /// its summary; the Footer and the closing magic are written either way.
  bool summary = true;
  /// MCAP: a chunk is closed once its uncompressed records reach this many bytes [bytes].
  std::size_t chunk_bytes = 4096;
  /// MCAP: write each chunk's CRC-32 (0, "not computed", when false).
  bool chunk_crc = true;
};

/// Where a chunk landed in an MCAP file, for tests that cut or corrupt the file.
struct McapChunkSpan {
  std::string file;              ///< the storage file's path
  std::uint64_t offset = 0;      ///< of the Chunk record's opcode [bytes]
  std::uint64_t length = 0;      ///< of the whole record, opcode and length included [bytes]
  std::uint64_t records_offset = 0;  ///< of its (compressed) records field [bytes]
  std::uint64_t records_size = 0;    ///< of the (compressed) records field [bytes]
  std::size_t messages = 0;
  std::int64_t last_log_time_ns = 0;  ///< the latest log time of its messages [ns]
};

/// Writes one rosbag2 bag. Topics are registered before their first message; every storage file
/// repeats all topics known when it starts, as rosbag2 does. Not thread-safe.
class Ros2BagWriter {
 public:
  /// Creates `folder` (which must not exist yet) and its first storage file,
  /// `<folder name>_0.mcap` or `_0.db3`.
  explicit Ros2BagWriter(std::string folder, Ros2BagWriterOptions options = {});
  /// Closes the bag if Close was not called (errors are then lost: call Close in tests).
  ~Ros2BagWriter();
  Ros2BagWriter(const Ros2BagWriter&) = delete;
  Ros2BagWriter& operator=(const Ros2BagWriter&) = delete;

  /// Registers a topic with its type ("sensor_msgs/msg/Imu"), serialization "cdr".
  void AddTopic(const std::string& topic, const std::string& type);
  /// Appends one message (CDR bytes with their encapsulation header) to the current file.
  void Write(const std::string& topic, std::int64_t log_time_ns, const std::vector<std::uint8_t>& cdr);
  /// Ends the current storage file and starts the next one (rosbag2's split by size).
  void SplitFile();
  /// Ends the last file and writes metadata.yaml. Throws std::runtime_error on a write error.
  void Close();

  const std::string& folder() const { return folder_; }
  /// The storage files so far, full paths, in order.
  std::vector<std::string> files() const;
  /// MCAP: every chunk written so far, in file order.
  const std::vector<McapChunkSpan>& chunks() const { return chunks_; }

  class StorageFile;  // one .mcap or .db3 being written

 private:
  struct Topic {
    std::string name;
    std::string type;
    std::uint64_t messages = 0;
  };
  struct FileStats {
    std::string name;  ///< relative to the folder
    std::int64_t first_ns = 0;
    std::int64_t last_ns = 0;
    std::uint64_t messages = 0;
  };
  void StartFile();
  void EndFile();
  void WriteMetadata() const;

  std::string folder_;
  Ros2BagWriterOptions options_;
  std::vector<Topic> topics_;
  std::vector<FileStats> files_;
  std::vector<McapChunkSpan> chunks_;
  std::unique_ptr<StorageFile> file_;
  bool closed_ = false;
};

}  // namespace ssta::testing
