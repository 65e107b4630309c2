#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "ssta/core/option_fields.h"
#include "ssta/io/sequence.h"

namespace ssta {

/// YAML section `attitude`: a Mahony-style complementary filter on gyro + accelerometer.
struct AttitudeFilterOptions {
  double kp = 1.0;    ///< [1/s] proportional gain pulling the estimate to the accelerometer's up
  double ki = 0.1;    ///< [1/s^2] integral gain (estimates the gyro bias; time constant kp/ki)
  /// Accelerometer readings whose magnitude differs from 9.81 by more than this share are not
  /// trusted (the vehicle is accelerating): the filter integrates the gyro alone then.
  double accel_gate = 0.15;
  double init_window_s = 0.2;  ///< [s] accelerometer samples averaged for the initial attitude
  /// [m/s^2] When the IMU is at rest over the initial window (mean gyro rate below 0.5 rad/s,
  /// spread of |a| below 10 % of its mean), the mean specific force must read 9.81 within this;
  /// otherwise the accelerometer's units or scale are wrong and the recording is rejected.
  double max_rest_gravity_error_mps2 = 0.5;
  /// When the IMU is at rest over the initial window (as above, and the accelerometer's mean
  /// direction turns between the window's halves by less than 0.75 of what the mean gyro rate
  /// across gravity would turn it, were that rate real), its mean gyro rate is the gyro bias
  /// the filter starts from. Without this the integral term takes
  /// kp/ki (10 s) to learn the bias, and meanwhile up leans by bias/kp: EuRoC's ADIS16448 reads
  /// 0.08 rad/s at rest, 4.5 degrees. A start that only rotates about the vertical is not told
  /// apart from rest: the yaw rate is then taken as bias and unlearnt over kp/ki.
  bool init_gyro_bias = true;
  /// Every field: its key, unit, range and meaning (reading, writing and IsValid come from it).
  static const OptionFields<AttitudeFilterOptions>& Fields();
  /// The first field out of its range, as "key: requirement" in `*error`.
  bool IsValid(std::string* error) const;
};

/// Up direction (unit, opposite to gravity) in the body frame over time, from the IMU.
/// Thread-safe for concurrent readers once built.
class GravityTrack {
 public:
  /// Runs the filter over `imu` (IMU sensor frame) and expresses its up in the body through
  /// `body_T_imu`. Precondition: samples sorted by time (Sequence guarantees it). Throws
  /// ssta::Error naming `imu_file` (the file the samples came from, for the message) when the
  /// IMU at rest over the initial window reads gravity off 9.81 by more than
  /// options.max_rest_gravity_error_mps2.
  GravityTrack(const std::vector<ImuSample>& imu, const Eigen::Isometry3d& body_T_imu,
               const AttitudeFilterOptions& options, const std::string& imu_file = "imu0/data.csv");

  /// Up in the body at `t`, interpolated between filter samples; nullopt outside the IMU time
  /// range or without samples.
  std::optional<Eigen::Vector3d> UpInBodyAt(std::int64_t t) const;
  std::size_t size() const { return times_.size(); }

 private:
  std::vector<std::int64_t> times_;
  std::vector<Eigen::Vector3d> up_body_;
};

/// Roll and pitch from `up_body` (the body's up, from the IMU), position and yaw from
/// `world_T_body` (odometry): the gravity-corrected pose. Yaw is the Z angle of a Z-Y-X
/// decomposition. Precondition: up_body is a unit vector.
Eigen::Isometry3d CorrectRollPitch(const Eigen::Isometry3d& world_T_body, const Eigen::Vector3d& up_body);

}  // namespace ssta
