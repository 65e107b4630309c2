#pragma once

// Private helpers of the scorers that split their samples by distance from the vehicle's path
// (eval grid, eval footprints): the path from a sequence's pose file, the bands, and their
// report and JSON.

#include <string>
#include <vector>

#include <Eigen/Core>

#include "ssta/core/json_writer.h"
#include "ssta/eval/distance_band.h"

namespace ssta::internal {

/// The vehicle's (x, y) positions from an ASL pose file, thinned to one per 0.25 m of travel
/// (the polyline between them is what DistanceToPath measures to). Throws ssta::Error naming
/// the file when it cannot be read.
std::vector<Eigen::Vector2d> ReadPath(const std::string& pose_csv);

/// The pose file of the sequence whose truth folder is `gt_dir` (SEQ/pose0/data.csv beside
/// gt/), or "" when there is none.
std::string FindPoseFile(const std::string& gt_dir);

/// Distance [m] from `p` to the polyline `path` (at least one point).
double DistanceToPath(const Eigen::Vector2d& p, const std::vector<Eigen::Vector2d>& path);

/// Samples sorted into bands of `band_m` metres of distance from a path, from 0 to the farthest
/// sample (bands without samples are kept, empty).
class BandAccumulator {
 public:
  /// Throws ssta::Error for band_m <= 0, an empty path or a non-finite point of it.
  BandAccumulator(std::vector<Eigen::Vector2d> path, double band_m);
  /// Bands of a distance the caller measures (AddAtDistance only). Throws for band_m <= 0.
  explicit BandAccumulator(double band_m);
  /// Adds one sample at `at` (x, y in the world [m]). Throws ssta::Error when it lies
  /// kMaxBands bands or more from the path (the path is not this grid's), or without a path.
  void Add(const Eigen::Vector2d& at, std::uint8_t truth, std::uint8_t predicted);
  /// Adds `count` samples at `distance` [m], >= 0. Throws ssta::Error beyond kMaxBands bands.
  void AddAtDistance(double distance, std::uint8_t truth, std::uint8_t predicted, std::int64_t count = 1);
  double band_m() const { return band_m_; }
  static constexpr int kMaxBands = 10000;
  /// The bands, each with its accuracy and matrix within (this band and every nearer one).
  std::vector<DistanceBand> Finish() const;

 private:
  std::vector<Eigen::Vector2d> path_;
  double band_m_;
  std::vector<DistanceBand> bands_;
};

/// A table for a terminal under the line "by distance from the path (PATH_SOURCE):": per band
/// the scored samples, accuracy, coverage, recall of each class, the unsafe and falsely blocked
/// rates, and the accuracy within. "" without bands.
std::string BandsReport(const std::vector<DistanceBand>& bands, const std::string& path_source);
/// The same table under the line "HEADING:".
std::string BandsTable(const std::vector<DistanceBand>& bands, const std::string& heading);

/// {"path", "band_m", "bands": [{"from_m", "to_m", "scored", "accuracy", "coverage",
///  "mean_iou", "accuracy_within", "metrics": {...}, "metrics_within": {...}}, ...]}.
void WriteBandsJson(const std::vector<DistanceBand>& bands, const std::string& path_source, double band_m,
                    JsonWriter* json);

}  // namespace ssta::internal
