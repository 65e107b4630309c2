#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include <Eigen/Geometry>

#include "ssta/io/sequence.h"
#include "ssta/pipeline/attitude_filter.h"
#include "ssta/pipeline/config.h"

namespace ssta {

/// Gravity and gravity-corrected poses for the frames of one sequence, as `gravity.source`
/// asks: the IMU attitude filter, the pose's attitude, a level body, or a fixed vector.
/// Thread-safe for concurrent readers once built.
class GravityProvider {
 public:
  GravityProvider(const Sequence& sequence, const GravityOptions& gravity, const AttitudeFilterOptions& attitude);

  /// Unit up vector in the original cam0 frame at `t`. `source_used` (optional) names the
  /// source that answered: "imu", "pose", "level" or "fixed" (auto falls back in that order).
  /// Throws ssta::Error when a source named explicitly has no data at `t`.
  Eigen::Vector3d UpInCamera(std::int64_t t, std::string* source_used = nullptr) const;

  /// Up in the body frame at `t` (same sources as UpInCamera, "fixed" excluded).
  Eigen::Vector3d UpInBody(std::int64_t t, std::string* source_used = nullptr) const;

  /// T_WB at `t` with roll and pitch taken from the IMU where an IMU answers (position and yaw
  /// from the odometry); the odometry pose as it is otherwise; nullopt without a pose at `t`.
  std::optional<Eigen::Isometry3d> WorldTBodyAt(std::int64_t t) const;

 private:
  const Sequence& sequence_;
  GravityOptions gravity_;
  std::unique_ptr<GravityTrack> track_;  // null without IMU samples
};

}  // namespace ssta
