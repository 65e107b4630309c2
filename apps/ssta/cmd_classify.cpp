// ssta classify: per-pixel traversability classes for every frame of a sequence, or one pair.

#include <filesystem>
#include <iostream>

#include "bag_options.h"
#include "commands.h"
#include "progress.h"
#include "ssta/io/image_io.h"
#include "ssta/pipeline/config.h"
#include "ssta/pipeline/frame_report.h"
#include "ssta/pipeline/sequence_classifier.h"

namespace ssta::cli {
namespace {

struct ClassifyArgs {
  std::string sequence, left, right, calib0, calib1;
  BagTopics topics;
  std::vector<std::string> config;
  std::vector<double> up;
  ClassifyOptions options;
  bool quiet = false;
};

void RunSequence(const ClassifyArgs& a) {
  const Sequence sequence = Sequence::Open(a.sequence, a.topics);
  PrintSequenceWarnings(sequence, std::cerr);
  const Config config = LoadLayeredConfig(&sequence, a.config);
  ProgressLine progress("classify", !a.quiet);
  const ClassifySummary summary = ClassifySequence(
      sequence, config, a.options, [&](int done, int total) { progress.Update(done, total); });
  progress.Finish();
  if (!a.quiet) {
    std::cout << summary.BriefReport();
    std::cout << "outputs: " << a.options.out_dir << "/{labels,overlay,frames}/<timestamp>.{png,json}, "
              << a.options.out_dir << "/summary.json, " << a.options.out_dir << "/config.yaml\n";
  }
  if (summary.frames_classified == 0) throw Error(a.sequence + ": no frame could be classified");
}

void RunPair(const ClassifyArgs& a) {
  if (a.left.empty() || a.right.empty() || a.calib0.empty() || a.calib1.empty()) {
    throw Error("classify needs --sequence SEQ, or --left, --right, --calib0 and --calib1 for one pair");
  }
  const StereoCalibration calibration = LoadStereoCalibration(a.calib0, a.calib1);
  const Config config = LoadLayeredConfig(nullptr, a.config);
  FramePipeline pipeline(calibration, config);
  Eigen::Vector3d up = pipeline.UpInCamera(Eigen::Vector3d::UnitZ());
  if (!a.up.empty()) {
    up = Eigen::Vector3d(a.up[0], a.up[1], a.up[2]);
    if (!up.allFinite() || up.norm() < 1e-9) throw Error("--up: must be a finite, non-zero vector");
  }
  const FrameResult result = pipeline.Process(ReadGreyImage(a.left), ReadGreyImage(a.right), up.normalized());
  const std::string name = std::filesystem::path(a.left).stem().string();
  WriteRunConfig(config, a.options.out_dir);  // as for a sequence
  FrameOutputExtras extras;
  extras.disparity = a.options.write_disparity;
  extras.explain = a.options.write_explain;
  WriteFrameOutputs(result, a.options.out_dir, name, extras);
  if (!a.quiet) {
    const auto& q = result.analysis.quality;
    std::cout << "quality check: " << (q.passed ? "passed" : "failed: " + q.reason) << "\n"
              << "segments: " << result.num_segments << ", total " << result.timings.total_ms << " ms\n"
              << "outputs: " << a.options.out_dir << "/{labels,overlay,frames}/" << name << ".{png,json}, "
              << a.options.out_dir << "/config.yaml\n";
  }
}

}  // namespace

void RegisterClassify(CLI::App& app) {
  auto args = std::make_shared<ClassifyArgs>();
  CLI::App* cmd = app.add_subcommand(
      "classify", "Classify every stereo frame of a sequence (or one pair) into the five SSTA classes");
  CLI::Option* sequence = cmd->add_option("--sequence", args->sequence, "sequence: an ASL / EuRoC folder, a KITTI raw drive, or a ROS 1 / ROS 2 bag");
  AddBagTopicOptions(cmd, &args->topics);
  // The single pair's options and the sequence exclude each other: one of them would be ignored.
  for (CLI::Option* pair_option :
       {cmd->add_option("--left", args->left, "single-pair mode: left image"),
        cmd->add_option("--right", args->right, "single-pair mode: right image"),
        cmd->add_option("--calib0", args->calib0, "single-pair mode: cam0 sensor.yaml"),
        cmd->add_option("--calib1", args->calib1, "single-pair mode: cam1 sensor.yaml"),
        cmd->add_option("--up", args->up, "single-pair mode: up direction in cam0 (x right, y down, z forward); "
                                          "default: a level body through cam0's T_BS")
            ->expected(3)
            ->delimiter(',')}) {
    pair_option->excludes(sequence);
  }
  cmd->add_option("--out", args->options.out_dir, "output folder")->required()->check(OutputFolder());
  cmd->add_option("--config", args->config, "YAML config (see config/default.yaml); repeatable, later files win; overrides the sequence's vehicle.yaml");
  cmd->add_option("--max-frames", args->options.frames.max_frames, "classify at most N frames (0: all)");
  cmd->add_option("--every", args->options.frames.every, "use every N-th frame");
  cmd->add_flag("--disparity", args->options.write_disparity, "also write disparity/<ts>.png (16 bit, disparity * 256, 0 = none: KITTI's and gt/'s convention) and disparity_colour/<ts>.png");
  cmd->add_flag("--explain", args->options.write_explain,
                "also write explain/<ts>.png (the id of the rule that set each pixel's class, docs/interfaces.md) and "
                "explain_colour/<ts>.png (the rules in colour, with a legend)");
  cmd->add_flag("--oracle-disparity", args->options.oracle_disparity,
                "use the sequence's gt/disparity instead of stereo matching (synthetic sequences)");
  cmd->add_flag("--strict", args->options.frames.strict, "any frame that cannot be used is an error, not a skip with a reason");
  cmd->add_flag("--quiet,-q", args->quiet, "no progress and no report");
  cmd->callback([args, cmd] {
    std::string error;
    if (!args->options.IsValid(&error)) throw Error("--" + error);
    if (!args->sequence.empty()) {
      RunSequence(*args);
    } else {
      for (const char* option : {"--max-frames", "--every", "--oracle-disparity", "--strict"}) {
        if (cmd->count(option) > 0) throw Error(std::string(option) + ": only with --sequence");
      }
      RunPair(*args);
    }
  });
}

}  // namespace ssta::cli
