// MountRefiner on analytic worlds: ground points on known planes seen through a mount with a
// known error, so the correction, its sign convention and the degenerate cases are exact.

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <optional>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "ssta/core/error.h"
#include "ssta/mount/ground_evidence.h"
#include "ssta/mount/mount_refiner.h"
#include "ssta/mount/online_mount_refiner.h"

namespace ssta {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;
constexpr double kTwoPi = 2.0 * 3.14159265358979323846;

/// A camera 0.6 m above the body origin, 0.2 m ahead, looking forward and pitched down 15 deg.
Eigen::Isometry3d TrueMount() {
  Eigen::Matrix3d body_R_level;  // camera x right, y down, z forward -> body x fwd, y left, z up
  body_R_level << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  Eigen::Isometry3d mount = Eigen::Isometry3d::Identity();
  mount.linear() = Eigen::AngleAxisd(15 * kDeg, Eigen::Vector3d::UnitY()).toRotationMatrix() * body_R_level;
  mount.translation() = Eigen::Vector3d(0.2, 0.06, 0.6);
  return mount;
}

/// The mount as a calibration file with an error would have it: rotated about body y by
/// `pitch_deg`, then about body x by `roll_deg` (as `ssta synth` injects it).
Eigen::Isometry3d WrongMount(double pitch_deg, double roll_deg) {
  Eigen::Isometry3d m = TrueMount();
  m.linear() = (Eigen::AngleAxisd(pitch_deg * kDeg, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(roll_deg * kDeg, Eigen::Vector3d::UnitX())).toRotationMatrix() *
               m.linear();
  return m;
}

/// One frame: ground points on the plane z_body = -body_height tilted by `tilt_deg` about body x
/// (terrain), 1 to 7 m ahead, with Gaussian noise and a share of gross outliers, in the camera
/// frame of the TRUE mount.
GroundEvidence Frame(std::mt19937& rng, double tilt_deg, double noise_m, double outlier_share, double body_height) {
  std::uniform_real_distribution<double> ahead(1.0, 7.0), side(-2.0, 2.0), unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, noise_m);
  const Eigen::Matrix3d tilt = Eigen::AngleAxisd(tilt_deg * kDeg, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const Eigen::Isometry3d camera_T_body = TrueMount().inverse();
  GroundEvidence e;
  e.usable = true;
  for (int i = 0; i < 300; ++i) {
    Eigen::Vector3d p_body = tilt * Eigen::Vector3d(ahead(rng), side(rng), 0.0) - Eigen::Vector3d(0, 0, body_height);
    p_body.z() += noise(rng) + (unit(rng) < outlier_share ? 0.3 + 0.5 * unit(rng) : 0.0);
    e.camera_points.push_back(camera_T_body * p_body);
  }
  return e;
}

double AngleDeg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle() / kDeg;
}

MountRefinementResult SolveFrames(const RefinementOptions& options, const Eigen::Isometry3d& configured, int frames,
                                  double outlier_share = 0.0, double body_height = 0.4, double terrain_deg = 0.5) {
  std::mt19937 rng(7);
  std::normal_distribution<double> terrain(0.0, terrain_deg);
  MountRefiner refiner(options, configured);
  for (int i = 0; i < frames; ++i) refiner.AddFrame(Frame(rng, terrain(rng), 0.02, outlier_share, body_height));
  return refiner.Solve();
}

TEST(MountRefiner, RecoversPitchAndRollOnAnalyticGround) {
  RefinementOptions options;
  const MountRefinementResult r = SolveFrames(options, WrongMount(3.0, 1.5), 30);
  ASSERT_EQ(r.status, RefinementStatus::kDetermined) << r.message;
  EXPECT_LT(AngleDeg(TrueMount().linear(), r.body_T_camera_refined.linear()), 0.3) << r.BriefReport();
  // The correction undoes the error: about -3 deg about body y and -1.5 deg about body x.
  EXPECT_NEAR(r.pitch_correction_deg, -3.0, 0.3);
  EXPECT_NEAR(r.roll_correction_deg, -1.5, 0.3);
  // The terrain tilts about body x only, by 0.5 deg (1 sigma) from frame to frame: the measured
  // scatter, not the 1 deg prior, sets the statistical part of the sigma. Roll: 0.5 / sqrt(30)
  // = 0.09 deg and the systematic term in quadrature; pitch: the systematic term and little more.
  const double systematic = options.systematic_sigma_deg;
  EXPECT_NEAR(r.tilt_scatter_axes_deg[0], 0.5, 0.15);
  EXPECT_LT(r.tilt_scatter_axes_deg[1], 0.1);
  EXPECT_NEAR(std::sqrt(r.roll_sigma_deg * r.roll_sigma_deg - systematic * systematic), 0.09, 0.04);
  EXPECT_GE(r.pitch_sigma_deg, systematic);
  EXPECT_LT(r.pitch_sigma_deg, std::hypot(0.05, systematic));
  EXPECT_EQ(r.frames_used, 30);
  EXPECT_EQ(r.points_used, 30 * 300);
  EXPECT_NEAR(r.residual_rms_m, 0.02, 0.005);
  EXPECT_DOUBLE_EQ(r.height_correction_m, 0.0);
  EXPECT_TRUE(r.body_T_camera_refined.translation().isApprox(TrueMount().translation()));
}

TEST(MountRefiner, RobustLossesIgnoreGrossOutliers) {
  for (RobustLoss loss : {RobustLoss::kHuber, RobustLoss::kCauchy}) {
    RefinementOptions options;
    options.robust_loss = loss;
    const MountRefinementResult r = SolveFrames(options, WrongMount(3.0, 1.5), 30, 0.15);
    ASSERT_TRUE(r.applied()) << r.message;
    EXPECT_LT(AngleDeg(TrueMount().linear(), r.body_T_camera_refined.linear()), 0.3) << RobustLossName(loss);
    // About 15 % of the points are 0.3-0.8 m off the ground.
    EXPECT_GT(r.outlier_points, 0.12 * r.points_used) << RobustLossName(loss);
    EXPECT_LT(r.outlier_points, 0.20 * r.points_used) << RobustLossName(loss);
    EXPECT_LT(r.residual_median_m, 0.03);
  }
}

TEST(MountRefiner, EstimatesCameraHeightWhenTheBodyHeightIsKnown) {
  RefinementOptions options;
  options.body_height_m = 0.4;
  options.estimate_height = true;
  Eigen::Isometry3d configured = WrongMount(-2.0, 1.0);
  configured.translation().z() += 0.05;  // the drawing says 5 cm too high
  const MountRefinementResult r = SolveFrames(options, configured, 30);
  ASSERT_TRUE(r.applied()) << r.message;
  EXPECT_NEAR(r.height_correction_m, -0.05, 0.02);
  EXPECT_GT(r.height_sigma_m, 0.0);
  EXPECT_LT(r.height_sigma_m, 0.02);
  EXPECT_NEAR(r.body_T_camera_refined.translation().z(), 0.6, 0.02);
  EXPECT_LT(AngleDeg(TrueMount().linear(), r.body_T_camera_refined.linear()), 0.3);
}

TEST(MountRefiner, TooFewFramesIsNotDetermined) {
  RefinementOptions options;
  options.min_frames = 5;
  const Eigen::Isometry3d configured = WrongMount(3.0, 0.0);
  const MountRefinementResult r = SolveFrames(options, configured, 4);
  EXPECT_EQ(r.status, RefinementStatus::kTooFewFrames);
  EXPECT_FALSE(r.applied());
  EXPECT_NE(r.message.find("not determined"), std::string::npos) << r.message;
  EXPECT_TRUE(r.body_T_camera_refined.isApprox(configured));
  EXPECT_TRUE(std::isnan(r.pitch_sigma_deg));
}

TEST(MountRefiner, TightPriorIsNotBetterDetermined) {
  RefinementOptions options;
  options.prior_sigma_deg = 0.01;
  const Eigen::Isometry3d configured = WrongMount(3.0, 1.5);
  const MountRefinementResult r = SolveFrames(options, configured, 30);
  EXPECT_EQ(r.status, RefinementStatus::kNotBetterThanPrior) << r.message;
  EXPECT_FALSE(r.applied());
  EXPECT_NE(r.message.find("not better determined than its prior"), std::string::npos);
  EXPECT_TRUE(r.body_T_camera_refined.isApprox(configured));
  // The prior dominates: the posterior sigma, less the systematic term, is close to the prior's.
  const double statistical = std::sqrt(r.pitch_sigma_deg * r.pitch_sigma_deg -
                                       options.systematic_sigma_deg * options.systematic_sigma_deg);
  EXPECT_GT(statistical, 0.9 * options.prior_sigma_deg);
  // Held at zero, the correction leaves every frame the same tilt: fully correlated frames.
  EXPECT_LE(statistical, options.prior_sigma_deg * r.sigma_inflation * 1.0001);
}

TEST(MountRefiner, GroundRougherThanTheTiltPriorIsNotApplied) {
  // The ground ahead tilts by 4 deg (1 sigma) from frame to frame; the model allows 1 deg.
  RefinementOptions options;
  const Eigen::Isometry3d configured = WrongMount(3.0, 1.5);
  const MountRefinementResult r = SolveFrames(options, configured, 30, 0.0, 0.4, 4.0);
  EXPECT_EQ(r.status, RefinementStatus::kTerrainTooRough) << r.BriefReport();
  EXPECT_GT(r.tilt_scatter_deg, options.terrain_tilt_sigma_deg);
  EXPECT_NE(r.message.find("not flat enough"), std::string::npos) << r.message;
  EXPECT_TRUE(r.body_T_camera_refined.isApprox(configured));
  // Told that the terrain is that rough, the same data is accepted, with a wider sigma.
  options.terrain_tilt_sigma_deg = 6.0;
  const MountRefinementResult wide = SolveFrames(options, configured, 30, 0.0, 0.4, 4.0);
  EXPECT_EQ(wide.status, RefinementStatus::kDetermined) << wide.BriefReport();
  EXPECT_GT(wide.roll_sigma_deg, 0.5);  // 4 / sqrt(30) = 0.73
  EXPECT_LT(wide.tilt_scatter_deg, options.terrain_tilt_sigma_deg);
}

TEST(MountRefiner, GravityReferenceWorksInABodyFrameWhoseXIsUp) {
  // EuRoC's body (its IMU) has x up: the same world seen through body' = R * body.
  const Eigen::Matrix3d body2_R_body = Eigen::AngleAxisd(0.5 * 3.14159265358979323846, Eigen::Vector3d::UnitY())
                                           .toRotationMatrix();
  ASSERT_TRUE((body2_R_body * Eigen::Vector3d::UnitZ()).isApprox(Eigen::Vector3d::UnitX()));
  auto in_body2 = [&](Eigen::Isometry3d m) {
    m.linear() = body2_R_body * m.linear();
    m.translation() = body2_R_body * m.translation();
    return m;
  };
  RefinementOptions options;
  options.ground_reference = GroundReference::kGravity;
  MountRefiner refiner(options, in_body2(WrongMount(3.0, 1.5)));
  std::mt19937 rng(11);
  for (int i = 0; i < 30; ++i) {
    GroundEvidence e = Frame(rng, 0.0, 0.02, 0.0, 0.4);
    e.up_body = body2_R_body * Eigen::Vector3d::UnitZ();
    refiner.AddFrame(e);
  }
  const MountRefinementResult r = refiner.Solve();
  ASSERT_TRUE(r.applied()) << r.BriefReport();
  EXPECT_LT(AngleDeg(in_body2(TrueMount()).linear(), r.body_T_camera_refined.linear()), 0.3) << r.BriefReport();
}

TEST(MountRefiner, SlidingWindowDropsTheOldestFrame) {
  RefinementOptions options;
  MountRefiner refiner(options, WrongMount(1.0, 0.0));
  std::mt19937 rng(3);
  for (int i = 0; i < 6; ++i) refiner.AddFrame(Frame(rng, 0.0, 0.02, 0.0, 0.4));
  refiner.DropOldest();
  EXPECT_EQ(refiner.NumFrames(), 5);
  const MountRefinementResult r = refiner.Solve();
  EXPECT_EQ(r.frames_used, 5);
  EXPECT_TRUE(r.applied()) << r.message;
  EXPECT_NEAR(r.pitch_correction_deg, -1.0, 0.3);
}

TEST(MountRefiner, AFewFramesOnASlopeOfTheirOwnDoNotPullTheEstimate) {
  // 30 frames on nearly level ground (0.3 deg of roll scatter) and 3 frames whose ground ahead
  // is a 10 deg slope: with the tilt prior alone they would pull the roll by about 1 deg.
  RefinementOptions options;
  const Eigen::Isometry3d configured = WrongMount(3.0, 1.5);
  std::mt19937 rng(21);
  std::normal_distribution<double> terrain(0.0, 0.3);
  MountRefiner refiner(options, configured);
  for (int i = 0; i < 33; ++i) {
    GroundEvidence e = Frame(rng, i % 11 == 5 ? 10.0 : terrain(rng), 0.02, 0.0, 0.4);
    e.timestamp_ns = i;
    refiner.AddFrame(std::move(e));
  }
  const MountRefinementResult r = refiner.Solve();
  ASSERT_TRUE(r.applied()) << r.BriefReport();
  const double error_deg = AngleDeg(TrueMount().linear(), r.body_T_camera_refined.linear());
  EXPECT_LT(error_deg, 0.2) << r.BriefReport();
  EXPECT_LT(error_deg, 2.0 * std::max(r.pitch_sigma_deg, r.roll_sigma_deg)) << r.BriefReport();
  EXPECT_GE(r.frames_downweighted, 3) << r.BriefReport();
  EXPECT_LE(r.frames_downweighted, 6) << r.BriefReport();
  for (int i : {5, 16, 27}) EXPECT_LT(r.frames[static_cast<std::size_t>(i)].weight, 0.05) << i;
  EXPECT_GT(r.frames[0].weight, 0.5);
  // The slope frames stay out of the measured scatter, which stays that of the level frames.
  EXPECT_NEAR(r.tilt_scatter_axes_deg[0], 0.3, 0.12);
  EXPECT_NE(r.Json().find("\"frames_downweighted\": "), std::string::npos);
}

/// Rolling ground: a long swell along the drive and a side slope that comes and goes [m].
double RollingHeight(double x, double y) {
  return 0.25 * std::sin(kTwoPi * x / 9.0) + 0.06 * y * std::sin(kTwoPi * x / 5.0 + 1.0);
}

/// The body standing on the ground `height` at x = s (heading +x): the plane through its four
/// wheel contacts (wheelbase 0.6 m, track 0.5 m), its origin 0.4 m above them.
Eigen::Isometry3d BodyOnRollingGround(double s, double (*height)(double, double) = RollingHeight) {
  const double hx = 0.3, hy = 0.25;
  const double fl = height(s + hx, hy), fr = height(s + hx, -hy);
  const double rl = height(s - hx, hy), rr = height(s - hx, -hy);
  const double slope_x = ((fl + fr) - (rl + rr)) / (4 * hx), slope_y = ((fl + rl) - (fr + rr)) / (4 * hy);
  const Eigen::Vector3d up = Eigen::Vector3d(-slope_x, -slope_y, 1.0).normalized();
  const Eigen::Vector3d x_axis = (Eigen::Vector3d::UnitX() - up.x() * up).normalized();
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear().col(0) = x_axis;
  pose.linear().col(1) = up.cross(x_axis);
  pose.linear().col(2) = up;
  pose.translation() = Eigen::Vector3d(s, 0.0, 0.25 * (fl + fr + rl + rr)) + 0.4 * up;
  return pose;
}

/// A drive of `frames` frames 0.1 m apart over the rolling ground, seen through the true mount
/// and calibrated with `configured` and `options`: each frame's ground points 1-7 m ahead
/// (2 cm noise); with the path reference only those a later body stands on, as calibrate-mount
/// keeps them.
MountRefinementResult SolveRollingDrive(const RefinementOptions& options, const Eigen::Isometry3d& configured,
                                        int frames) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> ahead(1.0, 7.0), side(-2.0, 2.0);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::vector<std::optional<Eigen::Isometry3d>> poses;
  for (int i = 0; i < frames; ++i) poses.push_back(BodyOnRollingGround(0.1 * i));
  std::vector<GroundEvidence> evidence;
  for (int i = 0; i < frames; ++i) {
    const Eigen::Isometry3d camera_T_world = (*poses[i] * TrueMount()).inverse();
    GroundEvidence e;
    e.timestamp_ns = i;
    e.usable = true;
    for (int k = 0; k < 2400; ++k) {
      const double x = poses[i]->translation().x() + ahead(rng), y = side(rng);
      e.camera_points.push_back(camera_T_world * Eigen::Vector3d(x, y, RollingHeight(x, y) + noise(rng)));
    }
    evidence.push_back(std::move(e));
  }
  if (options.ground_reference == GroundReference::kPath) return SolveAlongPath(options, configured, poses, evidence);
  MountRefiner refiner(options, configured);
  for (GroundEvidence& e : evidence) {
    e.camera_points.resize(static_cast<std::size_t>(options.points_per_frame));
    refiner.AddFrame(std::move(e));
  }
  return refiner.Solve();
}

