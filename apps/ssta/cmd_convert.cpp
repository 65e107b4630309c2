// ssta convert: a ROS bag (or any sequence SSTA reads) written out in the ASL folder layout.

#include <iostream>

#include "bag_options.h"
#include "commands.h"
#include "progress.h"

namespace ssta::cli {
namespace {

struct ConvertArgs {
  std::string sequence, out;
  BagTopics topics;
  bool quiet = false;
};

}  // namespace

void RegisterConvert(CLI::App& app) {
  auto args = std::make_shared<ConvertArgs>();
  CLI::App* cmd = app.add_subcommand("convert", "Write a ROS bag as an ASL sequence folder (rectified grey images, "
                                                "sensor.yaml, IMU, poses), for tools that want folders");
  cmd->add_option("--sequence", args->sequence, "a ROS 1 / ROS 2 bag (or any sequence SSTA reads)")->required();
  AddBagTopicOptions(cmd, &args->topics);
  cmd->add_option("--out", args->out, "folder to write the ASL sequence into (new or empty)")->required()->check(OutputFolder());
  cmd->add_flag("--quiet,-q", args->quiet, "no progress and no report");
  cmd->callback([args] {
    const Sequence sequence = Sequence::Open(args->sequence, args->topics);
    ProgressLine progress("convert", !args->quiet);
    WriteAslSequence(sequence, args->out, [&](int done, int total) { progress.Update(done, total); });
    progress.Finish();
    if (!args->quiet) {
      std::cout << args->out << ": " << sequence.frames().size() << " frames, " << sequence.imu().size()
                << " IMU samples, " << sequence.poses().size() << " poses";
      if (!sequence.skipped().empty()) std::cout << " (" << sequence.skipped().size() << " frames skipped)";
      std::cout << "\n";
      for (const auto& note : sequence.notes()) std::cout << "note: " << note << "\n";
      PrintSequenceWarnings(sequence, std::cout);
    }
  });
}

}  // namespace ssta::cli
