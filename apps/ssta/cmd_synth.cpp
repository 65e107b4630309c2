// `ssta synth`: renders a synthetic stereo sequence with exact ground truth.

#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "commands.h"
#include "progress.h"
#include "ssta/core/error.h"
#include "ssta/pipeline/config.h"
#include "ssta/synth/sequence_synthesizer.h"

namespace ssta::cli {
namespace {

/// `--drop-frames`: a fraction in [0, 1) ("0.1") or a comma-separated list of frame indices
/// ("3,7,12"). A single whole number counts as a list of one index.
void ParseDropFrames(const std::string& text, synth::FaultOptions* faults) {
  if (text.empty()) return;
  const bool is_list = text.find(',') != std::string::npos || text.find('.') == std::string::npos;
  std::stringstream in(text);
  std::string item;
  try {
    if (!is_list) {
      std::size_t used = 0;
      faults->drop_frame_fraction = std::stod(text, &used);
      if (used != text.size()) throw std::invalid_argument(text);
      return;
    }
    while (std::getline(in, item, ',')) {
      std::size_t used = 0;
      faults->drop_frame_indices.push_back(std::stoi(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    }
  } catch (const std::exception&) {
    throw Error("--drop-frames: expected a fraction like 0.1 or frame indices like 3,7,12, got '" +
                text + "'");
  }
}

/// `--add-box X,Y,LENGTH,WIDTH,HEIGHT[,YAW_DEG]`: one box on the scene's ground.
synth::AddedBox ParseBox(const std::string& text) {
  std::vector<double> v;
  std::stringstream in(text);
  std::string item;
  try {
    while (std::getline(in, item, ',')) {
      std::size_t used = 0;
      v.push_back(std::stod(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    }
  } catch (const std::exception&) {
    v.clear();
  }
  if (v.size() != 5 && v.size() != 6) {
    throw Error("--add-box: expected X,Y,LENGTH,WIDTH,HEIGHT[,YAW_DEG] in metres and degrees, got '" + text + "'");
  }
  synth::AddedBox box;
  box.x = v[0];
  box.y = v[1];
  box.length_m = v[2];
  box.width_m = v[3];
  box.height_m = v[4];
  if (v.size() == 6) box.yaw_deg = v[5];
  return box;
}

/// SynthOptions::IsValid names its keys ("rig.width: ..."); on the command line they are the
/// options that set them ("--width: ..."). Keys no option sets (vehicle.*: --config) stay.
std::string NameTheOption(const std::string& error) {
  static const std::pair<const char*, const char*> kFlags[] = {
      {"scene", "--scene"}, {"frames", "--frames"}, {"ramp_slope_deg", "--ramp-slope-deg"},
      {"grid_resolution_m", "--grid-resolution"}, {"rig.width", "--width"}, {"rig.height", "--height"},
      {"rig.focal_px", "--focal"}, {"rig.baseline_m", "--baseline"}, {"rig.camera_height_m", "--camera-height"},
      {"rig.pitch_down_deg", "--camera-pitch-deg"}, {"rig.rate_hz", "--rate"}, {"motion.speed_mps", "--speed"},
      {"motion.weave_amplitude_m", "--weave"}, {"motion.weave_period_s", "--weave-period"},
      {"motion.imu_rate_hz", "--imu-rate"}, {"render.max_label_range_m", "--max-label-range"},
      {"render.boundary_band_px", "--boundary-band"}, {"render.supersample", "--supersample"},
      {"render.sensor_noise_grey", "--noise"}, {"render.threads", "--threads"},
      {"faults.mount_pitch_error_deg", "--mount-pitch-error-deg"},
      {"faults.mount_roll_error_deg", "--mount-roll-error-deg"},
      {"faults.pose_drift_roll_deg_per_s", "--pose-drift-roll-deg-per-s"},
      {"faults.pose_drift_pitch_deg_per_s", "--pose-drift-pitch-deg-per-s"},
      {"faults.imu_gyro_noise", "--imu-gyro-noise"}, {"faults.imu_accel_noise", "--imu-accel-noise"},
      {"faults.imu_gyro_bias", "--imu-gyro-bias"}, {"faults.imu_accel_bias", "--imu-accel-bias"},
      {"faults.drop_frames", "--drop-frames"}, {"faults.textureless_patches", "--textureless-patches"},
      {"added_boxes", "--add-box"}};
  for (const auto& [key, flag] : kFlags) {
    const std::string prefix = std::string(key) + ":";
    if (error.rfind(prefix, 0) == 0) return flag + error.substr(std::string(key).size());
  }
  return error;
}

/// What `ssta synth` parses: the options, and the texts turned into them once all are read.
struct SynthArgs {
  synth::SynthOptions options;
  std::string out_dir, drop_frames;
  std::vector<std::string> config_files, boxes;
};

/// --width ... --imu-rate: the rig and its motion.
void AddRigOptions(CLI::App* cmd, synth::SynthOptions* options) {
  cmd->add_option("--width", options->rig.width, "image width [px]")->capture_default_str();
  cmd->add_option("--height", options->rig.height, "image height [px]")->capture_default_str();
  cmd->add_option("--focal", options->rig.focal_px, "focal length [px]")->capture_default_str();
  cmd->add_option("--baseline", options->rig.baseline_m, "stereo baseline [m]")->capture_default_str();
  cmd->add_option("--camera-height", options->rig.camera_height_m, "cam0 height above ground [m]")
      ->capture_default_str();
  cmd->add_option("--camera-pitch-deg", options->rig.pitch_down_deg, "rig pitch down [deg]")
      ->capture_default_str();
  cmd->add_option("--rate", options->rig.rate_hz, "camera rate [Hz]")->capture_default_str();
  cmd->add_option("--speed", options->motion.speed_mps, "vehicle speed [m/s]")->capture_default_str();
  cmd->add_option("--weave", options->motion.weave_amplitude_m, "lateral weave of the path [m]")
      ->capture_default_str();
  cmd->add_option("--weave-period", options->motion.weave_period_s, "period of the weave [s]")
      ->capture_default_str();
  cmd->add_option("--imu-rate", options->motion.imu_rate_hz, "IMU and pose0 rate [Hz]")
      ->capture_default_str();
}

/// --max-label-range ... --config: how the images and the truth are rendered.
void AddRenderOptions(CLI::App* cmd, SynthArgs* args) {
  cmd->add_option("--max-label-range", args->options.render.max_label_range_m,
                  "labels beyond this range are 255 [m]")
      ->capture_default_str();
  cmd->add_option("--boundary-band", args->options.render.boundary_band_px,
                  "labels within this many px of a class change are 255 (the gt grid still scores the cells they see)")
      ->capture_default_str();
  cmd->add_option("--supersample", args->options.render.supersample,
                  "rays per pixel side for anti-aliasing (1 = off, 2 = 2x2: about 5x slower)")
      ->capture_default_str();
  cmd->add_option("--noise", args->options.render.sensor_noise_grey, "pixel noise std dev [grey levels]")
      ->capture_default_str();
  cmd->add_flag("!--no-shadows", args->options.render.shadows, "render without cast sun shadows");
  cmd->add_option("--threads", args->options.render.threads,
                  "render threads (0 = all cores); the output is the same for any count")
      ->capture_default_str();
  cmd->add_flag("!--grid-all-cells", args->options.grid_seen_only,
                "classify every gt grid cell, also those no camera saw (default: those are 255)");
  cmd->add_option("--grid-resolution", args->options.grid_resolution_m, "gt grid cell size [m]")
      ->capture_default_str();
  cmd->add_option("--config", args->config_files,
                  "YAML config whose vehicle section sets the ground truth's thresholds (repeatable)");
}

/// --mount-pitch-error-deg ... --add-box: faults and additions to test against.
void AddFaultOptions(CLI::App* cmd, SynthArgs* args) {
  auto& f = args->options.faults;
  cmd->add_option("--mount-pitch-error-deg", f.mount_pitch_error_deg,
                  "rotate the rig in cam*/sensor.yaml about body y [deg] (positive: further down);\n"
                  "images stay true, gt/extrinsics.yaml keeps the truth");
  cmd->add_option("--mount-roll-error-deg", f.mount_roll_error_deg,
                  "rotate the rig in cam*/sensor.yaml about body x [deg] (positive: right side down);\n"
                  "images stay true, gt/extrinsics.yaml keeps the truth");
  cmd->add_option("--pose-drift-roll-deg-per-s", f.pose_drift_roll_deg_per_s,
                  "pose0 roll drifts linearly [deg/s]; images and IMU stay true");
  cmd->add_option("--pose-drift-pitch-deg-per-s", f.pose_drift_pitch_deg_per_s,
                  "pose0 pitch drifts linearly [deg/s]; images and IMU stay true");
  cmd->add_option("--imu-gyro-noise", f.imu_gyro_noise, "gyro white noise per sample [rad/s]");
  cmd->add_option("--imu-accel-noise", f.imu_accel_noise, "accel white noise per sample [m/s^2]");
  cmd->add_option("--imu-gyro-bias", f.imu_gyro_bias, "gyro bias on every axis [rad/s]");
  cmd->add_option("--imu-accel-bias", f.imu_accel_bias, "accel bias on every axis [m/s^2]");
  cmd->add_option("--drop-frames", args->drop_frames,
                  "frames missing from cam1 (cam0 and gt keep them): a fraction with a decimal\n"
                  "point (0.1), or 0-based frame indices (3,7,12)");
  cmd->add_option("--textureless-patches", f.textureless_patches,
                  "number of flat untextured discs on the ground ahead");
  cmd->add_option("--add-box", args->boxes,
                  "X,Y,LENGTH,WIDTH,HEIGHT[,YAW_DEG]: a wooden box (a crate) set on the ground, centred at X,Y\n"
                  "[m], HEIGHT above the ground; in the truth too (repeatable; gt/rig.yaml lists them).\n"
                  "The vehicle drives through one on its path: set it beside");
}

/// The random scene draws its rig and light from the seed too; what the command line gives wins.
void ApplyDrawnRig(const CLI::App& cmd, synth::SynthOptions* options) {
  synth::SynthOptions drawn = *options;
  synth::DrawRandomRig(options->seed, &drawn);
  const auto keep = [&](const char* flag, auto* value, auto drawn_value) {
    if (cmd.count(flag) == 0) *value = drawn_value;
  };
  keep("--width", &options->rig.width, drawn.rig.width);
  keep("--height", &options->rig.height, drawn.rig.height);
  keep("--focal", &options->rig.focal_px, drawn.rig.focal_px);
  keep("--baseline", &options->rig.baseline_m, drawn.rig.baseline_m);
  keep("--camera-height", &options->rig.camera_height_m, drawn.rig.camera_height_m);
  keep("--camera-pitch-deg", &options->rig.pitch_down_deg, drawn.rig.pitch_down_deg);
  keep("--noise", &options->render.sensor_noise_grey, drawn.render.sensor_noise_grey);
  options->render.sun_direction = drawn.render.sun_direction;
  options->render.sun_gain = drawn.render.sun_gain;
  options->render.ambient = drawn.render.ambient;
  options->render.sky_grey = drawn.render.sky_grey;
}

/// `ssta synth` once its options are parsed.
void RunSynth(const CLI::App& cmd, SynthArgs* args) {
  ParseDropFrames(args->drop_frames, &args->options.faults);
  for (const std::string& box : args->boxes) args->options.added_boxes.push_back(ParseBox(box));
  if (args->options.scene == "random") ApplyDrawnRig(cmd, &args->options);
  if (!args->config_files.empty()) args->options.vehicle = LoadLayeredConfig(nullptr, args->config_files).vehicle;
  std::string error;
  if (!args->options.IsValid(&error)) throw Error(NameTheOption(error));
  ProgressLine progress("synth");
  const synth::SynthSummary summary = synth::WriteSyntheticSequence(
      args->options, args->out_dir, [&progress](int done, int total) { progress.Update(done, total); });
  progress.Finish();
  std::cout << summary.BriefReport() << "\n";
  if (!summary.warning.empty()) std::cerr << "ssta synth: warning: " << summary.warning << "\n";
}

}  // namespace

void RegisterSynth(CLI::App& app) {
  auto args = std::make_shared<SynthArgs>();
  CLI::App* cmd = app.add_subcommand(
      "synth", "Render a synthetic stereo sequence with exact ground truth (SEQ/gt/) for testing and scoring");
  cmd->footer(
      "Writes an ASL sequence and SEQ/gt/ (labels, disparity*256, world grid of classes, true\n"
      "extrinsics, faults.yaml).\n"
      "Rig: rectified pinhole pair, 640x480, f = 420 px, principal point at the image centre,\n"
      "baseline 0.12 m, cam0 0.80 m above the ground pitched down 15 deg (horizon near row 127,\n"
      "largest ground disparity about 51 px), 15 Hz; IMU and pose0 at 200 Hz; vehicle 1 m/s\n"
      "heading +x from the origin with a gentle weave. Default vehicle thresholds: slope\n"
      "15/25 deg, step 0.10/0.20 m (written to SEQ/vehicle.yaml).\n"
      "Scenes:\n"
      "  yard     flat gravel; ramps of 8/18/30 deg; curbs 0.05/0.15 m; a 0.30 m step;\n"
      "           crates; rocks 0.06-0.4 m\n"
      "  hills    rolling hills (flanks up to ~30 deg), a 0.5 m deep ditch 6.5 m ahead, rocks\n"
      "  dropoff  flat ground ending 6 m ahead in a 0.8 m drop; a 0.3 m hole; rocks\n"
      "  forest   trunks, logs (a 0.12 m log across the way 6.5 m ahead), rocks\n"
      "  ramp     one plane of --ramp-slope-deg everywhere; the vehicle drives up it\n"
      "  random   terrain composed from all of the above (slopes, ditches, a drop-off, ramps, terraces,\n"
      "           curbs, crates, rocks, trunks, logs), a rig (image size, focal length, baseline,\n"
      "           height, pitch) and light (sun, sky, noise) drawn from --seed; the rig options are\n"
      "           ignored, gt/rig.yaml records the rig drawn\n"
      "The way ahead is clear for 5.5 m (yard 6.5 m, random 7 m; ramp unlimited): about 80 frames\n"
      "at the default speed and rate. Longer runs are written with a warning.\n"
      "Truth follows the class rule (docs/interfaces.md, section 3): the worse of the surface's slope\n"
      "class and the step class of the true heights within the vehicle's step_radius_m. Labels are\n"
      "255 (don't care) for sky, beyond --max-label-range, pixels hidden from cam1 and a 1 px band\n"
      "on class boundaries.");
  cmd->add_option("--scene", args->options.scene, "yard | hills | dropoff | forest | ramp | random (terrain, rig and light drawn from --seed)")
      ->capture_default_str();
  cmd->add_option("--out", args->out_dir, "output sequence folder SEQ")->required()->check(OutputFolder());
  cmd->add_option("--frames", args->options.frames, "number of stereo frames")->capture_default_str();
  cmd->add_option("--seed", args->options.seed, "seed of layout, texture and noise")->capture_default_str();
  cmd->add_option("--ramp-slope-deg", args->options.ramp_slope_deg, "slope of the ramp scene [deg]")
      ->capture_default_str();
  AddRigOptions(cmd, &args->options);
  AddRenderOptions(cmd, args.get());
  AddFaultOptions(cmd, args.get());
  cmd->callback([cmd, args] { RunSynth(*cmd, args.get()); });
}

}  // namespace ssta::cli
