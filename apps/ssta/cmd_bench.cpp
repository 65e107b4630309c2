// `ssta bench`: times the per-frame pipeline (and the map update) stage by stage on a
// recorded sequence or on frames rendered for the run.

#include <filesystem>
#include <iostream>
#include <memory>
#include <random>
#include <string>

#include "bag_options.h"
#include "commands.h"
#include "ssta/core/error.h"
#include "ssta/files/file_util.h"
#include "ssta/bench/pipeline_bench.h"
#include "ssta/pipeline/config.h"
#include "ssta/synth/sequence_synthesizer.h"

namespace ssta::cli {
namespace {

struct BenchArgs {
  std::string sequence, json, keep_rendered;
  BagTopics topics;
  std::vector<std::string> config;
  int frames = 30;
  bool refine = false;  ///< sets refinement.online
  PipelineBenchOptions options;
  synth::SynthOptions synth;
};

/// A folder for the rendered frames, removed at the end unless the user asked to keep it.
class RenderFolder {
 public:
  explicit RenderFolder(const std::string& keep) : keep_(!keep.empty()) {
    if (keep_) {
      path_ = keep;
    } else {
      std::random_device rd;
      path_ = (std::filesystem::temp_directory_path() / ("ssta_bench_" + std::to_string(rd()))).string();
    }
  }
  ~RenderFolder() {
    std::error_code ec;
    if (!keep_) std::filesystem::remove_all(path_, ec);
  }
  RenderFolder(const RenderFolder&) = delete;
  RenderFolder& operator=(const RenderFolder&) = delete;
  const std::string& path() const { return path_; }

 private:
  bool keep_;
  std::string path_;
};

void Run(BenchArgs& a) {
  if (a.frames < 1) throw Error("--frames: must be at least 1");
  a.options.max_frames = a.frames;
  std::string error;
  if (!a.options.IsValid(&error)) throw Error("--" + error);
  std::unique_ptr<RenderFolder> rendered;
  std::string source;
  if (a.sequence.empty()) {
    rendered = std::make_unique<RenderFolder>(a.keep_rendered);
    a.synth.frames = a.frames + a.options.warmup_frames;
    if (!a.config.empty()) a.synth.vehicle = LoadLayeredConfig(nullptr, a.config).vehicle;
    std::cerr << "ssta bench: rendering " << a.synth.frames << " frames of the " << a.synth.scene << " scene ("
              << a.synth.rig.width << "x" << a.synth.rig.height << ")...\n";
    synth::WriteSyntheticSequence(a.synth, rendered->path());
    a.sequence = rendered->path();
    source = "synthetic " + a.synth.scene;
  }
  const Sequence sequence = Sequence::Open(a.sequence, a.topics);
  PrintSequenceWarnings(sequence, std::cerr);
  Config config = LoadLayeredConfig(&sequence, a.config);
  if (a.refine) config.refinement.online = true;
  BenchReport report = RunPipelineBench(sequence, config, a.options);
  if (!source.empty()) report.source = source;
  std::cout << report.Table();
  if (!a.json.empty()) WriteTextAtomically(a.json, report.Json());
}

}  // namespace

void RegisterBench(CLI::App& app) {
  auto args = std::make_shared<BenchArgs>();
  CLI::App* cmd =
      app.add_subcommand("bench", "Time the per-frame pipeline and the map update, stage by stage and as a whole run");
  cmd->footer(
      "Reports per stage (image read and decoding included) median and p90 wall ms, CPU ms and\n"
      "frames/s, then the frames/s of a whole run as build-map does it (images read, classified,\n"
      "fused into a map on a second thread), and peak memory, on a sequence, or on\n"
      "frames rendered for the run (default: the yard scene at\n"
      "640x480; KITTI size: --width 1242 --height 375 --focal 718.856 --baseline 0.537\n"
      "--camera-height 1.65 --camera-pitch-deg 0 --config config/sensors/kitti.yaml).\n"
      "The first --warmup frames are run but not counted; the rendering options are ignored with\n"
      "--sequence. Speed only: use `ssta eval` for accuracy. See docs/performance.md.");
  cmd->add_option("--sequence", args->sequence, "sequence to run on: a folder or a ROS bag (default: render frames)");
  AddBagTopicOptions(cmd, &args->topics);
  cmd->add_option("--frames", args->frames, "frames to measure (after the warm-up)")->capture_default_str();
  cmd->add_option("--warmup", args->options.warmup_frames, "frames run first and not counted")
      ->capture_default_str();
  cmd->add_flag("--map", args->options.with_map,
                "also time the map update per frame in the stage rows (the whole run always fuses)");
  cmd->add_flag("--refine", args->refine,
                "also time the online mount refinement per frame (sets refinement.online, as build-map --refine)");
  cmd->add_option("--config", args->config, "YAML config; repeatable, later files win");
  cmd->add_option("--json", args->json, "also write the report as JSON to this file")->check(OutputFile());
  cmd->add_option("--scene", args->synth.scene, "scene to render: yard | hills | dropoff | forest | ramp")
      ->capture_default_str();
  cmd->add_option("--seed", args->synth.seed, "seed of the rendered scene")->capture_default_str();
  cmd->add_option("--width", args->synth.rig.width, "rendered image width [px]")->capture_default_str();
  cmd->add_option("--height", args->synth.rig.height, "rendered image height [px]")->capture_default_str();
  cmd->add_option("--focal", args->synth.rig.focal_px, "rendered focal length [px]")->capture_default_str();
  cmd->add_option("--baseline", args->synth.rig.baseline_m, "rendered stereo baseline [m]")->capture_default_str();
  cmd->add_option("--camera-height", args->synth.rig.camera_height_m, "rendered cam0 height [m]")
      ->capture_default_str();
  cmd->add_option("--camera-pitch-deg", args->synth.rig.pitch_down_deg, "rendered rig pitch down [deg]")
      ->capture_default_str();
  cmd->add_option("--keep-rendered", args->keep_rendered, "write the rendered sequence here and keep it");
  cmd->callback([args] { Run(*args); });
}

}  // namespace ssta::cli