TEST(MountRefiner, PathReferenceRecoversTheMountOnRollingGround) {
  RefinementOptions options;
  ASSERT_EQ(options.ground_reference, GroundReference::kPath);
  // The frames look at the swell ahead, which leans about 11 deg from their bodies' z on
  // average. Measured: 0.04-0.07 deg off from every error below; 0.16-0.47 deg when the
  // correction turns about axes perpendicular to that mean and one plane per frame is fitted
  // over the bend.
  double error_deg = 0.0;
  for (const auto& [pitch, roll] : {std::pair{3.0, 1.5}, {-3.0, -1.5}, {0.0, 1.5}, {1.0, 0.0}}) {
    SCOPED_TRACE(std::to_string(pitch) + " / " + std::to_string(roll) + " deg injected");
    const MountRefinementResult r = SolveRollingDrive(options, WrongMount(pitch, roll), 40);
    ASSERT_TRUE(r.applied()) << r.BriefReport();
    EXPECT_EQ(r.reference, "path");
    EXPECT_GE(r.frames_used, 15);
    const double error = AngleDeg(TrueMount().linear(), r.body_T_camera_refined.linear());
    std::cout << "rolling ground, path reference, " << pitch << " / " << roll << " deg injected: " << error
              << " deg off, sigma pitch " << r.pitch_sigma_deg << " roll " << r.roll_sigma_deg << " deg\n";
    EXPECT_LT(error, 0.1) << r.BriefReport();
    EXPECT_LT(error, std::hypot(r.pitch_sigma_deg, r.roll_sigma_deg)) << r.BriefReport();
    EXPECT_LT(std::max(r.pitch_sigma_deg, r.roll_sigma_deg), 0.3) << r.BriefReport();
    error_deg = std::max(error_deg, error);
  }
  const Eigen::Isometry3d configured = WrongMount(3.0, 1.5);

  // The ground ahead against the plane under the wheels now is wrong by far more here.
  options.ground_reference = GroundReference::kBody;
  options.terrain_tilt_sigma_deg = 10.0;  // let it answer
  const MountRefinementResult body = SolveRollingDrive(options, configured, 40);
  const double body_error_deg = AngleDeg(TrueMount().linear(), body.body_T_camera_refined.linear());
  std::cout << "rolling ground, body reference: " << body_error_deg << " deg off\n";
  EXPECT_GT(body_error_deg, 5.0 * error_deg) << body.BriefReport();
}

