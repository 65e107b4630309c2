#pragma once

#include <string>

#include "ssta/pipeline/config.h"
#include "ssta/pipeline/frame_pipeline.h"

namespace ssta {

/// The per-frame JSON (docs/interfaces.md, section 5 extension): every segment of at least
/// min_plane_points points (id, inliers, centroid, normal, plane, slope_deg, step_m, class,
/// reason), the smaller fragments summed up (count, pixels per class), the pixels of each class
/// per LabelRule (`pixels_by_rule`), the ground plane, the quality verdict and the stage
/// timings. Coordinates are in the rectified cam0 frame [m].
std::string FrameReportJson(const FrameResult& frame, const std::string& name);

/// The per-frame files beyond labels, overlay and JSON.
struct FrameOutputExtras {
  /// `disparity/<name>.png` (16 bit, disparity * 256) and `disparity_colour/<name>.png`.
  bool disparity = false;
  /// `explain/<name>.png`: the LabelRule id that set each label (8 bit, the labels' size), and
  /// `explain_colour/<name>.png`: the rules in colour over the left image with a legend.
  bool explain = false;
};

/// Writes `out_dir/labels/<name>.png`, `out_dir/overlay/<name>.png` and
/// `out_dir/frames/<name>.json` (folders created when missing), each file atomically, and the
/// `extras` asked for.
void WriteFrameOutputs(const FrameResult& frame, const std::string& out_dir, const std::string& name,
                       const FrameOutputExtras& extras = {});

/// Removes the per-frame files an earlier run's WriteFrameOutputs left in `out_dir`
/// (RemoveFrameFiles on each of its folders); returns how many.
int RemoveFrameOutputs(const std::string& out_dir);

/// Writes `out_dir/config.yaml` atomically: every setting of the run (ConfigToYaml), so that
/// `--config out_dir/config.yaml` repeats it and `ssta eval labels` can check its vehicle.
void WriteRunConfig(const Config& config, const std::string& out_dir);

}  // namespace ssta
