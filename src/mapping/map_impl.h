#pragma once

// Private: the state behind TraversabilityMap, shared by its translation units (fusion and
// queries, file I/O) and reachable from the exporters and tests through
// TraversabilityMapAccess.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "mapping/sensor_path.h"
#include "mapping/trav_octree.h"
#include "ssta/mapping/column_explanation.h"
#include "ssta/mapping/traversability_map.h"

namespace ssta {

namespace internal {
struct InsertScratch;  // InsertFrame's working buffers (frame_fusion.cpp)
}  // namespace internal

struct TraversabilityMap::Impl {
  MapOptions options;
  MapMetadata metadata;
  std::unique_ptr<internal::TravOcTree> tree;
  std::uint64_t frames_inserted = 0;
  std::int64_t last_timestamp_ns = 0;
  std::string software_version;
  /// For a map read from a file, the hash in its end marker ("fnv1a64:<hex>"); empty otherwise.
  std::string file_checksum;
  /// TraversabilityMap::sensor_path, indexed for NearestXy.
  internal::SensorPath sensor_path;
  /// InsertFrame's buffers, kept from frame to frame so that a frame allocates nothing once
  /// they have grown; no map state (created on the first insert, never saved or compared).
  std::shared_ptr<internal::InsertScratch> insert_scratch;
};

namespace internal {

/// A tree configured with the sensor model of `options` (precondition: options valid).
std::unique_ptr<TravOcTree> MakeTree(const MapOptions& options);

/// Cell description of `node` (null: unobserved) at the full-resolution voxel `key`
/// (cell_description.cpp).
CellInfo DescribeCell(const TraversabilityMap& map, const TravOcTree& tree, const TravNode* node,
                      const octomap::OcTreeKey& key);

/// The probabilities of the three classes from a voxel's class log-odds (softmax), the
/// traversable one raised by `prior_traversable` (MapOptions::class_prior_traversable_log_odds).
inline std::array<double, 3> FrameClassProbabilities(const std::array<float, 3>& log_odds, double prior_traversable) {
  std::array<double, 3> p{};
  double total = 0.0;
  for (int k = 0; k < 3; ++k) {
    total += (p[k] = std::exp(static_cast<double>(log_odds[k]) + (k == 0 ? prior_traversable : 0.0)));
  }
  for (double& x : p) x /= total;
  return p;
}

/// What one clear vote for class index k (0..2) adds to its log-odds: class_hit_log_odds, times
/// class_obstacle_gain for the non-traversable class.
inline double ClearViewLogOdds(int k, const MapOptions& options) {
  return options.class_hit_log_odds * (k == 2 ? options.class_obstacle_gain : 1.0);
}

/// The evidence in a voxel's class log-odds, in clear views: the largest |L_k| over what one
/// clear vote for class k adds (class_hit_log_odds, times class_obstacle_gain for an obstacle).
inline double ClassEvidenceViews(const std::array<float, 3>& log_odds, const MapOptions& options) {
  double views = 0.0;
  for (int k = 0; k < 3; ++k) {
    views = std::max(views, std::abs(static_cast<double>(log_odds[static_cast<std::size_t>(k)])) /
                                ClearViewLogOdds(k, options));
  }
  return views;
}

/// Whether a voxel's class log-odds are a verdict: nonzero, and at least
/// MapOptions::class_min_evidence_views clear views. Each vote already counts by how well its
/// view resolves the step radius, so weaker evidence means no view resolved the ground: the
/// open-ground prior must not answer for it.
inline bool HasClassEvidence(const std::array<float, 3>& log_odds, const MapOptions& options) {
  if (log_odds[0] == 0.0f && log_odds[1] == 0.0f && log_odds[2] == 0.0f) return false;
  return ClassEvidenceViews(log_odds, options) >= options.class_min_evidence_views;
}

/// Whether the open-ground prior alone would make the voxel traversable on too little evidence
/// (MapOptions::class_prior_min_evidence_views): without the prior the non-traversable class
/// is the most probable (ties to the worse), with it traversable is, and the votes hold fewer
/// clear views than the floor. Such a voxel is undecided.
inline bool PriorAloneWouldOpen(const std::array<float, 3>& log_odds, const MapOptions& options) {
  if (options.class_prior_min_evidence_views <= 0.0) return false;
  if (log_odds[2] < log_odds[0] || log_odds[2] < log_odds[1]) return false;  // the votes do not lean to an obstacle
  // L3 is the largest, so the prior opens the voxel exactly when it lifts L1 above L3.
  if (!(static_cast<double>(log_odds[0]) + options.class_prior_traversable_log_odds > log_odds[2])) return false;
  return ClassEvidenceViews(log_odds, options) < options.class_prior_min_evidence_views;
}

/// Whether the frames' votes make the voxel an obstacle (non-traversable the most probable class
/// with the open-ground prior, ties to the worse) on less obstacle evidence than
/// MapOptions::class_obstacle_min_evidence_views clear views: L3 under that many times what one
/// clear obstacle vote adds. Each vote already counts by how well its view resolves the step
/// radius, so such evidence is what stereo noise at the views' range can make. Such a voxel is
/// undecided.
inline bool ObstacleTooWeak(const std::array<float, 3>& log_odds, const MapOptions& options) {
  if (options.class_obstacle_min_evidence_views <= 0.0) return false;
  const double obstacle = log_odds[2];
  if (obstacle < log_odds[0] + options.class_prior_traversable_log_odds || obstacle < log_odds[1]) return false;
  return obstacle < options.class_obstacle_min_evidence_views * ClearViewLogOdds(2, options);
}

/// The floor that withholds the frames' verdict from a voxel with class evidence, leaving it
/// undecided: JudgeRule::kPriorWithheld (PriorAloneWouldOpen), kObstacleWithheld
/// (ObstacleTooWeak), or kNone when neither does.
inline JudgeRule WithheldVerdict(const std::array<float, 3>& log_odds, const MapOptions& options) {
  if (PriorAloneWouldOpen(log_odds, options)) return JudgeRule::kPriorWithheld;
  if (ObstacleTooWeak(log_odds, options)) return JudgeRule::kObstacleWithheld;
  return JudgeRule::kNone;
}

/// Whether `node` is occupied: its occupancy at or above the tree's threshold.
inline bool NodeOccupied(const TravOcTree& tree, const TravNode& node) {
  return node.getLogOdds() >= tree.getOccupancyThresLog();
}

/// Whether the voxel's verdict is traversable, as DescribeCell gives it (ties go to the worse
/// class). Fusion spares such ground from free-space rays (free_space_keeps_traversable) and
/// the merge must spare the same voxels, so both ask here.
inline bool HeldAsTraversable(const TravNode& node) {
  const auto& l = node.class_log_odds;
  return l[0] > 0.0f && l[0] > l[1] && l[0] > l[2];
}

/// Centre [m] of the voxels with key `k` along one axis.
inline double KeyCenter(const TravOcTree& tree, octomap::key_type k) { return tree.keyToCoord(k); }

/// Centre of the voxel `key` in W [m].
inline Eigen::Vector3d KeyCenter(const TravOcTree& tree, const octomap::OcTreeKey& key) {
  return {tree.keyToCoord(key[0]), tree.keyToCoord(key[1]), tree.keyToCoord(key[2])};
}

struct TraversabilityMapAccess {
  static const TravOcTree& Tree(const TraversabilityMap& map) { return *map.impl_->tree; }
  static TraversabilityMap::Impl& Impl(TraversabilityMap& map) { return *map.impl_; }
  static const TraversabilityMap::Impl& Impl(const TraversabilityMap& map) { return *map.impl_; }
  /// TraversabilityMap::Load on the bytes of the file `path` (`path` only names it in
  /// messages); the fuzz target calls it directly. Defined in map_file.cpp.
  static TraversabilityMap LoadFromBytes(const std::string& bytes, const std::string& path);
  static TraversabilityMap FromImpl(std::unique_ptr<TraversabilityMap::Impl> impl) {
    return TraversabilityMap(std::move(impl));
  }
};

/// TraversabilityMap::Impl for the code of src/mapping that is not its friend (the name is
/// private; the type TraversabilityMapAccess hands out is not).
using MapImpl = std::remove_reference_t<decltype(TraversabilityMapAccess::Impl(std::declval<TraversabilityMap&>()))>;

}  // namespace internal
}  // namespace ssta