/// The rolling ground's swell, curving across the way as well (0.3 per m) [m].
double SaggingHeight(double x, double y) {
  return 0.25 * std::sin(kTwoPi * x / 9.0) + 0.15 * y * y;
}

/// The normal of z = a + b x + c y fitted (least squares) to `points` [body frame].
Eigen::Vector3d FittedPlaneNormal(const std::vector<Eigen::Vector3d>& points) {
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : points) {
    const Eigen::Vector3d row(1.0, p.x(), p.y());
    normal += row * row.transpose();
    rhs += row * p.z();
  }
  const Eigen::Vector3d abc = normal.ldlt().solve(rhs);
  return Eigen::Vector3d(-abc[1], -abc[2], 1.0).normalized();
}

/// The swell and the curvature across of SaggingHeight, with a side slope that turns along the
/// way: 0.1 sin(2 pi x / 5 + 1) per m, a twist of up to 0.13 per m [m].
double TwistingHeight(double x, double y) {
  return SaggingHeight(x, y) + 0.1 * y * std::sin(kTwoPi * x / 5.0 + 1.0);
}

/// Frame `frame` of a drive over `height` (61 bodies 0.1 m apart) sees the ground 1-5 m ahead
/// that later bodies stand on, on a grid that does not line up with them, more of it to the
/// right than to the left as a camera's view is (`left_m` = 0.35) or as much to either side
/// (0.55): how far, in degrees, the plane DrivenOverGround expects there (with `options`) is
/// from the plane the ground points themselves fit.
double ExpectedPlaneErrorDeg(double (*height)(double, double), const RefinementOptions& options, int frame = 0,
                             double left_m = 0.35) {
  std::vector<std::optional<Eigen::Isometry3d>> poses;
  for (int i = 0; i <= 60; ++i) poses.push_back(BodyOnRollingGround(0.1 * i, height));
  const Eigen::Isometry3d camera_T_world = (*poses[static_cast<std::size_t>(frame)] * TrueMount()).inverse();
  const DrivenOverGround driven(poses, static_cast<std::size_t>(frame), TrueMount(), options);
  std::vector<Eigen::Vector3d> kept, in_body;
  for (double x = 0.1 * frame + 1.0; x <= 0.1 * frame + 5.0; x += 0.0173) {
    for (double y = -0.55; y <= left_m; y += 0.0483) {
      const Eigen::Vector3d p = camera_T_world * Eigen::Vector3d(x, y, height(x, y));
      if (!driven.Contains(p)) continue;
      kept.push_back(p);
      in_body.push_back(TrueMount() * p);
    }
  }
  EXPECT_GT(kept.size(), 500u);
  const Eigen::Vector3d expected = driven.ExpectedUp(kept), truth = FittedPlaneNormal(in_body);
  return std::atan2(expected.cross(truth).norm(), expected.dot(truth)) / kDeg;
}

