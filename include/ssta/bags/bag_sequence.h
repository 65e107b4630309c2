#pragma once

// ROS bags (ROS 1 `.bag`, ROS 2 MCAP and sqlite3, rosbag2 folders) as stereo sequences
// (docs/bags.md). Sequence::Open and Sequence::OpenBag (ssta/io/sequence.h) are defined in this
// module (ssta::bags), beside what tells a bag and describes one.

#include <string>

#include "ssta/io/sequence.h"

namespace ssta {

/// True when `path` is a ROS bag: a file that starts "#ROSBAG V2.0", a folder with
/// `metadata.yaml`, a `.mcap` or `.db3` file.
bool IsBagPath(const std::string& path);

/// What DescribeBag finds.
struct BagDescription {
  std::string text;     ///< for a person, one line per item, each ending in a newline
  std::string problem;  ///< why the bag cannot be used as a stereo sequence ("" when it can)
};

/// What a bag holds (topics, types, counts, rates, time span) and what OpenBag would make of it
/// with `topics` (the topics chosen, the calibration, the mounts, the frames paired and skipped
/// with their reasons, the assumptions). A bag that OpenBag refuses, or that pairs no frame, is
/// described with the reason in `problem`. Throws ssta::Error when the bag cannot be opened at all.
BagDescription DescribeBag(const std::string& path, const BagTopics& topics = {});

}  // namespace ssta
