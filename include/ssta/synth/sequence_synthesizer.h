#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "ssta/core/progress.h"
#include "ssta/synth/synth_options.h"

namespace ssta::synth {

/// The `seen` key of gt/grid.yaml that WriteSyntheticSequence writes: a cell is seen (scored)
/// when a pixel that both cameras see within the label range lands in it. Truth grids without
/// the key came from an older renderer that left the cells along class boundaries unseen.
inline constexpr char kTruthSeenBothCameras[] = "both_cameras";

/// What WriteSyntheticSequence produced.
struct SynthSummary {
  int frames_written = 0;            ///< cam0 frames (every frame)
  int frames_dropped = 0;            ///< frames missing from cam1
  std::vector<std::int64_t> dropped_timestamps_ns;
  int imu_samples = 0;               ///< rows of imu0/data.csv (and pose0/data.csv)
  double max_disparity_px = 0;       ///< largest true disparity over all frames [px]
  double render_ms_per_frame = 0;    ///< mean wall time to render one stereo pair [ms]
  Eigen::Isometry3d body_T_cam0 = Eigen::Isometry3d::Identity();  ///< true cam0 mount
  /// Not empty when the run drives past the scene's clear run (Scene::clear_run_m).
  std::string warning;
  /// Per-frame files of an earlier run in the same folder, removed first (RemoveFrameFiles).
  int stale_files_removed = 0;

  /// One line: frames, drops, largest disparity, render time.
  std::string BriefReport() const;
};

/// The true mount of cam0 in the body frame for a rig (camera x right, y down, z forward;
/// pitched down by `pitch_down_deg`; optical centre `camera_forward_m` ahead of, `baseline/2`
/// left of and `camera_height_m - body_height_m` above the body origin).
Eigen::Isometry3d TrueBodyTCam0(const RigOptions& rig, const MotionOptions& motion);

/// Renders a complete synthetic ASL sequence with ground truth into `out_dir` (created when
/// missing; files of an earlier synth run are overwritten, and its per-frame images removed
/// first; a folder holding a recorded sequence, without gt/, is refused): cam0/, cam1/, imu0/, pose0/,
/// vehicle.yaml and gt/ (labels, disparity, grid_classes.png + grid.yaml, extrinsics.yaml,
/// faults.yaml), as docs/interfaces.md, sections 2 and 6 describe. Deterministic for given options.
/// Conventions: IMU and pose0 start 0.1 s before the first frame and end 0.1 s after the last;
/// gt/disparity covers every surface pixel of cam0 including those hidden from cam1 (KITTI
/// "disp_occ"), while gt/labels marks hidden pixels 255; gt/extrinsics.yaml is a full
/// sensor.yaml of cam0 with the true T_BS; frames dropped by the fault are missing from cam1
/// only (cam0, gt/labels and gt/disparity keep them).
/// Throws ssta::Error on invalid options (message names the option) or when it cannot write.
SynthSummary WriteSyntheticSequence(const SynthOptions& options, const std::string& out_dir,
                                    const Progress& progress = {});

}  // namespace ssta::synth