TEST(DrivenOverGround, TheExpectedGroundSagsBelowTheChordsTheWheelsSpan) {
  // Each body's wheel plane is the chord through its contacts; the ground between them lies
  // (curvature / 2) (half span^2 - offset^2) below it, along the way (where the swell's
  // curvature changes from body to body) and across it.
  RefinementOptions options;  // wheelbase 0.6 m and track 0.5 m, as the bodies of the drive
  const double error_deg = ExpectedPlaneErrorDeg(SaggingHeight, options);
  std::cout << "expected ground with the chords' sag: " << error_deg << " deg off the ground's plane\n";
  EXPECT_LT(error_deg, 0.02);

  // Each sag alone leaves the other's tilt; neither: the wheel planes taken for the ground.
  for (const auto& [wheelbase, track] : {std::pair{0.0, 0.5}, {0.6, 0.0}, {0.0, 0.0}}) {
    options.wheelbase_m = wheelbase;
    options.track_m = track;
    const double off_deg = ExpectedPlaneErrorDeg(SaggingHeight, options);
    std::cout << "wheelbase " << wheelbase << " m, track " << track << " m: " << off_deg << " deg off\n";
    EXPECT_GT(off_deg, 10.0 * error_deg) << wheelbase << " / " << track;  // measured 0.08-1.98 deg
  }
}

