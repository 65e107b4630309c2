#pragma once

#include <string>

#include "ssta/core/option_fields.h"

namespace ssta {

/// Which direction the ground normal is expected along, in the body frame (YAML
/// `refinement.ground_reference`).
enum class GroundReference {
  /// "body": the vehicle rests on the ground, so the ground near it is the plane under the
  /// wheels, the body's x-y plane (normal = body z). Needs no IMU and holds on a uniform slope.
  kBody,
  /// "gravity": the ground is level in the world, so its normal in the body is up_body from the
  /// IMU-corrected pose (GravityProvider::UpInBody). Better when the body rocks on rough terrain
  /// over level ground.
  kGravity,
  /// "path": only ground that the vehicle later drives over is used, and it is expected parallel
  /// to the wheel plane of the later pose that stands on it (body z of that pose, seen from the
  /// frame's body through the sequence's poses). Holds on rolling ground, where the ground ahead
  /// is not parallel to the plane under the wheels now. Needs poses; used by the offline
  /// calibration (`ssta calibrate-mount`). Without poses, when the drive covers fewer than
  /// min_frames frames' ground, and online (build-map, whose later poses are not known yet) it
  /// acts as "body".
  kPath,
};

/// Parses "body" or "gravity"; throws ssta::Error naming `refinement.ground_reference` otherwise.
GroundReference ParseGroundReference(const std::string& name);
std::string GroundReferenceName(GroundReference reference);

/// Robust loss on the ground-point residuals (YAML `refinement.robust_loss`).
enum class RobustLoss {
  kHuber,   ///< "huber": quadratic inside loss_scale, linear outside
  kCauchy,  ///< "cauchy": log(1 + s^2); far outliers have almost no pull
};

RobustLoss ParseRobustLoss(const std::string& name);
std::string RobustLossName(RobustLoss loss);

/// YAML section `refinement`: the estimation of a correction to cam0's mount rotation (pitch
/// and roll about body axes perpendicular to up; rotation about up is unobservable from the
/// ground and held at zero) and,
/// optionally, of the camera's height, from the dominant ground planes of many frames.
/// Angles in degrees as in the config files, lengths in metres.
struct RefinementOptions {
  /// Ground points kept per frame after thinning (evenly spaced over the segment) [points].
  int points_per_frame = 300;
  /// A frame with fewer usable ground points than this is skipped [points].
  int min_points_per_frame = 50;
  /// Ground points farther than this from cam0 are not used (stereo depth error grows with the
  /// square of the range) [m].
  double max_range_m = 8.0;
  /// Fewer frames than this with a ground plane: the correction is reported "not determined".
  int min_frames = 5;
  /// Standard deviation of a ground point about its frame's plane (stereo noise + texture) up
  /// to point_sigma_range_m from cam0 [m].
  double point_sigma_m = 0.03;
  /// Beyond this range the sigma grows in proportion to the range: a disparity error moves a
  /// ground point along its ray, which grazes the ground, so its height error grows about
  /// linearly with range (depth error ~ range^2, times the grazing angle ~ 1 / range) [m].
  double point_sigma_range_m = 3.0;
  /// Robust loss on the point residuals, and where it leaves the quadratic, in multiples of
  /// each point's sigma.
  RobustLoss robust_loss = RobustLoss::kHuber;
  double loss_scale = 2.0;
  /// Expected direction of the ground normal in the body frame; see GroundReference.
  GroundReference ground_reference = GroundReference::kPath;
  /// Path reference: a ground point counts as driven over when a later pose's body has it within
  /// this far ahead or behind (along body x) [m]: about half the wheelbase.
  double path_half_length_m = 0.3;
  /// Path reference: ... and within this far to the side (along body y) [m]: about half the
  /// track, plus a margin that keeps enough points to see the roll.
  double path_half_width_m = 0.6;
  /// Path reference: front to rear wheel contacts [m]. A body's wheel plane is the chord
  /// through its contacts: where the ground curves along the way (curvature k, from how the
  /// later bodies' pitch turns over a wheelbase), the ground at x ahead of the body's centre lies
  /// k (w^2 / 4 - x^2) / 2 below that plane, and the expected ground follows it. 0: the ground is
  /// the wheel plane along the way.
  double wheelbase_m = 0.6;
  /// Path reference: left to right wheel contacts [m]. The same across the way, with the
  /// curvature across from the shape of the frame's ground points (a small mount error turns
  /// them but does not bend them). With wheelbase_m, also the twist of a side slope that turns
  /// along the way (from how the later bodies' roll turns): the four contacts' plane takes the
  /// mean of the front and the rear axle's side slope. 0: the ground is the wheel plane across
  /// the way.
  double track_m = 0.5;
  /// How far each frame's ground plane may tilt away from the reference (terrain, suspension,
  /// IMU error) [deg]: the 1-sigma of the first solve's per-frame tilt prior, and the limit on
  /// the measured scatter of the frames' tilts (larger: "terrain_too_rough").
  double terrain_tilt_sigma_deg = 1.0;
  /// The second solve weighs each frame by how its ground tilt agrees with the others: the tilt
  /// prior's sigma becomes the frames' measured tilt scatter (robust, per axis), under a Cauchy
  /// loss with this scale in those sigmas, so a frame on a slope the others do not share (a
  /// ramp, a hill's flank) pulls little [sigmas].
  double frame_loss_scale = 2.0;
  /// Floor on that measured scatter [deg]: below it the frames agree better than the disparity
  /// bias and the poses can be trusted, and a sigma from it would be overconfident.
  double min_tilt_scatter_deg = 0.05;
  /// Added in quadrature to the 1-sigma of pitch and of roll [deg]: errors that every frame
  /// shares, so no scatter shows them (a disparity bias tilts every frame's ground alike, the
  /// poses' own roll and pitch errors, ground whose plane ahead differs from the wheel plane
  /// later standing on it in the same way all along a drive). 0.2 covers the errors left on the
  /// twelve rendered tuning drives (docs/mount_calibration.md, Measured: 0.06 and 0.08 deg RMS
  /// about body x and y, 0.26 deg at most).
  /// calibrate-mount also keeps the configured mount when the body reference stands in for the
  /// path reference and the poses' body z turns more than twice this from its mean over the drive.
  double systematic_sigma_deg = 0.2;
  /// Prior on the mount correction: zero with this 1-sigma per angle [deg].
  double prior_sigma_deg = 5.0;
  /// The correction is applied only when the posterior 1-sigma of pitch and of roll is at most
  /// this fraction of prior_sigma_deg; otherwise the data added too little to the prior
  /// ("not better determined than its prior") [ratio in (0, 1)].
  double max_sigma_ratio = 0.5;
  /// Height of the body origin above the wheel-contact plane [m]; negative: unknown. When
  /// known, each frame's ground plane is expected this far below the body origin.
  double body_height_m = -1.0;
  /// 1-sigma of that per-frame ground height about body_height_m (terrain) [m].
  double terrain_height_sigma_m = 0.05;
  /// Also estimate a correction to cam0's height (body z of its T_BS translation). Needs
  /// body_height_m; otherwise the height is indistinguishable from the ground's offset.
  bool estimate_height = false;
  /// Prior 1-sigma on the height correction [m].
  double height_prior_sigma_m = 0.10;
  /// Gauss-Newton / Levenberg-Marquardt iteration limit.
  int max_iterations = 50;
  /// `ssta calibrate-mount` matches for the ground's level, not for speed: an SGBM of a one-pass
  /// mode (3way, sgbm) runs as hh4, and without a sub-pixel refinement the disparity is refined
  /// over 7 px (stereo.subpixel_window_px). The one-pass modes aggregate along paths from above
  /// only, which makes the ground's disparity about 0.1 px low; both modes err high on far
  /// ground, which the refinement takes out. A constant disparity error e tilts the ground like
  /// a camera pitched by e h / (f b). Online refinement (build-map) uses the map's disparity.
  bool unbiased_matching = true;

  /// `ssta build-map` refines the mount online while it fuses (`--refine` sets it): each solve
  /// that is determined replaces cam0's mount for the gravity and the poses of later frames.
  bool online = false;
  /// Online: the sliding window keeps the ground evidence of this many most recent frames with
  /// a usable ground plane [frames]; at least min_frames.
  int window_frames = 30;
  /// Online: solve once the window holds min_frames frames, then after every n-th further frame
  /// with a usable ground plane [frames].
  int solve_every_frames = 10;

  /// Every field: its key, unit, range and meaning (reading, writing and IsValid come from it).
  static const OptionFields<RefinementOptions>& Fields();
  /// The first field out of its range, as "key: requirement" in `*error`.
  bool IsValid(std::string* error) const;
};

}  // namespace ssta
