#pragma once

// The options that choose a ROS bag's topics, for every command that takes --sequence.

#include <ostream>

#include <CLI/CLI.hpp>

#include "ssta/io/sequence.h"

namespace ssta::cli {

inline void AddBagTopicOptions(CLI::App* cmd, BagTopics* topics) {
  const std::string group = "ROS bags (--sequence BAG; docs/bags.md)";
  cmd->add_option("--left-topic", topics->left, "left camera: sensor_msgs/Image or CompressedImage (default: the one stereo pair)")
      ->group(group);
  cmd->add_option("--right-topic", topics->right, "right camera (default: the left topic with left -> right)")->group(group);
  cmd->add_option("--imu-topic", topics->imu, "sensor_msgs/Imu topic, or none (default: the only one)")->group(group);
  cmd->add_option("--pose-topic", topics->pose, "nav_msgs/Odometry topic, /tf, or none (default: the only Odometry)")
      ->group(group);
  cmd->add_option("--pose-frame", topics->pose_frame,
                  "body frame: its pose is the vehicle's, the camera mount is read from /tf_static up to it "
                  "(default: the Odometry child frame, else base_link)")
      ->group(group);
  cmd->add_flag("--allow-truncated", topics->allow_truncated,
                "read a truncated bag (cut off by a crash or a copy) up to its last complete message, with a "
                "warning, instead of refusing it")
      ->group(group);
}

/// "warning: ..." for each thing the sequence lacks (a truncated bag read with --allow-truncated).
inline void PrintSequenceWarnings(const Sequence& sequence, std::ostream& out) {
  for (const auto& w : sequence.warnings()) out << "warning: " << w << "\n";
}

}  // namespace ssta::cli
