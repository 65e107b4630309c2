#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <string>

#include "ssta/core/error.h"
#include "ssta/io/sequence.h"
#include "ssta/sensors/attitude_filter.h"
#include "ssta_test_paths.h"

namespace ssta {
namespace {

constexpr double kDeg = M_PI / 180.0;

// Body attitude over time: roll and pitch swing (as on rough ground) while yawing slowly.
Eigen::Quaterniond TrueAttitude(double t) {
  const double roll = 8 * kDeg * std::sin(0.7 * t), pitch = 5 * kDeg * std::sin(1.1 * t + 0.3), yaw = 0.2 * t;
  return Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
         Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX());
}

// A 200 Hz IMU on that body (IMU = body frame), no translation: specific force is gravity's
// reaction; gyro = body rate + bias.
std::vector<ImuSample> SimulateImu(double seconds, const Eigen::Vector3d& gyro_bias) {
  std::vector<ImuSample> out;
  const double dt = 0.005;
  for (int i = 0; i * dt <= seconds; ++i) {
    const double t = i * dt;
    const Eigen::Quaterniond q0 = TrueAttitude(t - 1e-4), q1 = TrueAttitude(t + 1e-4);
    const Eigen::AngleAxisd delta(q0.conjugate() * q1);
    ImuSample s;
    s.timestamp_ns = static_cast<std::int64_t>(std::llround(t * 1e9));
    s.angular_rate = delta.axis() * delta.angle() / 2e-4 + gyro_bias;
    s.specific_force = TrueAttitude(t).conjugate() * Eigen::Vector3d(0, 0, 9.81);
    out.push_back(s);
  }
  return out;
}

double UpErrorDeg(const GravityTrack& track, double t) {
  const Eigen::Vector3d truth = TrueAttitude(t).conjugate() * Eigen::Vector3d::UnitZ();
  const auto up = track.UpInBodyAt(static_cast<std::int64_t>(t * 1e9));
  return std::acos(std::clamp(up->dot(truth), -1.0, 1.0)) / kDeg;
}

TEST(GravityTrack, FollowsRollAndPitchDespiteAGyroBias) {
  const auto imu = SimulateImu(60.0, Eigen::Vector3d(0.01, -0.008, 0.005));  // ~0.5 deg/s bias
  const GravityTrack track(imu, Eigen::Isometry3d::Identity(), AttitudeFilterOptions{});
  double worst = 0;
  for (double t = 20; t < 60; t += 0.37) worst = std::max(worst, UpErrorDeg(track, t));
  EXPECT_LT(worst, 0.5);
}

TEST(GravityTrack, GyroAloneDriftsWhichIsWhyTheAccelerometerIsUsed) {
  const auto imu = SimulateImu(60.0, Eigen::Vector3d(0.01, -0.008, 0.005));
  AttitudeFilterOptions gyro_only;
  gyro_only.kp = 0;
  gyro_only.ki = 0;
  const GravityTrack drifting(imu, Eigen::Isometry3d::Identity(), gyro_only);
  const GravityTrack filtered(imu, Eigen::Isometry3d::Identity(), AttitudeFilterOptions{});
  double worst_drifting = 0, worst_filtered = 0;
  for (double t = 20; t < 60; t += 0.37) {
    worst_drifting = std::max(worst_drifting, UpErrorDeg(drifting, t));
    worst_filtered = std::max(worst_filtered, UpErrorDeg(filtered, t));
  }
  EXPECT_GT(worst_drifting, 1.0);
  EXPECT_GT(worst_drifting, 5 * worst_filtered);
}

// An IMU standing still, tilted by `attitude`, with a gyro bias; rotating about the body's x axis
// at `start_rate` for the first 0.3 s when that is not zero.
std::vector<ImuSample> SimulateStandingImu(double seconds, const Eigen::Quaterniond& attitude, const Eigen::Vector3d& gyro_bias,
                                           double start_rate = 0.0) {
  std::vector<ImuSample> out;
  const double dt = 0.005;
  for (int i = 0; i * dt <= seconds; ++i) {
    const double t = i * dt;
    const double turned = start_rate * std::min(t, 0.3);
    const Eigen::Quaterniond q = attitude * Eigen::AngleAxisd(turned, Eigen::Vector3d::UnitX());
    ImuSample s;
    s.timestamp_ns = static_cast<std::int64_t>(std::llround(t * 1e9));
    s.angular_rate = Eigen::Vector3d(t < 0.3 ? start_rate : 0.0, 0, 0) + gyro_bias;
    s.specific_force = q.conjugate() * Eigen::Vector3d(0, 0, 9.81);
    out.push_back(s);
  }
  return out;
}

double WorstUpErrorDeg(const GravityTrack& track, const Eigen::Quaterniond& attitude, double from, double to) {
  const Eigen::Vector3d truth = attitude.conjugate() * Eigen::Vector3d::UnitZ();
  double worst = 0.0;
  for (double t = from; t < to; t += 0.05) {
    const auto up = track.UpInBodyAt(static_cast<std::int64_t>(std::llround(t * 1e9)));
    worst = std::max(worst, std::acos(std::clamp(up->dot(truth), -1.0, 1.0)) / kDeg);
  }
  return worst;
}

TEST(GravityTrack, AStartAtRestGivesTheGyroBiasAtOnce) {
  // EuRoC's IMU reads about 0.08 rad/s about a horizontal axis at rest. Learnt by the integral
  // term alone, up leans by up to bias / kp for seconds; taken from the first window, it does not.
  const Eigen::Quaterniond attitude(Eigen::AngleAxisd(12 * kDeg, Eigen::Vector3d(1, 2, 0).normalized()));
  const auto imu = SimulateStandingImu(30.0, attitude, Eigen::Vector3d(0.08, 0.02, 0.0));
  AttitudeFilterOptions learn_only;
  learn_only.init_gyro_bias = false;
  const double with_init = WorstUpErrorDeg(GravityTrack(imu, Eigen::Isometry3d::Identity(), {}), attitude, 0, 30);
  const double without = WorstUpErrorDeg(GravityTrack(imu, Eigen::Isometry3d::Identity(), learn_only), attitude, 0, 30);
  std::cout << "standing IMU, worst up error: " << with_init << " deg (bias learnt only: " << without << " deg)\n";
  EXPECT_LT(with_init, 0.05);
  EXPECT_GT(without, 2.0);
}

TEST(GravityTrack, AStartThatTiltsGivesNoBias) {
  // Turning about a horizontal axis at 0.3 rad/s during the first window: the accelerometer
  // shows it, so the rate is not taken as bias and the track equals the one without the option.
  const Eigen::Quaterniond attitude = Eigen::Quaterniond::Identity();
  const auto imu = SimulateStandingImu(5.0, attitude, Eigen::Vector3d(0.0, 0.02, 0.0), 0.3);
  AttitudeFilterOptions learn_only;
  learn_only.init_gyro_bias = false;
  const GravityTrack a(imu, Eigen::Isometry3d::Identity(), {});
  const GravityTrack b(imu, Eigen::Isometry3d::Identity(), learn_only);
  for (double t = 0.0; t < 5.0; t += 0.25) {
    const auto ta = static_cast<std::int64_t>(std::llround(t * 1e9));
    EXPECT_LT((*a.UpInBodyAt(ta) - *b.UpInBodyAt(ta)).norm(), 1e-12) << t;
  }
}

TEST(GravityTrack, EurocStandingStillKeepsUpWithTheAccelerometer) {
  // The EuRoC excerpt stands on the floor (rotors turning: |a| and the rates vibrate). Up from
  // the filter at every image time stays with the mean accelerometer direction; learning the
  // gyro bias (0.08 rad/s about a horizontal axis) with the integral term alone, it leaned.
  const Sequence seq = Sequence::Open(std::string(SSTA_TEST_DATA_DIR) + "/euroc-v1-01-mini");
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const ImuSample& s : seq.imu()) mean += s.specific_force;
  const Eigen::Vector3d up_imu = mean.normalized();
  AttitudeFilterOptions learn_only;
  learn_only.init_gyro_bias = false;
  double worst = 0.0, worst_learning = 0.0;
  const GravityTrack track(seq.imu(), Eigen::Isometry3d::Identity(), {});
  const GravityTrack learning(seq.imu(), Eigen::Isometry3d::Identity(), learn_only);
  for (const StereoFrame& frame : seq.frames()) {
    worst = std::max(worst, std::acos(std::clamp(track.UpInBodyAt(frame.timestamp_ns)->dot(up_imu), -1.0, 1.0)) / kDeg);
    worst_learning = std::max(
        worst_learning, std::acos(std::clamp(learning.UpInBodyAt(frame.timestamp_ns)->dot(up_imu), -1.0, 1.0)) / kDeg);
  }
  std::cout << "EuRoC up against the mean accelerometer: " << worst << " deg (bias learnt only: " << worst_learning
            << " deg)\n";
  EXPECT_LT(worst, 0.6);  // measured 0.34 deg (vibration in the first window)
  EXPECT_GT(worst_learning, 1.5);  // measured 2.2 deg
}

