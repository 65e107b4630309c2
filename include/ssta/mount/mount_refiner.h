#pragma once

#include <cstdint>
#include <deque>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "ssta/mount/ground_evidence.h"
#include "ssta/mount/refinement_options.h"

namespace ssta {

/// Outcome of a mount refinement.
enum class RefinementStatus {
  kDetermined,          ///< solved and better determined than the prior: apply it
  kTooFewFrames,        ///< fewer than min_frames usable frames: not determined, not solved
  kNotBetterThanPrior,  ///< solved, but the posterior sigma is not below max_sigma_ratio * prior
  /// solved, but the frames' ground tilts about the reference scatter more than
  /// terrain_tilt_sigma_deg allows (robust scatter per axis): the ground is not flat enough for
  /// the model, and the estimate would be biased by the terrain
  kTerrainTooRough,
  kFailed,              ///< the solver or the covariance failed (message says why)
};

std::string RefinementStatusName(RefinementStatus status);

/// One frame's ground plane after the solve, in the corrected body frame.
struct FrameGroundEstimate {
  std::int64_t timestamp_ns = 0;
  int points = 0;
  double tilt_deg = 0.0;  ///< angle between its normal and the reference direction [deg]
  double height_m = 0.0;  ///< distance of the body origin above the plane [m]
  /// Weight of the frame's tilt prior in the final solve, in (0, 1]: the Cauchy loss's
  /// derivative at its tilt; a frame whose tilt the others do not share comes near 0.
  double weight = 1.0;
};

/// A mount refinement's estimate, uncertainty and statistics.
///
/// The correction is the rotation `body_R_correction` = AngleAxis of roll * a_roll +
/// pitch * a_pitch [rad], two body axes perpendicular to the reference up direction: body x
/// (forward) and body y (left) for the default body reference on a REP-103 body (z up); in
/// general body x (or y) made perpendicular to up, and up cross that. It is the smallest
/// rotation that tilts the ground normal, with no rotation about it (unobservable). The refined
/// mount is `body_T_camera_refined = [body_R_correction * R, t + (0, 0, height_correction_m)]`
/// where `[R, t]` = `body_T_camera_initial`. Positive pitch rotates the camera about body y
/// (nose down for a forward-looking camera), positive roll about body x.
struct MountRefinementResult {
  RefinementStatus status = RefinementStatus::kTooFewFrames;
  std::string message;  ///< one sentence for people: why this status

  double pitch_correction_deg = 0.0;
  double roll_correction_deg = 0.0;
  double height_correction_m = 0.0;  ///< 0 unless estimate_height
  /// Posterior 1-sigma (ceres::Covariance) [deg, m]; NaN when not solved. The height sigma is
  /// NaN unless the height is estimated.
  double pitch_sigma_deg = std::numeric_limits<double>::quiet_NaN();
  double roll_sigma_deg = std::numeric_limits<double>::quiet_NaN();
  double height_sigma_m = std::numeric_limits<double>::quiet_NaN();
  double prior_sigma_deg = 0.0;  ///< the prior it was compared with [deg]

  Eigen::Matrix3d body_R_correction = Eigen::Matrix3d::Identity();
  Eigen::Isometry3d body_T_camera_initial = Eigen::Isometry3d::Identity();
  /// The refined mount. Equal to the initial one unless status is kDetermined.
  Eigen::Isometry3d body_T_camera_refined = Eigen::Isometry3d::Identity();

