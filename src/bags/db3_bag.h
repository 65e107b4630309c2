#pragma once

// Private: one rosbag2 sqlite3 file (.db3) as a BagReader.

#include <memory>
#include <string>

#include "bags/bag_reader.h"

namespace ssta::internal {

/// Opens a rosbag2 `.db3` file read-only: its `topics(id, name, type, serialization_format, ...)`
/// are the connections (the serialization format, "cdr", is the encoding), its
/// `messages(id, topic_id, timestamp, data)` the messages; a reference's `position` is the row id.
/// format() is "ros2 sqlite3". Throws ssta::Error naming the file: missing, not an sqlite
/// database, or a database without rosbag2's tables. One sqlite connection behind a mutex: safe
/// for concurrent List and Read.
std::unique_ptr<BagReader> OpenDb3File(const std::string& path);

}  // namespace ssta::internal
