#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "ssta/io/sequence.h"
#include "ssta/mount/ground_evidence.h"
#include "ssta/mount/mount_refiner.h"
#include "ssta/mount/refinement_options.h"

namespace ssta {

/// One solve of the online refinement.
struct OnlineSolve {
  int frame = 0;                 ///< 1-based count of frames offered when it ran
  std::int64_t timestamp_ns = 0; ///< of the frame that triggered it
  RefinementStatus status = RefinementStatus::kTooFewFrames;
  double pitch_correction_deg = 0.0, roll_correction_deg = 0.0;  ///< against sensor.yaml [deg]
  double pitch_sigma_deg = 0.0, roll_sigma_deg = 0.0;            ///< 1-sigma [deg]
  int frames_used = 0;           ///< frames in the window
};

/// What the online mount refinement did over a run of frames.
struct OnlineRefinementSummary {
  int frames_offered = 0;        ///< frames whose evidence was offered (usable or not)
  int frames_with_evidence = 0;  ///< of those, frames with a usable ground plane
  std::vector<SkippedFrame> no_evidence;  ///< frames without usable ground evidence, and why
  int solves = 0;                ///< solves run
  int applied = 0;               ///< solves whose result replaced the mount (status determined)
  /// Solves not applied, by status: too_few_frames, not_better_than_prior, terrain_too_rough,
  /// failed (RefinementStatus order after kDetermined).
  std::array<int, 4> rejected{};
  std::string last_rejection;    ///< the message of the last solve not applied; empty if none
  std::vector<OnlineSolve> history;  ///< every solve, in order
  /// Frames offered before the first applied solve: they were processed with the start mount.
  int frames_before_first_applied = 0;
  double solve_ms = 0.0;         ///< total solve + covariance time [ms]
  /// Frames its user processed a second time with the refined mount (build-map's warm-up);
  /// set by the user, 0 otherwise.
  int frames_reprocessed = 0;
  /// The last applied solve (its correction and 1-sigma are relative to the configured mount);
  /// nullopt when none was applied.
  std::optional<MountRefinementResult> last_applied;
  Eigen::Isometry3d body_T_camera_configured = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d body_T_camera_start = Eigen::Isometry3d::Identity();  ///< in use before any solve
  Eigen::Isometry3d body_T_camera = Eigen::Isometry3d::Identity();        ///< in use at the end

  int rejected_total() const { return rejected[0] + rejected[1] + rejected[2] + rejected[3]; }
  /// A few lines: the mount in use (correction +- 1-sigma), solves applied / rejected and why.
  std::string BriefReport() const;
  /// A JSON object (no trailing newline), keys in snake_case with units.
  std::string Json() const;
};

/// The mount refinement while a map is built: a sliding window of the most recent frames'
/// ground evidence (MountRefiner), solved when the window first holds `min_frames` frames and
/// then after every `solve_every_frames` further frames with evidence. A solve whose status is
/// kDetermined replaces the mount in use (body_T_camera()); any other keeps it, counted with
/// its reason. Every solve's prior is centred on the configured mount, so solves do not
/// compound. Deterministic: the same frames give the same mounts. Not thread-safe.
class OnlineMountRefiner {
 public:
  /// `body_T_camera_configured`: cam0's mount from its sensor.yaml, the centre of every solve's
  /// prior; `body_T_camera_start`: the mount in use until a solve is applied (the configured
  /// one, or one an earlier run refined). Throws ssta::Error when `options` are invalid.
  OnlineMountRefiner(const RefinementOptions& options, const Eigen::Isometry3d& body_T_camera_configured,
                     const Eigen::Isometry3d& body_T_camera_start);

  /// Offers one frame's evidence (usable or not; unusable frames are only counted) and solves
  /// when due. Returns true when the mount in use changed.
  bool AddFrame(GroundEvidence evidence);

  /// cam0's mount in use: the last applied solve's, else the start mount.
  const Eigen::Isometry3d& body_T_camera() const { return summary_.body_T_camera; }
  /// The result of the last solve, nullopt before the first.
  const std::optional<MountRefinementResult>& last_result() const { return last_result_; }
  const OnlineRefinementSummary& summary() const { return summary_; }

 private:
  RefinementOptions options_;
  MountRefiner window_;
  int since_solve_ = 0;  // frames with evidence added since the last solve
  std::optional<MountRefinementResult> last_result_;
  OnlineRefinementSummary summary_;
};

}  // namespace ssta
