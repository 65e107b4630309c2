#pragma once

#include <Eigen/Geometry>

#include "ssta/synth/scene.h"
#include "ssta/synth/synth_options.h"

namespace ssta::synth {

/// An ideal IMU sample in the body frame (the IMU defines the body).
struct ImuSample {
  Eigen::Vector3d gyro_rad_s = Eigen::Vector3d::Zero();     ///< angular rate of B in B [rad/s]
  Eigen::Vector3d accel_m_s2 = Eigen::Vector3d::Zero();     ///< specific force in B [m/s^2]
};

/// The vehicle driving over a Scene: a weaving path at constant speed from the scene's start
/// pose; height, roll and pitch follow a plane fitted to the base-ground heights under the four
/// wheel contacts. Body frame x forward, y left, z up; the body origin is `body_height_m` above
/// the contact plane. Smooth where the base ground is smooth. Thread-safe: all methods const.
class VehicleTrajectory {
 public:
  /// Precondition: `motion` is valid; `scene` outlives the trajectory.
  VehicleTrajectory(const Scene& scene, const MotionOptions& motion);

  /// Pose of the body in the world at time `t_s` [s] since the start.
  Eigen::Isometry3d WorldTBody(double t_s) const;

  /// What a perfect IMU reads at `t_s`: rates and specific force (a - g) in the body, from
  /// central differences of WorldTBody (step 1 ms). At rest: accel = R_WB^T (0, 0, 9.81).
  ImuSample Imu(double t_s) const;

 private:
  const Scene& scene_;
  MotionOptions motion_;
};

/// Gravity in the world frame [m/s^2].
inline const Eigen::Vector3d kGravityWorld(0.0, 0.0, -9.81);

}  // namespace ssta::synth