TEST(DrivenOverGround, TheExpectedGroundTwistsWhereTheSideSlopeTurns) {
  // Four contacts span a plane whose side slope is the mean of the front and the rear axle's;
  // where the side slope turns along the way the ground leaves it by twist * x * y, and where
  // the twist itself changes, by twist' y (x^2 - wheelbase^2 / 4) / 2. Frames along the drive,
  // the last ones seeing only its end, where the points lie ahead of the last body's centre.
  // Measured: 0.011-0.031 deg; 0.017-0.168 deg with neither term (the wheel planes' sag alone).
  for (int frame : {0, 10, 20, 30, 40, 45}) {
    const double error_deg = ExpectedPlaneErrorDeg(TwistingHeight, RefinementOptions{}, frame, 0.55);
    std::cout << "twisting ground, frame " << frame << ": " << error_deg << " deg off the ground's plane\n";
    EXPECT_LT(error_deg, 0.045) << frame;
  }
}

TEST(MountRefiner, ReportsAndJsonCarryTheEstimate) {
  const MountRefinementResult r = SolveFrames(RefinementOptions{}, WrongMount(3.0, 1.5), 10);
  const std::string report = r.BriefReport();
  EXPECT_NE(report.find("pitch correction"), std::string::npos) << report;
  const std::string json = r.Json();
  for (const char* key : {"\"status\": \"determined\"", "\"pitch_sigma_deg\"", "\"roll_correction_deg\"",
                          "\"body_T_camera_refined\"", "\"outlier_points\"", "\"frames\""}) {
    EXPECT_NE(json.find(key), std::string::npos) << key << "\n" << json;
  }
}

