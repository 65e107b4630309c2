#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include <Eigen/Geometry>

#include "ssta/core/option_fields.h"
#include "ssta/io/sequence.h"
#include "ssta/sensors/attitude_filter.h"

namespace ssta {

/// Where each frame's gravity (up direction) comes from (YAML `gravity.source`).
enum class GravitySource {
  kAuto,   ///< "auto": the IMU when it has samples around the frame, else the pose, else level
  kImu,    ///< "imu": mean accelerometer reading around the frame (platform at rest or cruising)
  kPose,   ///< "pose": the attitude of pose0 (or EuRoC's ground truth) at the frame
  kLevel,  ///< "level": the body is level, up = body z; the camera tilt comes from cam0's T_BS
  kFixed,  ///< "fixed": `up_camera` as given, in the original cam0 frame
};

/// YAML section `gravity`.
struct GravityOptions {
  GravitySource source = GravitySource::kAuto;
  Eigen::Vector3d up_camera{0.0, -1.0, 0.0};  ///< for source "fixed": up in cam0 (y down)
  /// Every field: its key, unit, range and meaning (reading, writing and IsValid come from it).
  static const OptionFields<GravityOptions>& Fields();
  /// The first field out of its range, as "key: requirement" in `*error`.
  bool IsValid(std::string* error) const;
};

std::string GravitySourceName(GravitySource source);

/// Gravity and gravity-corrected poses for the frames of one sequence, as `gravity.source`
/// asks: the IMU attitude filter, the pose's attitude, a level body, or a fixed vector.
/// Thread-safe for concurrent readers once built. With an IMU in use (source auto or imu, and
/// IMU samples), every frame takes its attitude from the IMU: a frame outside the IMU's time
/// range throws (the callers skip it with that reason), as docs/interfaces.md, section 2 asks.
class GravityProvider {
 public:
  /// Throws ssta::Error naming the IMU file when an IMU in use overlaps none of the frames.
  GravityProvider(const Sequence& sequence, const GravityOptions& gravity, const AttitudeFilterOptions& attitude);

  /// Unit up vector in the original cam0 frame at `t`. `source_used` (optional) names the
  /// source that answered: "imu", "pose", "level" or "fixed" (auto: the IMU when the sequence
  /// has one, else the pose, else level). Throws ssta::Error when the IMU in use does not cover
  /// `t` or a source named explicitly has no data at `t`.
  Eigen::Vector3d UpInCamera(std::int64_t t, std::string* source_used = nullptr) const;

  /// Up in the body frame at `t` (same sources as UpInCamera, "fixed" excluded).
  Eigen::Vector3d UpInBody(std::int64_t t, std::string* source_used = nullptr) const;

  /// T_WB at `t` with roll and pitch taken from the IMU in use (position and yaw from the
  /// odometry); the odometry pose as it is without one; nullopt without a pose at `t`. Throws
  /// ssta::Error when the IMU in use does not cover `t`.
  std::optional<Eigen::Isometry3d> WorldTBodyAt(std::int64_t t) const;

  /// Where the frames' up direction comes from, for reports: "IMU attitude filter (FILE)",
  /// "pose attitude (FILE)", "level ..." or "fixed ...".
  std::string Describe() const;

 private:
  std::string ImuGap(std::int64_t t) const;  // why the IMU gives no attitude at t

  const Sequence& sequence_;
  GravityOptions gravity_;
  std::unique_ptr<GravityTrack> track_;  // null without IMU samples
};

}  // namespace ssta
