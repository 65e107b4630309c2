#pragma once

#include <functional>
#include <string>
#include <vector>

#include "ssta/io/camera_calibration.h"
#include "ssta/io/sequence.h"
#include "ssta/core/progress.h"
#include "ssta/pipeline/config.h"
#include "ssta/pipeline/sequence_run.h"
#include "ssta/mount/mount_refiner.h"

namespace ssta {

/// Which frames of a sequence the offline calibration runs over.
struct MountCalibrationOptions {
  RefinementOptions refinement;
  FrameSelection frames;  ///< which frames, and whether one that cannot be used is an error
  /// Each frame's true disparity (gt/disparity/<ts>.png of a synthetic sequence) instead of
  /// stereo matching: what is left is the ground model's error, apart from the matcher's.
  bool oracle_disparity = false;

  /// Checks the fields; the message starts with the key name.
  bool IsValid(std::string* error) const;
};

/// The offline mount calibration of one sequence.
struct MountCalibration {
  MountRefinementResult refinement;
  int frames_listed = 0;             ///< frames the sequence lists (incl. those it skipped)
  int frames_processed = 0;          ///< frames run through the per-frame pipeline
  std::vector<SkippedFrame> skipped; ///< frames not used, with the reason
  /// The rig with cam0's refined T_BS and cam1's T_BS that follows from the original pair
  /// (body_T_cam1 = body_T_cam0_refined * cam0_T_cam1); equal to the input unless applied.
  StereoCalibration refined;
  double pipeline_s = 0.0;  ///< wall time of the per-frame pipeline over all frames [s]
  /// Empty, or why the path reference gave way to the body reference (too few frames whose
  /// ground the drive goes over, e.g. a short drive or no poses).
  std::string reference_note;
  /// Path reference: frames with enough ground that a later frame's body stands on.
  int frames_on_path = 0;
  /// Empty, or how the matching differed from the config's (refinement.unbiased_matching).
  std::string matching_note;

  /// The refinement's report, then the frames skipped with their reasons.
  std::string BriefReport() const;
  /// A JSON document: the refinement, both refined T_BS (4x4 row-major), skipped frames.
  std::string Json() const;
};

/// Runs the per-frame pipeline (stereo, segmentation, dominant ground plane) over the selected
/// frames of `sequence` with `config`, collects each frame's ground evidence (up in the body
/// from GravityProvider; with the path reference, only the ground a later frame's body stands
/// on, through the sequence's poses) and solves for cam0's mount correction over all of them.
/// With refinement.unbiased_matching the matcher runs as that option says.
/// Throws ssta::Error on invalid options or config, and when no frame has a usable ground
/// plane (the message says why the first frames were skipped). Too few frames or a result not
/// better determined than its prior are statuses in the result, not exceptions.
MountCalibration CalibrateMount(const Sequence& sequence, const Config& config, const MountCalibrationOptions& options,
                                const Progress& progress = {});

}  // namespace ssta
