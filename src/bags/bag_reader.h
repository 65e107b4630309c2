#pragma once

// Private: ROS bags as the sequence reader sees them. A bag is a set of connections (topic,
// message type, serialization) and messages found by reference; the readers know containers
// (ROS 1 .bag, ROS 2 MCAP and sqlite3), ros_messages.h knows the messages inside them.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace ssta::internal {

/// One topic of a bag with its message type and how its messages are serialized.
struct BagConnection {
  std::string topic;     ///< "/stereo/left/image_raw"
  std::string type;      ///< as recorded: "sensor_msgs/Image" (ROS 1), "sensor_msgs/msg/Image" (ROS 2)
  std::string encoding;  ///< "ros1" or "cdr"
};

/// Where one message sits in its bag. The fields past `connection` mean something only to the
/// reader that made the reference.
struct BagMessageRef {
  std::int64_t log_time_ns = 0;  ///< when the recorder received it
  int connection = 0;            ///< index into BagReader::connections()
  std::uint64_t position = 0;    ///< reader's own: a chunk's file offset, a row id, ...
  std::uint64_t offset = 0;      ///< reader's own: the message's offset inside that chunk, ...
};

/// A bag opened for reading. Safe for concurrent Read() calls from several threads.
class BagReader {
 public:
  virtual ~BagReader() = default;

  /// The file or folder the bag was opened from, for messages.
  virtual const std::string& path() const = 0;
  /// "ros1", "ros2 mcap" or "ros2 sqlite3".
  virtual std::string format() const = 0;
  /// Every connection (topic) of the bag. A topic recorded from several publishers with the same
  /// type appears once.
  virtual const std::vector<BagConnection>& connections() const = 0;
  /// References to every message on the given connections (indices into connections()),
  /// ordered by log time (ties in file order). Reads the bag's index where it has one, and never
  /// keeps message data. Throws ssta::Error naming the file on a corrupt or truncated bag.
  virtual std::vector<BagMessageRef> List(const std::vector<int>& connections) const = 0;
  /// The serialized bytes of one message: ROS 1 serialization, or CDR with its 4-byte
  /// encapsulation header. Throws ssta::Error naming the file on a corrupt or truncated record.
  virtual std::vector<std::uint8_t> Read(const BagMessageRef& ref) const = 0;
  /// Why the bag is incomplete, "" when it is whole: one sentence starting "PATH: truncated: "
  /// that says where it ends and when its last complete message was logged (TruncationText).
  /// List() and Read() then give the complete messages; the sequence reader refuses such a bag
  /// unless asked to read what is there (BagTopics::allow_truncated).
  virtual std::string Truncation() const { return ""; }
};

/// "PATH: truncated: WHAT; the last complete message was logged at S.NNNNNNNNN s" (`last_ns`
/// the log time [ns]; "holds no complete message" when `last_ns` < 0).
std::string TruncationText(const std::string& path, const std::string& what, std::int64_t last_ns);

/// Opens a ROS 1 bag (format 2.0; bz2 and lz4 chunks) with Debian's rosbag library.
/// Throws ssta::Error naming the file.
std::unique_ptr<BagReader> OpenRos1Bag(const std::string& path);

/// Opens a ROS 2 bag: a rosbag2 folder with `metadata.yaml` (storage_identifier mcap or sqlite3,
/// the files it lists under relative_file_paths, in order), or a single `.mcap` or `.db3` file.
/// Throws ssta::Error naming the file (and the record or key) on anything it cannot read.
std::unique_ptr<BagReader> OpenRos2Bag(const std::string& path);

/// OpenRos1Bag or OpenRos2Bag by what `path` is.
std::unique_ptr<BagReader> OpenBag(const std::string& path);

}  // namespace ssta::internal
