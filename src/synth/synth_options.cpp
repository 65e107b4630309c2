#include "ssta/synth/synth_options.h"

#include <cmath>

#include "ssta/synth/scene.h"
#include "ssta/core/units.h"
#include "synth/random.h"

#include "ssta/core/error.h"

namespace ssta::synth {
namespace {
bool Finite(double x) { return std::isfinite(x); }
}  // namespace

bool RigOptions::IsValid(std::string* error) const {
  if (width < 16 || width > 8192) return Fail(error, "width: must be in [16, 8192] px");
  if (height < 16 || height > 8192) return Fail(error, "height: must be in [16, 8192] px");
  if (!(focal_px > 1 && focal_px < 1e5)) return Fail(error, "focal_px: must be in (1, 1e5) px");
  if (!(baseline_m > 0.001 && baseline_m < 10)) return Fail(error, "baseline_m: must be in (0.001, 10) m");
  if (!(camera_height_m > 0.05 && camera_height_m < 20)) {
    return Fail(error, "camera_height_m: must be in (0.05, 20) m");
  }
  if (!Finite(camera_forward_m) || std::abs(camera_forward_m) > 10) {
    return Fail(error, "camera_forward_m: must be within 10 m of the body origin");
  }
  if (!(pitch_down_deg > -45 && pitch_down_deg < 80)) {
    return Fail(error, "pitch_down_deg: must be in (-45, 80) degrees");
  }
  if (!(rate_hz > 0.1 && rate_hz <= 1000)) return Fail(error, "rate_hz: must be in (0.1, 1000] Hz");
  return true;
}

bool RenderOptions::IsValid(std::string* error) const {
  if (supersample < 1 || supersample > 4) return Fail(error, "supersample: must be 1, 2, 3 or 4");
  if (!(sensor_noise_grey >= 0 && sensor_noise_grey <= 50)) {
    return Fail(error, "sensor_noise_grey: must be in [0, 50] grey levels");
  }
  if (!(max_label_range_m > 0 && max_label_range_m <= 1000)) {
    return Fail(error, "max_label_range_m: must be in (0, 1000] m");
  }
  if (!(max_ray_m >= max_label_range_m && max_ray_m <= 10000)) {
    return Fail(error, "max_ray_m: must be in [max_label_range_m, 10000] m");
  }
  if (boundary_band_px < 0 || boundary_band_px > 10) {
    return Fail(error, "boundary_band_px: must be in [0, 10] px");
  }
  if (threads < 0 || threads > 256) return Fail(error, "threads: must be in [0, 256] (0 = all)");
  if (!(sun_direction.allFinite() && sun_direction.z() > 0)) {
    return Fail(error, "sun_direction: must point above the horizon");
  }
  if (!(sun_gain >= 0 && sun_gain <= 2 && ambient >= 0 && ambient <= 2)) {
    return Fail(error, "sun_gain, ambient: must be in [0, 2]");
  }
  if (!(sky_grey >= 0 && sky_grey <= 205)) return Fail(error, "sky_grey: must be in [0, 205] grey levels");
  return true;
}

void DrawRandomRig(std::uint64_t seed, SynthOptions* o) {
  Rng rng(seed * 0x9e3779b97f4a7c15ULL + 29);
  const std::pair<int, int> sizes[] = {{640, 480}, {752, 480}, {800, 600}, {1024, 576}, {1241, 376}};
  for (;;) {
    RigOptions rig = o->rig;
    const auto [w, h] = sizes[static_cast<int>(rng.Uniform(0, 5))];
    rig.width = w;
    rig.height = h;
    rig.focal_px = rng.Uniform(350, 800);
    rig.baseline_m = rng.Uniform(0.10, 0.50);
    rig.camera_height_m = rng.Uniform(0.5, 1.6);
    rig.pitch_down_deg = rng.Uniform(5, 25);
    const double hfov_deg = RadToDeg(2 * std::atan(0.5 * w / rig.focal_px));
    // The nearest level ground in view, at the bottom row.
    const double p = DegToRad(rig.pitch_down_deg), y_bottom = 0.5 * (h - 1) / rig.focal_px;
    const double d_max = rig.focal_px * rig.baseline_m * (y_bottom * std::cos(p) + std::sin(p)) / rig.camera_height_m;
    if (hfov_deg < 40 || hfov_deg > 110 || d_max > 0.2 * w) continue;
    o->rig = rig;
    break;
  }
  RenderOptions& r = o->render;
  const double elevation = DegToRad(rng.Uniform(20, 75)), azimuth = rng.Uniform(0, 2 * kPi);
  r.sun_direction = Eigen::Vector3d(std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth),
                                    std::sin(elevation));
  r.sun_gain = rng.Uniform(0.3, 0.8);
  r.ambient = rng.Uniform(0.3, 0.6);
  r.sky_grey = rng.Uniform(140, 205);
  r.sensor_noise_grey = rng.Uniform(0.5, 3.0);
}

