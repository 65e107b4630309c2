#include "ssta/synth/vehicle_trajectory.h"

#include <cmath>

namespace ssta::synth {
namespace {
constexpr double kTwoPi = 6.283185307179586;

/// Rotation vector of a rotation matrix (inverse of the exponential map).
Eigen::Vector3d Log(const Eigen::Matrix3d& r) {
  const Eigen::AngleAxisd aa(r);
  return aa.angle() * aa.axis();
}
}  // namespace

VehicleTrajectory::VehicleTrajectory(const Scene& scene, const MotionOptions& motion)
    : scene_(scene), motion_(motion) {}

Eigen::Isometry3d VehicleTrajectory::WorldTBody(double t_s) const {
  const double yaw0 = scene_.start_yaw_rad;
  const Eigen::Vector2d forward(std::cos(yaw0), std::sin(yaw0));
  const Eigen::Vector2d left(-forward.y(), forward.x());
  const double s = motion_.speed_mps * t_s;
  const double omega = motion_.weave_period_s > 0 ? kTwoPi / motion_.weave_period_s : 0.0;
  const double lateral = motion_.weave_amplitude_m * std::sin(omega * t_s);
  const double lateral_rate = motion_.weave_amplitude_m * omega * std::cos(omega * t_s);
  const Eigen::Vector2d xy = scene_.start_xy + s * forward + lateral * left;
  const double yaw = yaw0 + std::atan2(lateral_rate, motion_.speed_mps);

  // Plane through the four wheel contacts (least squares; exact for the symmetric layout).
  const Eigen::Vector2d fx(std::cos(yaw), std::sin(yaw)), fy(-fx.y(), fx.x());
  const double hx = 0.5 * motion_.wheelbase_m, hy = 0.5 * motion_.track_m;
  auto z_at = [&](double a, double b) {
    const Eigen::Vector2d p = xy + a * fx + b * fy;
    return scene_.BaseHeight(p.x(), p.y());
  };
  const double fl = z_at(hx, hy), fr = z_at(hx, -hy), rl = z_at(-hx, hy), rr = z_at(-hx, -hy);
  const double z0 = 0.25 * (fl + fr + rl + rr);
  const double slope_x = ((fl + fr) - (rl + rr)) / (4 * hx);  // dz per metre forward
  const double slope_y = ((fl + rl) - (fr + rr)) / (4 * hy);  // dz per metre left

  const Eigen::Vector3d ex(fx.x(), fx.y(), 0), ey(fy.x(), fy.y(), 0);
  const Eigen::Vector3d up = (Eigen::Vector3d::UnitZ() - slope_x * ex - slope_y * ey).normalized();
  const Eigen::Vector3d x_axis = (ex - ex.dot(up) * up).normalized();
  Eigen::Matrix3d r;
  r.col(0) = x_axis;
  r.col(1) = up.cross(x_axis);
  r.col(2) = up;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = r;
  pose.translation() = Eigen::Vector3d(xy.x(), xy.y(), z0) + motion_.body_height_m * up;
  return pose;
}

ImuSample VehicleTrajectory::Imu(double t_s) const {
  constexpr double kH = 1e-3;
  const Eigen::Isometry3d a = WorldTBody(t_s - kH), b = WorldTBody(t_s), c = WorldTBody(t_s + kH);
  ImuSample s;
  // Body rates: the relative rotation over [t-h, t+h], taken in the body frame at t.
  const Eigen::Vector3d w_prev = Log(a.linear().transpose() * b.linear()) / kH;
  const Eigen::Vector3d w_next = Log(b.linear().transpose() * c.linear()) / kH;
  s.gyro_rad_s = 0.5 * (w_prev + w_next);
  const Eigen::Vector3d acc_world =
      (c.translation() - 2 * b.translation() + a.translation()) / (kH * kH);
  s.accel_m_s2 = b.linear().transpose() * (acc_world - kGravityWorld);
  return s;
}

}  // namespace ssta::synth