  int frames_used = 0;
  int points_used = 0;
  /// Robust-loss statistics over the ground points at the solution: points outside the loss's
  /// quadratic zone (|distance| > loss_scale * the point's sigma), RMS and median |point-to-plane| [m].
  int outlier_points = 0;
  double residual_rms_m = 0.0;
  double residual_median_m = 0.0;
  /// RMS over the frames of the angle between each frame's ground normal and the reference at
  /// the solution [deg].
  double ground_tilt_rms_deg = 0.0;
  /// Robust scatter (1-sigma) of the frames' tilts about the reference, about the first (roll)
  /// and second (pitch) tilt axis [deg], from the median |tilt|; at least min_tilt_scatter_deg.
  /// The final solve's tilt prior.
  Eigen::Vector2d tilt_scatter_axes_deg = Eigen::Vector2d::Zero();
  /// The larger of the two [deg]; compared with terrain_tilt_sigma_deg.
  double tilt_scatter_deg = 0.0;
  /// Robust scale of the point residuals in their assumed sigmas (1.4826 x median); the final
  /// solve multiplies every point sigma by it.
  double point_sigma_scale = 1.0;
  /// Frames whose weight is below 0.5 (their tilt is beyond frame_loss_scale scatters).
  int frames_downweighted = 0;
  /// Factor on the covariance's 1-sigma for frames that see overlapping ground, so their tilts
  /// are not independent: sqrt((1 + rho) / (1 - rho)), rho the lag-1 correlation of the tilts.
  double sigma_inflation = 1.0;
  /// The reference the solve used: "path", "body" or "gravity" (path acts as body for evidence
  /// without a path).
  std::string reference = "body";
  double initial_cost = 0.0, final_cost = 0.0;
  int iterations = 0;
  double solve_ms = 0.0;  ///< solve + covariance wall time [ms]
  std::vector<FrameGroundEstimate> frames;

  /// True when the refined mount should replace the configured one.
  bool applied() const { return status == RefinementStatus::kDetermined; }
  /// A few lines: status, correction +- sigma, frames, robust statistics, time.
  std::string BriefReport() const;
  /// A JSON object (no trailing newline), keys in snake_case with units (`_deg`, `_m`).
  std::string Json() const;
};

/// Estimates a correction to cam0's mount (pitch, roll and optionally height) shared by a set
/// of frames, with one ground plane per frame, by robust least squares (Ceres).
///
/// Model, in the body frame: a ground point p_c of frame i maps to
/// p_b = R_corr * R_BS * p_c + t_BS + (0, 0, dh). Frame i's ground is the plane n_i . p + d_i = 0
/// with n_i the reference direction (body z, or up_body_i) tilted by a per-frame 2-DoF rotation
/// under a prior of terrain_tilt_sigma_deg, and d_i the body origin's height above it (a prior
/// at body_height_m when known). Residuals: (n_i . p_b + d_i) / sigma(range) under the robust
/// loss; priors on R_corr (prior_sigma_deg) and dh. The tilt priors are what make the
/// correction observable: the ground seen by the camera is, on average, parallel to the plane
/// under the wheels.
///
/// Evidence is kept in a window (AddFrame / DropOldest), so the same refiner serves the offline
/// whole-sequence solve and an online sliding window. Not thread-safe.
class MountRefiner {
 public:
  /// Throws ssta::Error when `options` are invalid (message "refinement.<key>: ...").
  MountRefiner(const RefinementOptions& options, const Eigen::Isometry3d& body_T_camera);

  /// Adds a usable frame to the window. Precondition: evidence.usable.
  void AddFrame(GroundEvidence evidence);
  /// Removes the oldest frame of the window (no-op when empty).
  void DropOldest();
  int NumFrames() const { return static_cast<int>(window_.size()); }

  /// Solves over the window. Never throws on degenerate data: too few frames or a result not
  /// better determined than its prior come back as a status.
  MountRefinementResult Solve() const;

 private:
  RefinementOptions options_;
  Eigen::Isometry3d body_T_camera_;
  std::deque<GroundEvidence> window_;
};

/// The path reference over a whole drive (GroundReference::kPath): `frames[i]` holds frame i's
/// ground points (usable or not; thinned generously, the driven-over ones are chosen here) and
/// `world_T_body[i]` its pose. Each frame keeps the points a later body stands on (at most
/// points_per_frame, evenly) with that ground's expected normal, and the mount is solved; then
/// the points are chosen again through the refined mount and solved once more (a mount error of
/// degrees moves far points along the path by centimetres, onto the wrong later body, and on
/// curved ground that is a tilt). `*frames_on_path` (optional) receives how many frames kept
/// enough points in the last round. Fewer than min_frames: kTooFewFrames, as Solve(). With the
/// sag below the wheels' chords (wheelbase_m, track_m), the drive is also solved against the
/// wheel planes alone; where those determine no mount, their answer is returned.
MountRefinementResult SolveAlongPath(const RefinementOptions& options, const Eigen::Isometry3d& body_T_camera,
                                     const std::vector<std::optional<Eigen::Isometry3d>>& world_T_body,
                                     const std::vector<GroundEvidence>& frames, int* frames_on_path = nullptr);

}  // namespace ssta