TEST(GravityTrack, OutsideTheImuTimeRangeThereIsNoAnswer) {
  const GravityTrack track(SimulateImu(1.0, Eigen::Vector3d::Zero()), Eigen::Isometry3d::Identity(), {});
  EXPECT_FALSE(track.UpInBodyAt(-1).has_value());
  EXPECT_FALSE(track.UpInBodyAt(2'000'000'000).has_value());
  EXPECT_TRUE(track.UpInBodyAt(500'000'000).has_value());
}

TEST(CorrectRollPitch, KeepsPositionAndYawAndTakesRollPitchFromUp) {
  const Eigen::Quaterniond truth = TrueAttitude(2.0);
  Eigen::Isometry3d drifted = Eigen::Isometry3d::Identity();
  // Odometry with 3 degrees of extra roll and pitch but the right yaw and position.
  drifted.linear() = (truth * Eigen::AngleAxisd(3 * kDeg, Eigen::Vector3d::UnitX()) *
                      Eigen::AngleAxisd(3 * kDeg, Eigen::Vector3d::UnitY())).toRotationMatrix();
  const Eigen::Matrix3d d = drifted.linear();
  // Give the drifted pose exactly the true yaw (Z-Y-X), as odometry would.
  const double true_yaw = 0.4;
  drifted.linear() = Eigen::AngleAxisd(true_yaw - std::atan2(d(1, 0), d(0, 0)), Eigen::Vector3d::UnitZ()) * d;
  drifted.translation() = Eigen::Vector3d(1, 2, 3);
  const Eigen::Vector3d up_body = truth.conjugate() * Eigen::Vector3d::UnitZ();
  const Eigen::Isometry3d fixed = CorrectRollPitch(drifted, up_body);
  EXPECT_TRUE(fixed.translation().isApprox(Eigen::Vector3d(1, 2, 3)));
  EXPECT_TRUE((fixed.linear().transpose() * Eigen::Vector3d::UnitZ()).isApprox(up_body, 1e-9));
  EXPECT_NEAR(std::atan2(fixed.linear()(1, 0), fixed.linear()(0, 0)), true_yaw, 1e-9);
}

std::vector<ImuSample> ScaleAccelerometer(std::vector<ImuSample> imu, double scale) {
  for (ImuSample& s : imu) s.specific_force *= scale;
  return imu;
}

std::string ErrorOf(const std::vector<ImuSample>& imu, const AttitudeFilterOptions& options) {
  try {
    const GravityTrack track(imu, Eigen::Isometry3d::Identity(), options, "seq/imu0/data.csv");
    (void)track;
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(GravityTrack, AnImuAtRestReadingGInsteadOfMetresPerSecondSquaredIsAnError) {
  const std::string m = ErrorOf(ScaleAccelerometer(SimulateImu(1.0, Eigen::Vector3d::Zero()), 1.0 / 9.81), {});
  EXPECT_EQ(m.rfind("seq/imu0/data.csv: the IMU at rest reads 1 m/s^2", 0), 0u) << m;
  EXPECT_NE(m.find("attitude.max_rest_gravity_error_mps2 = 0.5"), std::string::npos) << m;
}

TEST(GravityTrack, TheRestGravityThresholdIsConfigurable) {
  // 6 % scale error: 0.59 m/s^2 off.
  const auto imu = ScaleAccelerometer(SimulateImu(1.0, Eigen::Vector3d::Zero()), 1.06);
  EXPECT_NE(ErrorOf(imu, {}), "");
  AttitudeFilterOptions lenient;
  lenient.max_rest_gravity_error_mps2 = 0.7;
  EXPECT_EQ(ErrorOf(imu, lenient), "");
  // 4 % is within the default.
  EXPECT_EQ(ErrorOf(ScaleAccelerometer(SimulateImu(1.0, Eigen::Vector3d::Zero()), 1.04), {}), "");
}

TEST(GravityTrack, AStartThatIsNotAtRestIsNotJudged) {
  // Shaking hard over the initial window (|a| swings by far more than 10 %): not at rest, so
  // the mean is no measure of gravity and no error is raised.
  auto imu = SimulateImu(1.0, Eigen::Vector3d::Zero());
  for (std::size_t i = 0; i < imu.size(); ++i) imu[i].specific_force *= (i % 2 == 0 ? 0.5 : 1.2);
  EXPECT_EQ(ErrorOf(imu, {}), "");
  // Spinning fast (2 rad/s) is not at rest either.
  auto spinning = ScaleAccelerometer(SimulateImu(1.0, Eigen::Vector3d::Zero()), 0.5);
  for (ImuSample& s : spinning) s.angular_rate += Eigen::Vector3d(0, 0, 2.0);
  EXPECT_EQ(ErrorOf(spinning, {}), "");
}

}  // namespace
}  // namespace ssta
