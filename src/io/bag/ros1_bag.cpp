// ROS 1 bags (format 2.0) through Debian's rosbag_storage: it reads the container (chunks, bz2
// and lz4 compression, the connection and chunk indexes); ros_messages.cpp decodes the bytes.

#include <algorithm>
#include <map>
#include <mutex>

#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <ros/serialization.h>

#include "bag_reader.h"
#include "ssta/core/error.h"

namespace ssta::internal {
namespace {

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
      throw Error(path + ": not a readable ROS 1 bag (" + e.what() + ")");
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
