#pragma once

#include <cstdint>
#include <functional>
#include <array>
#include <map>
#include <string>
#include <vector>

#include "ssta/io/ground_truth.h"
#include "ssta/io/sequence.h"
#include "ssta/pipeline/config.h"
#include "ssta/pipeline/frame_pipeline.h"

namespace ssta {

/// How a sequence is classified (`ssta classify` options that are not in the config file).
struct ClassifyOptions {
  std::string out_dir;          ///< where labels/, overlay/, frames/, summary.json and config.yaml go
  int max_frames = 0;           ///< 0: all frames
  int every = 1;                ///< use every n-th frame
  bool write_disparity = false; ///< also write disparity/<ts>.png in false colour
  /// Any frame that cannot be used (unpaired, missing or unreadable image, wrong size) is an
  /// error instead of a skip with a reason.
  bool strict = false;
  /// Use the sequence's gt/disparity/<ts>.png (16-bit, disparity * 256) instead of stereo
  /// matching: measures the analysis alone on synthetic sequences.
  bool oracle_disparity = false;
  bool IsValid(std::string* error) const;
};

/// What a classify run did: frames used and skipped (with reasons), quality-check failures,
/// pixel shares per class and the mean time per stage.
struct ClassifySummary {
  int frames_total = 0;
  int frames_classified = 0;
  std::vector<SkippedFrame> skipped;        ///< unusable frames and why
  std::vector<SkippedFrame> quality_failed; ///< classified, but their depth pixels are undecided
  std::array<std::int64_t, 5> class_pixels{};  ///< pixels per class id over all frames
  StageTimings mean_timings;
  double wall_s = 0.0;
  /// Per-frame files of an earlier run in the output folders, removed first (RemoveFrameFiles).
  int stale_files_removed = 0;

  /// A few lines for people.
  std::string BriefReport() const;
  /// Machine-readable summary (written as summary.json).
  std::string Json() const;
};

/// Overwrites a frame's labels (`labels`: the rectified common area, `geometry`'s crop) with the
/// verdicts of its true labels, gt/labels/<ts>.png of a synthetic sequence (ids 1-3 at the full
/// rectified size, found as ReadTrueDisparity finds its file); where the truth has none (255:
/// sky, occlusions, the band on class boundaries) the frame keeps its own. Throws ssta::Error
/// naming the file when it is missing, unreadable or not of the rectified image's size.
void ApplyTrueLabels(const Sequence& sequence, std::int64_t timestamp_ns, const RectifiedGeometry& geometry,
                     ImageU8* labels);

/// Called after each frame: (frames done, frames to do).
using ProgressCallback = std::function<void(int done, int total)>;

/// Classifies every usable frame of `sequence` and writes the per-frame outputs, summary.json
/// and config.yaml (ConfigToYaml of `config`, written first). The per-frame files of an earlier
/// run in the output folders (labels/, overlay/, frames/, disparity/, disparity_colour/) are
/// removed first. Frames that cannot be read are skipped with a reason; bad config or
/// calibration throw ssta::Error before any work.
ClassifySummary ClassifySequence(const Sequence& sequence, const Config& config,
                                 const ClassifyOptions& options, const ProgressCallback& progress = {});

}  // namespace ssta
