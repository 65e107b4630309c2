// ssta inspect: what a recording holds and what SSTA would read from it, before a long run.

#include <iostream>

#include "bag_options.h"
#include "commands.h"
#include "ssta/bags/bag_sequence.h"

namespace ssta::cli {
namespace {

struct InspectArgs {
  std::string sequence;
  BagTopics topics;
};

void DescribeFolder(const Sequence& s) {
  const auto& c = s.calibration();
  std::cout << s.root() << ": " << s.format() << " sequence\n"
            << "  camera: " << c.left.width << "x" << c.left.height << " px, f " << c.left.fu << " px, baseline "
            << c.LeftTRight().translation().norm() << " m, " << (c.IsRectified() ? "rectified" : "raw (rectified on read)")
            << "\n"
            << "  frames: " << s.frames().size() << " paired, " << s.skipped().size() << " skipped";
  if (!s.frames().empty()) {
    std::cout << ", " << 1e-9 * static_cast<double>(s.frames().back().timestamp_ns - s.frames().front().timestamp_ns)
              << " s";
  }
  std::cout << "\n  imu: " << (s.imu().empty() ? "none" : std::to_string(s.imu().size()) + " samples (" + s.imu_path() + ")")
            << "\n  poses: "
            << (s.poses().empty() ? "none" : std::to_string(s.poses().size()) + " (" + s.pose_path() + ")") << "\n";
  std::cout << DescribeSkipped(s.skipped());
  if (s.vehicle_config()) std::cout << "  vehicle config: " << *s.vehicle_config() << "\n";
}

}  // namespace

void RegisterInspect(CLI::App& app) {
  auto args = std::make_shared<InspectArgs>();
  CLI::App* cmd = app.add_subcommand(
      "inspect",
      "Show what a recording holds (a bag's topics, types, counts and rates) and what SSTA reads from it; exit "
      "status 2 when it cannot be used");
  cmd->add_option("--sequence", args->sequence, "a ROS 1 / ROS 2 bag, an ASL / EuRoC folder or a KITTI raw drive")->required();
  AddBagTopicOptions(cmd, &args->topics);
  // Exit status 0: the recording can be used as it is; 2: it cannot, with the reason last.
  cmd->callback([args] {
    if (IsBagPath(args->sequence)) {
      const BagDescription d = DescribeBag(args->sequence, args->topics);
      std::cout << d.text << std::flush;
      if (!d.problem.empty()) throw Error(d.problem);
    } else {
      const Sequence s = Sequence::Open(args->sequence, args->topics);
      DescribeFolder(s);
      std::cout << std::flush;
      if (s.frames().empty()) throw Error(s.root() + ": no left and right images pair up: no frame to use");
    }
  });
}

}  // namespace ssta::cli
