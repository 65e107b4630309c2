// ssta build-map: fuse a sequence's classified frames into a persistent OctoMap map.

#include <csignal>
#include <filesystem>
#include <iostream>

#include "bag_options.h"
#include "commands.h"
#include "map_arguments.h"
#include "progress.h"
#include "ssta/files/file_util.h"
#include "ssta/pictures/map_picture.h"
#include "ssta/pipeline/config.h"
#include "ssta/pipeline/map_builder.h"

namespace ssta::cli {
namespace {

std::atomic<bool> g_stop{false};
extern "C" void RequestStop(int) { g_stop = true; }

struct BuildMapArgs {
  std::string sequence, json, picture;
  BagTopics topics;
  std::vector<std::string> config;
  BuildMapOptions options;
  bool quiet = false;
  bool sequential = false;
  bool refine = false;  ///< sets refinement.online
};

void Run(const BuildMapArgs& a) {
  const Sequence sequence = Sequence::Open(a.sequence, a.topics);
  Config config = LoadLayeredConfig(&sequence, a.config);
  if (a.refine) config.refinement.online = true;
  // SIGINT / SIGTERM stop after the current frame; the map is saved before exiting.
  std::signal(SIGINT, RequestStop);
  std::signal(SIGTERM, RequestStop);
  ProgressLine progress("build-map", !a.quiet);
  const BuildMapSummary summary = BuildMap(sequence, SequenceNameOf(a.sequence), config, a.options,
                                           [&](int done, int total) { progress.Update(done, total); }, &g_stop);
  progress.Finish();
  if (summary.Fused() && !a.picture.empty()) {
    MapPictureOptions picture;
    picture.title = std::filesystem::path(a.options.map_path).filename().string();
    ExportPicture(TraversabilityMap::Load(a.options.map_path), a.picture, picture);
  }
  if (!a.quiet) {
    // Said once the file is written: a run that fuses nothing leaves it as it was.
    const bool replaced = !a.options.resume && summary.map_existed && summary.frames_used > 0;
    std::cout << summary.BriefReport() << "map: " << a.options.map_path
              << (replaced ? " (replaced the earlier file; --resume continues a map)" : "") << "\n";
    if (summary.Fused() && !a.picture.empty()) std::cout << "picture: " << a.picture << "\n";
  }
  if (!a.json.empty()) WriteTextAtomically(a.json, summary.Json());
  RequireFused(summary, a.sequence, a.options.map_path);
  if (summary.interrupted) throw Error("interrupted; the map holds the frames fused so far (continue with --resume)");
}

}  // namespace

void RegisterBuildMap(CLI::App& app) {
  auto args = std::make_shared<BuildMapArgs>();
  CLI::App* cmd = app.add_subcommand("build-map", "Fuse a sequence's classified frames into a 3D traversability map (OctoMap)");
  cmd->add_option("--sequence", args->sequence, "sequence: an ASL / EuRoC folder, a KITTI raw drive, or a ROS 1 / ROS 2 bag")->required();
  AddBagTopicOptions(cmd, &args->topics);
  cmd->add_option("--map", args->options.map_path, "map file to write (.ot)")->required()->check(OutputFile());
  cmd->add_option("--config", args->config, "YAML config; repeatable, later files win");
  cmd->add_flag("--resume", args->options.resume,
                "continue the existing map: with another sequence, or finish an interrupted run of this one "
                "(frames already in the map are not fused again)");
  cmd->add_flag("--allow-overlap", args->options.allow_overlap,
                "with --resume: fuse the sequence even when the map already holds frames of it (same time and "
                "image, e.g. the same recording from a bag and from a folder); their evidence then counts twice");
  cmd->add_flag("--static", args->options.static_platform,
                "the platform stands still and the sequence has no poses: every frame at the origin, levelled by gravity");
  cmd->add_option("--world-frame", args->options.world_frame,
                  "name of the world frame the poses are in, recorded in the map: maps merge only when they "
                  "name the same frame (docs/fleet.md)");
  cmd->add_option("--max-frames", args->options.frames.max_frames, "fuse at most N frames (0: all)");
  cmd->add_option("--every", args->options.frames.every, "use every N-th frame");
  cmd->add_option("--json", args->json, "write the run's summary as JSON to this file")->check(OutputFile());
  cmd->add_option("--picture", args->picture,
                  "write a picture of the map for people to this PNG (as export --format picture: classes, relief, "
                  "sensor path, legend, scale)")
      ->check(OutputFile());
  cmd->add_flag("--refine", args->refine,
                "refine cam0's mount pitch and roll online from the ground (sets refinement.online; "
                "docs/mount_calibration.md)");
  cmd->add_flag("--oracle-disparity", args->options.oracles.disparity,
                "use the sequence's gt/disparity instead of stereo matching (synthetic sequences)");
  cmd->add_flag("--oracle-labels", args->options.oracles.labels,
                "fuse the sequence's gt/labels where they have a verdict instead of the frame's classes "
                "(synthetic sequences; with --oracle-disparity: the fusion alone)");
  cmd->add_flag("--strict", args->options.frames.strict, "any frame that cannot be used is an error, not a skip with a reason");
  cmd->add_flag("--sequential", args->sequential,
                "classify and fuse one frame after the other (default: fuse each frame on a second thread while the "
                "next is classified; the same map)");
  cmd->add_flag("--quiet,-q", args->quiet, "no progress and no report");
  cmd->callback([args] {
    args->options.pipelined = !args->sequential;
    std::string error;
    if (!args->options.IsValid(&error)) throw Error("--" + error);
    Run(*args);
  });
}

}  // namespace ssta::cli