TEST(RefinementOptions, MessagesNameTheKey) {
  std::string error;
  EXPECT_TRUE(RefinementOptions{}.IsValid(&error)) << error;
  RefinementOptions o;
  o.prior_sigma_deg = 0.0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error.rfind("prior_sigma_deg:", 0), 0u) << error;
  o = RefinementOptions{};
  o.estimate_height = true;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error.rfind("estimate_height:", 0), 0u) << error;
  o = RefinementOptions{};
  o.max_sigma_ratio = 1.0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error.rfind("max_sigma_ratio:", 0), 0u) << error;
  try {
    MountRefiner refiner(o, TrueMount());
    FAIL() << "invalid options accepted";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("refinement.max_sigma_ratio:", 0), 0u) << e.what();
  }
  o = RefinementOptions{};
  o.window_frames = o.min_frames - 1;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error.rfind("window_frames:", 0), 0u) << error;
  o = RefinementOptions{};
  o.solve_every_frames = 0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error.rfind("solve_every_frames:", 0), 0u) << error;
  EXPECT_THROW(ParseRobustLoss("l2"), Error);
  EXPECT_EQ(ParseGroundReference("gravity"), GroundReference::kGravity);
}

TEST(GroundEvidence, FrameWithoutGroundPlaneIsSkippedWithAReason) {
  FrameResult frame;
  frame.cloud = Image3f(4, 4, Eigen::Vector3f(0.f, 1.f, 3.f));
  frame.segment_ids = ImageI32(4, 4, 0);
  const GroundEvidence none = ExtractGroundEvidence(frame, Eigen::Matrix3d::Identity(), Eigen::Vector3d::UnitZ(),
                                                    RefinementOptions{});
  EXPECT_FALSE(none.usable);
  EXPECT_EQ(none.reason, "no dominant ground plane");

  frame.analysis.ground.found = true;
  frame.analysis.ground.segment_id = 0;
  frame.analysis.quality.passed = true;
  RefinementOptions options;
  options.min_points_per_frame = 20;
  options.points_per_frame = 30;
  const GroundEvidence few = ExtractGroundEvidence(frame, Eigen::Matrix3d::Identity(), Eigen::Vector3d::UnitZ(), options);
  EXPECT_FALSE(few.usable);
  EXPECT_NE(few.reason.find("fewer than min_points_per_frame"), std::string::npos) << few.reason;

  options.min_points_per_frame = 4;
  options.points_per_frame = 8;
  const Eigen::Matrix3d camera_R_rectified = Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const GroundEvidence ok = ExtractGroundEvidence(frame, camera_R_rectified, Eigen::Vector3d::UnitZ(), options);
  ASSERT_TRUE(ok.usable) << ok.reason;
  EXPECT_EQ(ok.camera_points.size(), 8u);  // 16 thinned to 8
  EXPECT_TRUE(ok.camera_points[0].isApprox(camera_R_rectified * Eigen::Vector3d(0, 1, 3)));
}

