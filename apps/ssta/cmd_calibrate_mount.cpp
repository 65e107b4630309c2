// ssta calibrate-mount: refine cam0's mount rotation (pitch, roll) from the ground planes of a
// sequence and write the corrected sensor.yaml files.

#include <filesystem>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "bag_options.h"
#include "commands.h"
#include "progress.h"
#include "ssta/files/file_util.h"
#include "ssta/pipeline/config.h"
#include "ssta/pipeline/mount_calibration.h"

namespace ssta::cli {
namespace {

struct CalibrateMountArgs {
  std::string sequence, out, out_cam1, out_dir, report, ground_reference;
  BagTopics topics;
  std::vector<std::string> config;
  MountCalibrationOptions options;
  bool quiet = false;
};

/// Where the two sensor.yaml files go: --out-dir DIR gives DIR/cam0/sensor.yaml and
/// DIR/cam1/sensor.yaml (a drop-in for a sequence folder); --out FILE gives FILE for cam0 and
/// --out-cam1, or cam1_sensor.yaml beside FILE, for cam1.
std::pair<std::string, std::string> OutputPaths(const CalibrateMountArgs& a) {
  namespace fs = std::filesystem;
  if (!a.out_dir.empty()) {
    return {(fs::path(a.out_dir) / "cam0" / "sensor.yaml").string(), (fs::path(a.out_dir) / "cam1" / "sensor.yaml").string()};
  }
  const fs::path cam1 = a.out_cam1.empty() ? fs::path(a.out).parent_path() / "cam1_sensor.yaml" : fs::path(a.out_cam1);
  if (fs::path(a.out).lexically_normal() == cam1.lexically_normal()) {
    throw Error("--out: " + a.out + " is also where cam1 would go; give --out-cam1");
  }
  return {a.out, cam1.string()};
}

void Run(const CalibrateMountArgs& a) {
  if (a.out.empty() == a.out_dir.empty()) throw Error("--out: give exactly one of --out FILE and --out-dir DIR");
  if (!a.out_cam1.empty() && a.out.empty()) throw Error("--out-cam1: only with --out");
  const auto [cam0_path, cam1_path] = OutputPaths(a);
  const Sequence sequence = Sequence::Open(a.sequence, a.topics);
  PrintSequenceWarnings(sequence, std::cerr);
  const Config config = LoadLayeredConfig(&sequence, a.config);
  MountCalibrationOptions options = a.options;
  options.refinement = config.refinement;
  if (!a.ground_reference.empty()) options.refinement.ground_reference = ParseGroundReference(a.ground_reference);
  std::string invalid;
  if (!options.IsValid(&invalid)) throw Error("--" + invalid);
  ProgressLine progress("calibrate-mount", !a.quiet);
  const MountCalibration result = CalibrateMount(sequence, config, options,
                                                 [&](int done, int total) { progress.Update(done, total); });
  progress.Finish();
  if (!a.quiet) std::cout << result.BriefReport();
  if (!a.report.empty()) WriteTextAtomically(a.report, result.Json());
  if (!result.refinement.applied()) {
    throw Error(a.sequence + ": mount " + RefinementStatusName(result.refinement.status) + ": " +
                result.refinement.message + "; nothing written");
  }
  for (const auto& path : {cam0_path, cam1_path}) {
    const auto parent = std::filesystem::path(path).parent_path();
    if (!parent.empty()) MakeDirectories(parent.string());
  }
  std::ostringstream note;
  note << std::fixed << std::setprecision(3) << "ssta calibrate-mount: pitch " << result.refinement.pitch_correction_deg
       << " +- " << result.refinement.pitch_sigma_deg << " deg, roll " << result.refinement.roll_correction_deg << " +- "
       << result.refinement.roll_sigma_deg << " deg from " << result.refinement.frames_used << " frames of " << a.sequence;
  SaveCameraCalibration(result.refined.left, cam0_path, note.str() + " (cam0)");
  SaveCameraCalibration(result.refined.right, cam1_path, note.str() + " (cam1, from the rig)");
  if (!a.quiet) std::cout << "wrote " << cam0_path << " and " << cam1_path << "\n";
}

}  // namespace

void RegisterCalibrateMount(CLI::App& app) {
  auto args = std::make_shared<CalibrateMountArgs>();
  CLI::App* cmd = app.add_subcommand(
      "calibrate-mount", "Refine cam0's mount pitch and roll from the ground seen over a sequence (Ceres)");
  cmd->footer(
      "The ground each frame sees where the vehicle later drives is taken as parallel to the plane\n"
      "under the wheels there (from the poses); the mount rotation that makes this true over all\n"
      "frames is estimated, frames weighed by their agreement, with a 1-sigma from the measured\n"
      "scatter. Yaw is not observable from the ground and is kept. Drive a few metres straight on\n"
      "at walking pace. Writes the refined cam0 sensor.yaml and the cam1 one that follows\n"
      "from the rig only when the estimate is determined; when there are too few frames, the result\n"
      "is not better determined than its prior, or the terrain is too rough for the model, it exits\n"
      "with status 2 and writes nothing but --report. See docs/mount_calibration.md.");
  cmd->add_option("--sequence", args->sequence, "sequence: an ASL / EuRoC folder, a KITTI raw drive, or a ROS 1 / ROS 2 bag")->required();
  AddBagTopicOptions(cmd, &args->topics);
  cmd->add_option("--out", args->out, "refined cam0 sensor.yaml to write (cam1 goes beside it as cam1_sensor.yaml)");
  cmd->add_option("--out-cam1", args->out_cam1, "with --out: where the cam1 sensor.yaml goes instead");
  cmd->add_option("--out-dir", args->out_dir, "instead of --out: write DIR/cam0/sensor.yaml and DIR/cam1/sensor.yaml");
  cmd->add_option("--config", args->config, "YAML config; repeatable, later files win");
  cmd->add_option("--max-frames", args->options.frames.max_frames, "use at most N frames (0: all)");
  cmd->add_option("--every", args->options.frames.every, "use every N-th frame");
  cmd->add_option("--ground-reference", args->ground_reference,
                  "path: the ground a later pose's body stands on is parallel to its wheel plane (needs "
                  "poses and a drive over the ground seen; else body); "
                  "body: the ground is parallel to the plane under the wheels (body x-y; a z-up body); "
                  "gravity: the ground is level, its normal is up from the IMU-corrected pose "
                  "(default: refinement.ground_reference in the config, path)")
      ->check(CLI::IsMember({"path", "body", "gravity"}));
  cmd->add_option("--report", args->report, "write the estimate, its uncertainty and the frames as JSON")
      ->check(OutputFile());
  cmd->add_flag("--oracle-disparity", args->options.oracle_disparity,
                "use the sequence's gt/disparity instead of stereo matching (synthetic sequences): the ground "
                "model's error apart from the matcher's");
  cmd->add_flag("--quiet,-q", args->quiet, "no progress and no report on stdout");
  cmd->callback([args] {
    std::string error;
    if (!args->options.IsValid(&error)) throw Error("--" + error);
    Run(*args);
  });
}

}  // namespace ssta::cli
