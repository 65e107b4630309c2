// ROS 1 bags (format 2.0) through Debian's rosbag_storage: it reads the container (chunks, bz2
// and lz4 compression, the connection and chunk indexes); ros_messages.cpp decodes the bytes.

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>

#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <ros/serialization.h>

#include "bag_reader.h"
#include "ssta/core/error.h"

namespace ssta::internal {
namespace {

/// The bag header record's index_pos: where the index that rosbag reads at open starts (0 while
/// the recorder has not closed the bag). -1 when the file does not start as a bag 2.0 does.
std::int64_t IndexPosition(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string magic(13, '\0');
  if (!in.read(&magic[0], 13) || magic != "#ROSBAG V2.0\n") return -1;
  const auto u32 = [&in]() -> std::int64_t {
    unsigned char b[4];
    if (!in.read(reinterpret_cast<char*>(b), 4)) return -1;
    return b[0] | (b[1] << 8) | (b[2] << 16) | (static_cast<std::int64_t>(b[3]) << 24);
  };
  std::int64_t header_left = u32();
  while (header_left > 4) {
    const std::int64_t field_bytes = u32();
    if (field_bytes < 0 || field_bytes > header_left - 4) return -1;
    std::string field(static_cast<std::size_t>(field_bytes), '\0');
    if (!in.read(&field[0], field_bytes)) return -1;
    header_left -= 4 + field_bytes;
    if (field.rfind("index_pos=", 0) == 0 && field.size() == 18) {
      std::uint64_t v = 0;
      for (int i = 7; i >= 0; --i) v = (v << 8) | static_cast<unsigned char>(field[10 + static_cast<std::size_t>(i)]);
      return static_cast<std::int64_t>(v);
    }
  }
  return -1;
}

/// The error for a bag rosbag cannot open: a truncated one is said to be, with the way to
/// recover it.
Error OpenError(const std::string& path, const std::string& rosbag_says) {
  std::error_code ec;
  const auto size = static_cast<std::int64_t>(std::filesystem::file_size(path, ec));
  const std::int64_t index = IndexPosition(path);
  const bool cut = !ec && (index == 0 || index >= size || rosbag_says.find("wanted") != std::string::npos);
  if (!cut) return Error(path + ": not a readable ROS 1 bag (" + rosbag_says + ")");
  const std::string where = index == 0 ? "before the recorder closed it, so it has no index"
                                       : "at byte " + std::to_string(size) + ", before the end of its index" +
                                             (index > 0 ? " (which starts at byte " + std::to_string(index) + ")" : "");
  return Error(path + ": truncated: the file ends " + where + " (rosbag: " + rosbag_says +
               "); `rosbag reindex " + path + "` recovers its complete messages (keeping the original as .orig.bag)");
}

class Ros1Bag final : public BagReader {
 public:
  explicit Ros1Bag(const std::string& path) : path_(path) {
    try {
      bag_.open(path, rosbag::bagmode::Read);
      rosbag::View all(bag_);
      for (const rosbag::ConnectionInfo* c : all.getConnections()) {
        const auto [it, added] = topic_index_.emplace(c->topic, static_cast<int>(connections_.size()));
        if (added) {
          connections_.push_back({c->topic, c->datatype, "ros1"});
        } else if (connections_[static_cast<std::size_t>(it->second)].type != c->datatype) {
          throw Error(path + ": topic " + c->topic + " is recorded with two types, " +
                      connections_[static_cast<std::size_t>(it->second)].type + " and " + c->datatype);
        }
      }
    } catch (const rosbag::BagException& e) {
      throw OpenError(path, e.what());
    }
  }

  const std::string& path() const override { return path_; }
  std::string format() const override { return "ros1"; }
  const std::vector<BagConnection>& connections() const override { return connections_; }

  std::vector<BagMessageRef> List(const std::vector<int>& wanted) const override {
    std::vector<BagMessageRef> out;
    const std::lock_guard<std::mutex> lock(mutex_);
    for (const int c : wanted) {
      const std::vector<BagMessageRef>& one = ListOne(c);
      out.insert(out.end(), one.begin(), one.end());
    }
    std::stable_sort(out.begin(), out.end(), [](const BagMessageRef& a, const BagMessageRef& b) {
      return a.log_time_ns < b.log_time_ns;
    });
    return out;
  }

  std::vector<std::uint8_t> Read(const BagMessageRef& ref) const override {
    const std::lock_guard<std::mutex> lock(mutex_);  // rosbag reads through one shared buffer
    SSTA_CHECK(ref.position < instances_.size(), "a message reference from another reader");
    const rosbag::MessageInstance& m = instances_[ref.position];
    try {
      std::vector<std::uint8_t> bytes(m.size());
      ros::serialization::OStream stream(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
      m.write(stream);
      return bytes;
    } catch (const std::exception& e) {  // rosbag::BagException, ros::serialization's own
      throw Error(path_ + ": message on " + m.getTopic() + " at " + std::to_string(ref.log_time_ns) +
                  " ns: " + e.what());
    }
  }

 private:
  std::string path_;
  rosbag::Bag bag_;
  std::vector<BagConnection> connections_;
  std::map<std::string, int> topic_index_;
  mutable std::mutex mutex_;
  /// One connection's messages, listed once: rosbag's view merges the per-connection indexes in
  /// time order without reading data. Caller holds mutex_.
  const std::vector<BagMessageRef>& ListOne(int c) const {
    const auto cached = listed_.find(c);
    if (cached != listed_.end()) return cached->second;
    const std::string& topic = connections_.at(static_cast<std::size_t>(c)).topic;
    std::vector<BagMessageRef> refs;
    try {
      rosbag::View view(bag_, [&](const rosbag::ConnectionInfo* info) { return info->topic == topic; });
      for (const rosbag::MessageInstance& m : view) {
        BagMessageRef ref;
        ref.log_time_ns = static_cast<std::int64_t>(m.getTime().toNSec());
        ref.connection = c;
        ref.position = instances_.size();
        instances_.push_back(m);
        refs.push_back(ref);
      }
    } catch (const rosbag::BagException& e) {
      throw Error(path_ + ": " + e.what());
    }
    return listed_.emplace(c, std::move(refs)).first->second;
  }

  // rosbag's handles to the listed messages (each once): a reference's position indexes this list.
  mutable std::vector<rosbag::MessageInstance> instances_;
  mutable std::map<int, std::vector<BagMessageRef>> listed_;
};

}  // namespace

std::unique_ptr<BagReader> OpenRos1Bag(const std::string& path) { return std::make_unique<Ros1Bag>(path); }

}  // namespace ssta::internal