GroundEvidence NoGround(std::int64_t t) {
  GroundEvidence e;
  e.timestamp_ns = t;
  e.reason = "no dominant ground plane";
  return e;
}

TEST(OnlineMountRefiner, SolvesWhenTheWindowFirstFillsThenEveryKFramesAndAppliesTheCorrection) {
  RefinementOptions options;
  options.min_frames = 5;
  options.window_frames = 12;
  options.solve_every_frames = 4;
  const Eigen::Isometry3d configured = WrongMount(3.0, 1.5);
  OnlineMountRefiner online(options, configured, configured);
  std::mt19937 rng(11);
  std::normal_distribution<double> terrain(0.0, 0.5);
  std::vector<int> changed_at;
  for (int i = 0; i < 25; ++i) {
    GroundEvidence e = Frame(rng, terrain(rng), 0.02, 0.0, 0.4);
    e.timestamp_ns = i;
    if (online.AddFrame(std::move(e))) changed_at.push_back(i);
    // The window never holds more than window_frames frames.
    if (online.last_result()) {
      EXPECT_LE(online.last_result()->frames_used, options.window_frames);
    }
  }
  // Solves after frames 5, 9, 13, 17, 21, 25 (1-based): at indices 4, 8, ... 24.
  EXPECT_EQ(changed_at, (std::vector<int>{4, 8, 12, 16, 20, 24}));
  const OnlineRefinementSummary& s = online.summary();
  ASSERT_EQ(s.history.size(), 6u);
  EXPECT_EQ(s.history[0].frame, 5);
  EXPECT_EQ(s.history[0].timestamp_ns, 4);
  EXPECT_EQ(s.history[0].frames_used, 5);
  EXPECT_EQ(s.history[5].frames_used, 12);
  EXPECT_EQ(s.history[5].pitch_correction_deg, s.last_applied->pitch_correction_deg);
  EXPECT_EQ(s.solves, 6);
  EXPECT_EQ(s.applied, 6);
  EXPECT_EQ(s.rejected_total(), 0);
  EXPECT_EQ(s.frames_before_first_applied, 5);
  EXPECT_EQ(online.last_result()->frames_used, 12);
  ASSERT_TRUE(s.last_applied);
  EXPECT_NEAR(s.last_applied->pitch_correction_deg, -3.0, 0.4);
  EXPECT_NEAR(s.last_applied->roll_correction_deg, -1.5, 0.4);
  EXPECT_LT(AngleDeg(TrueMount().linear(), online.body_T_camera().linear()), 0.4) << s.BriefReport();
  EXPECT_TRUE(online.body_T_camera().isApprox(s.last_applied->body_T_camera_refined));
  EXPECT_NE(s.Json().find("\"applied\": 6"), std::string::npos) << s.Json();
  EXPECT_NE(s.BriefReport().find("6 solves, 6 applied, 0 rejected"), std::string::npos) << s.BriefReport();

  // Deterministic: the same frames give the same mount, bit for bit.
  OnlineMountRefiner again(options, configured, configured);
  std::mt19937 rng2(11);
  std::normal_distribution<double> terrain2(0.0, 0.5);
  for (int i = 0; i < 25; ++i) again.AddFrame(Frame(rng2, terrain2(rng2), 0.02, 0.0, 0.4));
  EXPECT_EQ(again.body_T_camera().matrix(), online.body_T_camera().matrix());
}

