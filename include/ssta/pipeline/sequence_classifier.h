#pragma once

#include <cstdint>
#include <functional>
#include <array>
#include <map>
#include <string>
#include <vector>

#include "ssta/core/progress.h"
#include "ssta/io/sequence.h"
#include "ssta/pipeline/config.h"
#include "ssta/pipeline/frame_pipeline.h"
#include "ssta/pipeline/sequence_run.h"

namespace ssta {

/// How a sequence is classified (`ssta classify` options that are not in the config file).
struct ClassifyOptions {
  std::string out_dir;          ///< where labels/, overlay/, frames/, summary.json and config.yaml go
  /// Which frames to classify, and whether a frame that cannot be used (unpaired, missing or
  /// unreadable image, wrong size) is an error instead of a skip with a reason.
  FrameSelection frames;
  bool write_disparity = false; ///< also write disparity/<ts>.png in false colour
  bool write_explain = false;   ///< also write explain/<ts>.png (rule ids) and explain_colour/<ts>.png
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
  /// Classified, but failed the quality check and not judged (QualityCheck::judged): their depth
  /// pixels are undecided.
  std::vector<SkippedFrame> quality_failed;
  std::array<std::int64_t, 5> class_pixels{};  ///< pixels per class id over all frames
  StageTimings mean_timings;
  double wall_s = 0.0;
  /// Per-frame files of an earlier run in the output folders, removed first (RemoveFrameFiles).
  int stale_files_removed = 0;

  /// Counts a classified frame: its classes, timings and quality verdict.
  void Add(const FrameResult& frame);
  /// A few lines for people.
  std::string BriefReport() const;
  /// Machine-readable summary (written as summary.json).
  std::string Json() const;
};

/// Classifies every usable frame of `sequence` and writes the per-frame outputs, summary.json
/// and config.yaml (ConfigToYaml of `config`, written first). The per-frame files of an earlier
/// run in the output folders (labels/, overlay/, frames/, disparity/, disparity_colour/) are
/// removed first. Frames that cannot be read are skipped with a reason; bad config or
/// calibration throw ssta::Error before any work.
ClassifySummary ClassifySequence(const Sequence& sequence, const Config& config,
                                 const ClassifyOptions& options, const Progress& progress = {});

}  // namespace ssta
