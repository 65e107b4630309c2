#include "ssta/sensors/attitude_filter.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "ssta/core/error.h"

namespace ssta {
namespace {

constexpr double kGravity = 9.81;


/// The initial window is taken as the attitude at rest; when it looks at rest (slow rotation,
/// steady |a|), the mean specific force must be gravity. An IMU in g, or with a scale error,
/// would otherwise give a plausible up and silently wrong gating.
/// The initial window looks at rest: slow rotation, steady |a|.
bool LooksAtRest(double mean_norm, double norm_spread, double mean_rate) {
  return mean_rate < 0.5 && norm_spread <= 0.1 * mean_norm;
}

void CheckGravityAtRest(const Eigen::Vector3d& mean_force, double mean_norm, double norm_spread, double mean_rate,
                        int samples, const AttitudeFilterOptions& options, const std::string& imu_file) {
  if (!LooksAtRest(mean_norm, norm_spread, mean_rate)) return;
  const double reading = mean_force.norm();
  if (std::abs(reading - kGravity) <= options.max_rest_gravity_error_mps2) return;
  char text[256];
  std::snprintf(text, sizeof(text),
                ": the IMU at rest reads %.3g m/s^2 (mean of the first %d samples), gravity is 9.81; off by more "
                "than attitude.max_rest_gravity_error_mps2 = %g (accelerometer in g instead of m/s^2, or a scale "
                "error?)",
                reading, samples, options.max_rest_gravity_error_mps2);
  throw Error(imu_file + text);
}

}  // namespace

const OptionFields<AttitudeFilterOptions>& AttitudeFilterOptions::Fields() {
  using O = AttitudeFilterOptions;
  static const OptionFields<O> fields = [] {
    OptionFields<O> f;
    f.push_back(Real<O>("kp", &O::kp, Closed(0, 100), "1/s", "pull towards the accelerometer's up"));
    f.push_back(Real<O>("ki", &O::ki, Closed(0, 10), "1/s^2", "gyro bias integration (time constant kp/ki)"));
    f.push_back(Real<O>("accel_gate", &O::accel_gate, OpenClosed(0, 1), "",
                        "the accelerometer is ignored while |a| is off 9.81 by more than this share"));
    f.push_back(Real<O>("init_window_s", &O::init_window_s, OpenClosed(0, 10), "s",
                        "accelerometer samples averaged for the initial attitude"));
    f.push_back(Real<O>("max_rest_gravity_error_mps2", &O::max_rest_gravity_error_mps2, OpenClosed(0, 9.81),
                        "m/s^2", "an IMU at rest over that window must read 9.81 within this (else its "
                                 "units or scale are wrong)"));
    f.push_back(Flag<O>("init_gyro_bias", &O::init_gyro_bias,
                        "an IMU at rest over that window: its mean gyro rate is the initial gyro bias "
                        "(else up leans by bias/kp until ki learns it)"));
    return f;
  }();
  return fields;
}

bool AttitudeFilterOptions::IsValid(std::string* error) const { return CheckOptions(*this, Fields(), error); }

GravityTrack::GravityTrack(const std::vector<ImuSample>& imu, const Eigen::Isometry3d& body_T_imu,
                           const AttitudeFilterOptions& options, const std::string& imu_file) {
  std::string error;
  if (!options.IsValid(&error)) throw Error("attitude." + error);
  if (imu.empty()) return;

  // Initial attitude: the mean accelerometer direction over the first window is up.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero(), mean_rate = Eigen::Vector3d::Zero();
  const auto init_end = imu.front().timestamp_ns + static_cast<std::int64_t>(options.init_window_s * 1e9);
  int n = 0;
  double norm_sum = 0.0, norm_sq_sum = 0.0, rate_sum = 0.0;
  for (const ImuSample& s : imu) {
    if (s.timestamp_ns > init_end && n > 0) break;
    mean += s.specific_force;
    mean_rate += s.angular_rate;
    const double a = s.specific_force.norm();
    norm_sum += a;
    norm_sq_sum += a * a;
    rate_sum += s.angular_rate.norm();
    ++n;
  }
  mean /= n;
  mean_rate /= n;
  const double norm_spread = std::sqrt(std::max(0.0, norm_sq_sum / n - (norm_sum / n) * (norm_sum / n)));
  CheckGravityAtRest(mean, norm_sum / n, norm_spread, rate_sum / n, n, options, imu_file);
  // The gyro bias from a start at rest. Were the mean rate a real rotation, its part across
  // gravity would turn the accelerometer's direction by |w_perp| * window / 2 between the
  // window's halves; at rest only vibration and noise move it (EuRoC, rotors turning: 0.54 of
  // that). A real rotation turns it by about that much: above 0.75 the rate is not a bias.
  Eigen::Vector3d integral = Eigen::Vector3d::Zero();
  if (options.init_gyro_bias && n >= 4 && mean.norm() > 1e-6 && LooksAtRest(norm_sum / n, norm_spread, rate_sum / n)) {
    Eigen::Vector3d first = Eigen::Vector3d::Zero(), second = Eigen::Vector3d::Zero();
    for (int i = 0; i < n; ++i) (2 * i < n ? first : second) += imu[static_cast<std::size_t>(i)].specific_force;
    const double turn = std::atan2(first.cross(second).norm(), first.dot(second));
    const Eigen::Vector3d along = mean.normalized();
    const double rate_across = (mean_rate - mean_rate.dot(along) * along).norm();
    const double window_s = 1e-9 * static_cast<double>(imu[static_cast<std::size_t>(n - 1)].timestamp_ns - imu.front().timestamp_ns);
    if (turn < 0.75 * rate_across * window_s / 2) integral = -mean_rate;  // the integral term converges to -bias
  }
  // world_q_imu maps IMU vectors into a world frame with z up (yaw is arbitrary).
  Eigen::Quaterniond world_q_imu = mean.norm() > 1e-6
                                       ? Eigen::Quaterniond::FromTwoVectors(mean.normalized(), Eigen::Vector3d::UnitZ())
                                       : Eigen::Quaterniond::Identity();
  const Eigen::Matrix3d body_R_imu = body_T_imu.linear();

  times_.reserve(imu.size());
  up_body_.reserve(imu.size());
  for (std::size_t i = 0; i < imu.size(); ++i) {
    const ImuSample& s = imu[i];
    const double dt = i == 0 ? 0.0 : 1e-9 * static_cast<double>(s.timestamp_ns - imu[i - 1].timestamp_ns);
    Eigen::Vector3d omega = s.angular_rate;
    const double a_norm = s.specific_force.norm();
    if (std::abs(a_norm - kGravity) < options.accel_gate * kGravity) {
      // Error between measured and estimated up, in the IMU frame: rotating the estimate by
      // (measured x estimated) turns it towards the measurement.
      const Eigen::Vector3d up_estimate = world_q_imu.conjugate() * Eigen::Vector3d::UnitZ();
      const Eigen::Vector3d e = (s.specific_force / a_norm).cross(up_estimate);
      integral += options.ki * e * dt;
      omega += options.kp * e + integral;
    }
    const double angle = omega.norm() * dt;
    if (angle > 0) world_q_imu = (world_q_imu * Eigen::Quaterniond(Eigen::AngleAxisd(angle, omega.normalized()))).normalized();
    times_.push_back(s.timestamp_ns);
    up_body_.push_back(body_R_imu * (world_q_imu.conjugate() * Eigen::Vector3d::UnitZ()));
  }
}

std::optional<Eigen::Vector3d> GravityTrack::UpInBodyAt(std::int64_t t) const {
  if (times_.empty() || t < times_.front() || t > times_.back()) return std::nullopt;
  const auto it = std::lower_bound(times_.begin(), times_.end(), t);
  const std::size_t j = static_cast<std::size_t>(it - times_.begin());
  if (*it == t || j == 0) return up_body_[j];
  const double s = static_cast<double>(t - times_[j - 1]) / static_cast<double>(times_[j] - times_[j - 1]);
  return ((1.0 - s) * up_body_[j - 1] + s * up_body_[j]).normalized();
}

Eigen::Isometry3d CorrectRollPitch(const Eigen::Isometry3d& world_T_body, const Eigen::Vector3d& up_body) {
  SSTA_CHECK(std::abs(up_body.norm() - 1.0) < 1e-6, "up_body must be a unit vector");
  const Eigen::Matrix3d r = world_T_body.linear();
  const double yaw = std::atan2(r(1, 0), r(0, 0));
  // For R = Rz(yaw) Ry(pitch) Rx(roll): up in the body = (-sin p, sin r cos p, cos r cos p).
  const double pitch = std::atan2(-up_body.x(), std::hypot(up_body.y(), up_body.z()));
  const double roll = std::atan2(up_body.y(), up_body.z());
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                  Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                     .toRotationMatrix();
  out.translation() = world_T_body.translation();
  return out;
}

}  // namespace ssta