TEST(OnlineMountRefiner, FramesWithoutGroundPlaneAreCountedAndNeverSolvedOn) {
  RefinementOptions options;
  const Eigen::Isometry3d configured = WrongMount(3.0, 1.5);
  OnlineMountRefiner online(options, configured, configured);
  std::mt19937 rng(5);
  // Too little evidence: fewer frames with a ground plane than min_frames, among many without.
  for (int i = 0; i < 20; ++i) {
    const bool ground = i % 5 == 0;  // 4 of 20
    EXPECT_FALSE(online.AddFrame(ground ? Frame(rng, 0.0, 0.02, 0.0, 0.4) : NoGround(i)));
  }
  const OnlineRefinementSummary& s = online.summary();
  EXPECT_EQ(s.frames_offered, 20);
  EXPECT_EQ(s.frames_with_evidence, 4);
  ASSERT_EQ(s.no_evidence.size(), 16u);
  EXPECT_EQ(s.no_evidence.front().timestamp_ns, 1);
  EXPECT_EQ(s.no_evidence.front().reason, "no dominant ground plane");
  EXPECT_EQ(s.solves, 0);
  EXPECT_FALSE(online.last_result());
  EXPECT_FALSE(s.last_applied);
  EXPECT_TRUE(online.body_T_camera().isApprox(configured));
  EXPECT_NE(s.BriefReport().find("no solve: fewer frames with ground evidence than min_frames"), std::string::npos)
      << s.BriefReport();

  // The fifth frame with a ground plane fills the window: now it solves and applies.
  EXPECT_TRUE(online.AddFrame(Frame(rng, 0.0, 0.02, 0.0, 0.4)));
  EXPECT_EQ(online.summary().applied, 1);
  EXPECT_EQ(online.summary().frames_before_first_applied, 21);
}

TEST(OnlineMountRefiner, UndeterminedSolvesAreRejectedWithTheirReasonAndKeepTheMount) {
  RefinementOptions options;
  options.min_frames = 3;
  options.window_frames = 6;
  options.solve_every_frames = 3;
  options.prior_sigma_deg = 0.02;  // the data can add nothing to so tight a prior
  const Eigen::Isometry3d configured = WrongMount(3.0, 1.5);
  const Eigen::Isometry3d start = WrongMount(1.0, 0.5);  // e.g. from a resumed map
  OnlineMountRefiner online(options, configured, start);
  std::mt19937 rng(9);
  for (int i = 0; i < 9; ++i) EXPECT_FALSE(online.AddFrame(Frame(rng, 0.0, 0.02, 0.0, 0.4)));
  const OnlineRefinementSummary& s = online.summary();
  EXPECT_EQ(s.solves, 3);
  EXPECT_EQ(s.applied, 0);
  EXPECT_EQ(s.rejected[1], 3);  // not_better_than_prior
  EXPECT_EQ(s.last_rejection.rfind("not_better_than_prior: ", 0), 0u) << s.last_rejection;
  EXPECT_TRUE(online.body_T_camera().isApprox(start));
  EXPECT_NE(s.BriefReport().find("3 not_better_than_prior"), std::string::npos) << s.BriefReport();
  EXPECT_NE(s.BriefReport().find("the one the map recorded"), std::string::npos) << s.BriefReport();
  EXPECT_NE(s.Json().find("\"not_better_than_prior\": 3"), std::string::npos) << s.Json();
}

}  // namespace
}  // namespace ssta
