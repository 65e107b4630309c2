#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ssta/core/vehicle_options.h"

namespace ssta::synth {

/// The rectified stereo rig of a synthetic sequence: two identical pinhole cameras, zero
/// distortion, cam1 displaced by `baseline_m` along cam0's x axis (to the right).
/// The defaults keep the largest ground disparity in view near 51 px (below the default
/// 64-disparity search range) with the horizon at about row 127.
struct RigOptions {
  int width = 640;                ///< image width [px]
  int height = 480;               ///< image height [px]
  double focal_px = 420.0;        ///< focal length fu = fv [px]; principal point at the centre
  double baseline_m = 0.12;       ///< distance between the optical centres [m]
  double camera_height_m = 0.80;  ///< cam0 optical centre above the ground under the body [m]
  double camera_forward_m = 0.20; ///< cam0 optical centre ahead of the body origin [m]
  double pitch_down_deg = 15.0;   ///< rig pitched down about body y [deg]
  double rate_hz = 15.0;          ///< camera frame rate [Hz]

  bool IsValid(std::string* error) const;
};

/// How the frames are rendered.
struct RenderOptions {
  int supersample = 1;            ///< rays per pixel side (1 = none, 2 = 2x2 anti-aliasing)
  double sensor_noise_grey = 1.5; ///< std dev of the additive Gaussian pixel noise [grey levels]
  /// Labels beyond this range from cam0 are 255 (don't care), and the truth grid reaches this
  /// far around the path [m].
  double max_label_range_m = 20.0;
  double max_ray_m = 120.0;       ///< rays that hit nothing within this distance see the sky [m]
  int boundary_band_px = 1;       ///< labels within this many px of a class change become 255
  bool shadows = true;            ///< cast sun shadows (about 5-20 % more render time)
  /// Towards the sun in the world (z up; normalised when used): high on the left and a little
  /// behind by default, so shadows fall to the right.
  Eigen::Vector3d sun_direction{-0.2, 0.6, 0.78};
  double sun_gain = 0.62;         ///< sunlight on a surface facing the sun, times its albedo
  double ambient = 0.45;          ///< light from the sky everywhere, times the albedo
  double sky_grey = 185.0;        ///< grey of the sky at the horizon; it brightens by 50 to the zenith
  int threads = 0;                ///< render threads (0 = all hardware threads); same bytes for any

  bool IsValid(std::string* error) const;
};

/// The vehicle path: it drives straight on from the scene's start pose along a gentle weave.
struct MotionOptions {
  double speed_mps = 1.0;         ///< forward speed [m/s]
  double weave_amplitude_m = 0.15; ///< lateral sinusoidal weave of the path [m] (0 = straight)
  double weave_period_s = 8.0;    ///< period of the weave [s]
  double wheelbase_m = 0.6;       ///< distance front to rear wheel contacts [m]
  double track_m = 0.5;           ///< distance left to right wheel contacts [m]
  double body_height_m = 0.20;    ///< body origin (IMU) above the wheel-contact plane [m]
  double imu_rate_hz = 200.0;     ///< IMU and pose0 sample rate [Hz]

  bool IsValid(std::string* error) const;
};

/// Deliberate errors written into the sequence; every one is recorded in gt/faults.yaml.
/// The images are always rendered with the true geometry.
struct FaultOptions {
  double mount_pitch_error_deg = 0.0;  ///< sensor.yaml rig rotated about body y (+ = down) [deg]
  double mount_roll_error_deg = 0.0;   ///< sensor.yaml rig rotated about body x [deg]
  double pose_drift_roll_deg_per_s = 0.0;   ///< pose0 roll drifts linearly [deg/s]
  double pose_drift_pitch_deg_per_s = 0.0;  ///< pose0 pitch drifts linearly [deg/s]
  double imu_gyro_noise = 0.0;   ///< white noise std dev per gyro sample [rad/s]
  double imu_accel_noise = 0.0;  ///< white noise std dev per accelerometer sample [m/s^2]
  double imu_gyro_bias = 0.0;    ///< constant bias added to every gyro axis [rad/s]
  double imu_accel_bias = 0.0;   ///< constant bias added to every accelerometer axis [m/s^2]
  /// Fraction in [0, 1) of frames whose cam1 image is missing (chosen by the seed); ignored
  /// when `drop_frame_indices` is not empty. cam0 and gt keep every frame.
  double drop_frame_fraction = 0.0;
  std::vector<int> drop_frame_indices;  ///< explicit 0-based frame indices to drop from cam1
  int textureless_patches = 0;   ///< flat untextured discs laid on the ground ahead of the path

  bool IsValid(std::string* error) const;
};

/// A rig and lighting drawn from `seed` within real ranges, for the `random` scene: image sizes
/// from VGA to KITTI's, focal length 350 to 800 px (horizontal field of view 40 to 110 deg),
/// baseline 0.10 to 0.50 m, camera 0.5 to 1.6 m up and pitched 5 to 25 deg down, with the
/// nearest ground disparity within 20 % of the image width (a rig designed for its range); sun,
/// sky, ambient light and sensor noise. Replaces `o->rig` (but its rate) and the lighting of
/// `o->render`.
void DrawRandomRig(std::uint64_t seed, struct SynthOptions* o);

/// A box set on the scene's ground (`ssta synth --add-box`): a crate that is there in one drive
/// of a scene and not in another. The truth (labels, disparity, grid) includes it.
struct AddedBox {
  double x = 0.0, y = 0.0;  ///< centre in world [m]
  double length_m = 0.6;    ///< side along yaw_deg [m], in (0, 50]
  double width_m = 0.6;     ///< side across [m], in (0, 50]
  double height_m = 0.5;    ///< top above the ground under its centre [m], in (0, 20]
  double yaw_deg = 0.0;     ///< heading of the length side, from +x towards +y [deg]
};

/// Everything `ssta synth` needs. A given (options, seed) always produces the same bytes.
struct SynthOptions {
  std::string scene = "yard";   ///< one of SceneNames(): yard, hills, dropoff, forest, ramp
  int frames = 30;              ///< number of stereo frames
  std::uint64_t seed = 1;       ///< seeds scene layout, texture, noise and faults
  double ramp_slope_deg = 20.0; ///< slope of the `ramp` scene's plane [deg]
  double grid_resolution_m = 0.1;  ///< cell size of gt/grid_classes.png [m]
  /// Cells of gt/grid_classes.png that no frame saw (with both cameras, within the label range)
  /// are 255 (don't care), so that a map is scored on what the cameras could see; the labels'
  /// don't-care band does not unscore a cell. false: every cell is classified.
  bool grid_seen_only = true;
  VehicleOptions vehicle;       ///< thresholds for the ground-truth classes; written to vehicle.yaml
  RigOptions rig;
  RenderOptions render;
  MotionOptions motion;
  FaultOptions faults;
  /// Boxes added to the scene (at most 100); the vehicle's pose follows the ground only, so one
  /// on its path is driven through.
  std::vector<AddedBox> added_boxes;

  /// Checks every field; the message starts with the offending option name.
  bool IsValid(std::string* error) const;
};

}  // namespace ssta::synth
