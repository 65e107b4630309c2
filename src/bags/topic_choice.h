#pragma once

// Private: which topics of a bag make the stereo sequence. The left and right image topics (asked
// for, or the one pair whose names differ in a side word), the CameraInfo beside each, the IMU
// and the pose source (Odometry, or /tf).

#include <map>
#include <string>
#include <vector>

#include "bags/bag_reader.h"
#include "bags/ros_messages.h"
#include "ssta/core/error.h"
#include "ssta/io/sequence.h"

namespace ssta::internal {

/// "sensor_msgs/msg/Image" (ROS 2) and "sensor_msgs/Image" (ROS 1) are the same type.
std::string PlainType(const std::string& type);

/// A bag's connections by topic, with the checks every choice of topic needs.
class Topics {
 public:
  explicit Topics(const BagReader& bag);
  const BagReader& bag() const { return bag_; }
  bool Has(const std::string& topic) const { return index_.count(topic) > 0; }
  int Index(const std::string& topic) const { return index_.at(topic); }
  /// The topic's type without ROS 2's "/msg/" (PlainType).
  std::string Type(const std::string& topic) const;
  RosEncoding Encoding(const std::string& topic) const;
  /// Every topic of `type` (plain), sorted.
  std::vector<std::string> OfType(const std::string& type) const;
  /// Checks that `topic` (given with `option`) exists with one of `types`; throws ssta::Error
  /// naming the bag, the option and the topic.
  void Require(const std::string& topic, const std::vector<std::string>& types, const std::string& option) const;

 private:
  const BagReader& bag_;
  std::map<std::string, int> index_;
};

/// The topics a bag sequence is read from, after the automatic choice.
struct ChosenTopics {
  std::string left, right, left_info, right_info, imu, pose;
  std::string pose_frame;
  /// `pose` is "/tf" because the bag has no Odometry: used when /tf moves the body frame.
  bool pose_from_tf_if_moving = false;
};

/// The topics `asked` names, the others found by type and name (docs/bags.md). Throws
/// ssta::Error naming the bag and the option that resolves an ambiguity or a missing topic.
ChosenTopics ChooseTopics(const BagReader& bag, const BagTopics& asked);

/// The first message on `topic`, decoded with `decode`. Throws ssta::Error when it has none.
template <typename Decode>
auto FirstMessage(const Topics& topics, const std::string& topic, Decode decode) {
  const BagReader& bag = topics.bag();
  const auto refs = bag.List({topics.Index(topic)});
  if (refs.empty()) throw Error(bag.path() + ": " + topic + " holds no messages");
  return decode(bag.Read(refs.front()), topics.Encoding(topic), bag.path() + ": " + topic);
}

/// A table of the bag's topics: type, message count and rate (for `ssta inspect`).
std::string DescribeTopics(const BagReader& bag);

}  // namespace ssta::internal