bool MotionOptions::IsValid(std::string* error) const {
  if (!(speed_mps >= 0 && speed_mps <= 30)) return Fail(error, "speed_mps: must be in [0, 30] m/s");
  if (!(weave_amplitude_m >= 0 && weave_amplitude_m <= 5)) {
    return Fail(error, "weave_amplitude_m: must be in [0, 5] m");
  }
  if (!(weave_period_s > 0.5 && weave_period_s <= 1000)) {
    return Fail(error, "weave_period_s: must be in (0.5, 1000] s");
  }
  if (weave_amplitude_m > 0 && speed_mps <= 0) {
    return Fail(error, "weave_amplitude_m: must be 0 when speed_mps is 0");
  }
  if (!(wheelbase_m > 0.05 && wheelbase_m < 10)) return Fail(error, "wheelbase_m: must be in (0.05, 10) m");
  if (!(track_m > 0.05 && track_m < 10)) return Fail(error, "track_m: must be in (0.05, 10) m");
  if (!(body_height_m >= 0 && body_height_m < 5)) return Fail(error, "body_height_m: must be in [0, 5) m");
  if (!(imu_rate_hz >= 10 && imu_rate_hz <= 2000)) {
    return Fail(error, "imu_rate_hz: must be in [10, 2000] Hz");
  }
  return true;
}

bool FaultOptions::IsValid(std::string* error) const {
  if (!(std::abs(mount_pitch_error_deg) <= 30)) {
    return Fail(error, "mount_pitch_error_deg: must be within +-30 degrees");
  }
  if (!(std::abs(mount_roll_error_deg) <= 30)) {
    return Fail(error, "mount_roll_error_deg: must be within +-30 degrees");
  }
  if (!(std::abs(pose_drift_roll_deg_per_s) <= 10)) {
    return Fail(error, "pose_drift_roll_deg_per_s: must be within +-10 deg/s");
  }
  if (!(std::abs(pose_drift_pitch_deg_per_s) <= 10)) {
    return Fail(error, "pose_drift_pitch_deg_per_s: must be within +-10 deg/s");
  }
  if (!(imu_gyro_noise >= 0 && imu_gyro_noise <= 10)) return Fail(error, "imu_gyro_noise: must be in [0, 10] rad/s");
  if (!(imu_accel_noise >= 0 && imu_accel_noise <= 100)) {
    return Fail(error, "imu_accel_noise: must be in [0, 100] m/s^2");
  }
  if (!(std::abs(imu_gyro_bias) <= 10)) return Fail(error, "imu_gyro_bias: must be within +-10 rad/s");
  if (!(std::abs(imu_accel_bias) <= 100)) return Fail(error, "imu_accel_bias: must be within +-100 m/s^2");
  if (!(drop_frame_fraction >= 0 && drop_frame_fraction < 1)) {
    return Fail(error, "drop_frames: a fraction must be in [0, 1)");
  }
  for (int i : drop_frame_indices) {
    if (i < 0) return Fail(error, "drop_frames: frame indices must not be negative");
  }
  if (textureless_patches < 0 || textureless_patches > 100) {
    return Fail(error, "textureless_patches: must be in [0, 100]");
  }
  return true;
}

bool SynthOptions::IsValid(std::string* error) const {
  bool known = false;
  for (const std::string& n : SceneNames()) known = known || n == scene;
  if (!known) return Fail(error, "scene: unknown scene '" + scene + "' (yard, hills, dropoff, forest, ramp, random)");
  if (frames < 1 || frames > 100000) return Fail(error, "frames: must be in [1, 100000]");
  if (!(ramp_slope_deg >= 0 && ramp_slope_deg < 60)) {
    return Fail(error, "ramp_slope_deg: must be in [0, 60) degrees");
  }
  if (!(grid_resolution_m >= 0.01 && grid_resolution_m <= 5)) {
    return Fail(error, "grid_resolution_m: must be in [0.01, 5] m");
  }
  std::string e;
  if (!vehicle.IsValid(&e)) return Fail(error, "vehicle." + e);
  if (!rig.IsValid(&e)) return Fail(error, "rig." + e);
  if (!render.IsValid(&e)) return Fail(error, "render." + e);
  if (!motion.IsValid(&e)) return Fail(error, "motion." + e);
  if (!faults.IsValid(&e)) return Fail(error, "faults." + e);
  for (int i : faults.drop_frame_indices) {
    if (i >= frames) return Fail(error, "faults.drop_frames: frame index " + std::to_string(i) + " is not below frames");
  }
  if (added_boxes.size() > 100) return Fail(error, "added_boxes: at most 100");
  for (const AddedBox& b : added_boxes) {
    if (!(Finite(b.x) && Finite(b.y) && std::abs(b.x) <= 1e4 && std::abs(b.y) <= 1e4 && Finite(b.yaw_deg))) {
      return Fail(error, "added_boxes: x and y must be within 10 km of the origin, yaw_deg finite");
    }
    if (!(b.length_m > 0 && b.length_m <= 50 && b.width_m > 0 && b.width_m <= 50)) {
      return Fail(error, "added_boxes: length and width must be in (0, 50] m");
    }
    if (!(b.height_m > 0 && b.height_m <= 20)) return Fail(error, "added_boxes: height must be in (0, 20] m");
  }
  if (rig.camera_height_m <= motion.body_height_m) {
    return Fail(error, "rig.camera_height_m: must be above motion.body_height_m");
  }
  return true;
}

}  // namespace ssta::synth
