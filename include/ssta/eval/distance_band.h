#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ssta/eval/confusion_matrix.h"

namespace ssta {

/// The scored samples (truth 1..3) at one range of distances from the vehicle's path. A stereo
/// map's error grows with the square of range, so one figure over every sample mixes what the
/// rig resolves with what it cannot; the scorers split their samples into bands of distance.
struct DistanceBand {
  double from_m = 0.0;  ///< inclusive [m]
  double to_m = 0.0;    ///< exclusive [m]
  ConfusionMatrix matrix;
  /// Accuracy over the scored samples of this band and every nearer one (NaN while there are
  /// none).
  double accuracy_within = 0.0;
  /// Every sample of this band and every nearer one, summed.
  ConfusionMatrix matrix_within;
};

/// The path a synthetic sequence's vehicle drove: its (x, y) positions in the world [m] from
/// SEQ/pose0/data.csv beside the truth folder, one per 0.25 m of travel, and that file.
struct DrivenPath {
  std::vector<Eigen::Vector2d> points;  ///< empty when the sequence has no pose file
  std::string source;                   ///< the pose file, "" when there is none
};

/// The driven path of the sequence `sequence` (a folder holding gt/ or mav0/gt/). Throws
/// ssta::Error naming the file when a pose file is there but cannot be read.
DrivenPath ReadDrivenPath(const std::string& sequence);

}  // namespace ssta
