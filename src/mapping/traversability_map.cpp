#include "ssta/mapping/traversability_map.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_map>
#include <utility>
#include <vector>

#include "mapping/free_space_walk.h"
#include "mapping/map_impl.h"
#include "mapping/voxel_containers.h"
#include "ssta/core/error.h"

#ifndef SSTA_VERSION
#define SSTA_VERSION "unknown"
#endif

namespace ssta {

using internal::FreeSpaceWalk;
using internal::SortByCode;
using internal::TravNode;
using internal::TravOcTree;
using internal::VoxelIndex;

namespace {

/// Per-voxel accumulator of one frame's in-range points.
struct VoxelAccumulator {
  Eigen::Vector3d sum_p = Eigen::Vector3d::Zero();
  std::uint32_t points = 0;
  std::array<std::uint32_t, 3> votes{};  // classes 1..3
  double slope_sum = 0.0;
  std::uint32_t slope_count = 0;
  double step_sum = 0.0;
  std::uint32_t step_count = 0;
  double max_abs_step = -1.0;  // < 0: none
  double height_sum = 0.0;
  std::uint32_t height_count = 0;
};

/// Whether the ray to a hit voxel ends on an obstacle (free_space_obstacle_shortening_per_m2):
/// most of its points are non-traversable and they do not lie below the frame's ground plane
/// (by more than half a voxel; an unknown height counts as not below). Such a ray's last metres
/// pass above the ground in front of the obstacle rather than along it, so they need no
/// clearance; rays into a pit (its walls and floor lie below the ground) graze its near edge.
bool EndsOnAnObstacle(const VoxelAccumulator& acc, const MapOptions& opt) {
  if (opt.free_space_obstacle_shortening_per_m2 < 0.0) return false;
  if (acc.votes[2] <= acc.votes[0] + acc.votes[1]) return false;
  if (acc.height_count == 0) return true;
  return acc.height_sum / acc.height_count >= -0.5 * opt.resolution_m;
}

/// Accumulator of one frame's points beyond range (ray direction only).
struct FarAccumulator {
  Eigen::Vector3d sum_p = Eigen::Vector3d::Zero();
  std::uint32_t points = 0;
};

/// `norm > max_range` decided from the squared norm without the square root where the answer
/// is clear (the root is correctly rounded, so only a squared norm within a relative 1e-9 of
/// max_range^2 needs it).
struct RangeTest {
  explicit RangeTest(double max_range)
      : max_range(max_range), below(max_range * max_range * (1.0 - 1e-9)),
        above(max_range * max_range * (1.0 + 1e-9)) {}
  double max_range, below, above;
};
inline bool BeyondRange(double squared_norm, const RangeTest& r) {
  if (squared_norm < r.below) return false;
  if (squared_norm > r.above) return true;
  return std::sqrt(squared_norm) > r.max_range;
}

/// Majority vote of the 1..3 verdicts, ties to the worse class; -1 when there are none.
int MajorityClassIndex(const std::array<std::uint32_t, 3>& votes) {
  int best = -1;
  std::uint32_t best_votes = 0;
  for (int k = 0; k < 3; ++k) {
    if (votes[k] > 0 && votes[k] >= best_votes) {
      best = k;
      best_votes = votes[k];
    }
  }
  return best;
}

float Clamp(double v, double lo, double hi) { return static_cast<float>(std::min(hi, std::max(lo, v))); }

float DecayTowardsZero(float l, double decay) {
  if (l > 0.0f) return static_cast<float>(std::max(0.0, l - decay));
  if (l < 0.0f) return static_cast<float>(std::min(0.0, l + decay));
  return l;
}

/// The voxel's verdict is traversable (as DescribeCell gives it: ties go to the worse class).
bool HeldAsTraversable(const TravNode& node) {
  const auto& l = node.class_log_odds;
  return l[0] > 0.0f && l[0] > l[1] && l[0] > l[2];
}

}  // namespace

namespace internal {

struct InsertScratch {
  VoxelIndex voxel_index;                  ///< the frame's voxels -> accumulators
  std::vector<VoxelAccumulator> hits;      ///< in-range voxels, in order of first point
  std::vector<std::uint64_t> hit_codes;    ///< their Morton codes
  std::vector<octomap::OcTreeKey> hit_keys;  ///< and keys
  std::vector<FarAccumulator> far;         ///< voxels of points beyond range
  std::vector<octomap::point3d> ray_ends;  ///< where each ray stops
  std::vector<octomap::OcTreeKey> ray_end_keys;
  VoxelIndex ray_cells;  ///< free_space_ray_cell > 1: cell -> group
  std::vector<std::pair<Eigen::Vector3d, std::uint32_t>> ray_groups;  ///< sum of ends, count
  FreeSpaceWalk free_space;  ///< the voxels the rays pass
  std::vector<std::pair<std::uint64_t, const VoxelAccumulator*>> voxels, voxels_sort;
  std::vector<std::uint64_t> codes;
};

std::unique_ptr<TravOcTree> MakeTree(const MapOptions& options) {
  auto tree = std::make_unique<TravOcTree>(options.resolution_m);
  tree->setProbHit(options.occupancy_hit_prob);
  tree->setProbMiss(options.occupancy_miss_prob);
  tree->setClampingThresMin(options.occupancy_clamp_min_prob);
  tree->setClampingThresMax(options.occupancy_clamp_max_prob);
  tree->setOccupancyThres(options.occupied_threshold_prob);
  return tree;
}

}  // namespace internal

TraversabilityMap::TraversabilityMap(const MapOptions& options, MapMetadata metadata)
    : impl_(std::make_unique<Impl>()) {
  std::string error;
  if (!options.IsValid(&error)) throw Error("map options: " + error);
  if (!metadata.vehicle.IsValid(&error)) throw Error("map vehicle: " + error);
  impl_->options = options;
  impl_->metadata = std::move(metadata);
  impl_->tree = internal::MakeTree(options);
  impl_->software_version = SSTA_VERSION;
}

TraversabilityMap::TraversabilityMap(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
TraversabilityMap::~TraversabilityMap() = default;
TraversabilityMap::TraversabilityMap(TraversabilityMap&&) noexcept = default;
TraversabilityMap& TraversabilityMap::operator=(TraversabilityMap&&) noexcept = default;

InsertStats TraversabilityMap::InsertFrame(const std::vector<ClassifiedPoint>& points,
                                           const Eigen::Vector3d& sensor_origin_world,
                                           std::int64_t timestamp_ns) {
  TravOcTree& tree = *impl_->tree;
  const MapOptions& opt = impl_->options;
  InsertStats stats;
  stats.points_in = points.size();

  octomap::OcTreeKey origin_key;
  if (!sensor_origin_world.allFinite() ||
      !tree.CoordToKeyChecked(sensor_origin_world.x(), sensor_origin_world.y(), sensor_origin_world.z(),
                              &origin_key)) {
    stats.inserted = false;
    stats.reason = "sensor origin is not finite or lies outside the map's addressable cube";
    stats.points_rejected = points.size();
    return stats;
  }

  if (!impl_->insert_scratch) impl_->insert_scratch = std::make_shared<internal::InsertScratch>();
  internal::InsertScratch& scratch = *impl_->insert_scratch;

  // 1. Thin the points: one accumulator per voxel, keyed by the voxel's Morton code.
  VoxelIndex& index = scratch.voxel_index;
  std::vector<VoxelAccumulator>& hits = scratch.hits;
  std::vector<FarAccumulator>& far = scratch.far;
  index.Clear();
  hits.clear();
  scratch.hit_codes.clear();
  scratch.hit_keys.clear();
  far.clear();
  const RangeTest range(opt.max_range_m);
  std::uint64_t last_code = ~std::uint64_t{0};
  VoxelIndex::Entry* entry = nullptr;  // of last_code (image neighbours share voxels)
  for (const ClassifiedPoint& point : points) {
    const Eigen::Vector3d p = point.world_p.cast<double>();
    octomap::OcTreeKey key;
    if (!p.allFinite() || !tree.CoordToKeyChecked(p.x(), p.y(), p.z(), &key)) {
      ++stats.points_rejected;
      continue;
    }
    const std::uint64_t code = TravOcTree::MortonCode(key);
    if (code != last_code) {
      entry = &index.FindOrInsert(code);
      last_code = code;
    }
    if (BeyondRange((p - sensor_origin_world).squaredNorm(), range)) {
      if (entry->far < 0) {
        entry->far = static_cast<std::int32_t>(far.size());
        far.emplace_back();
      }
      FarAccumulator& acc = far[static_cast<std::size_t>(entry->far)];
      acc.sum_p += p;
      ++acc.points;
      ++stats.points_beyond_range;
      continue;
    }
    if (entry->hit < 0) {
      entry->hit = static_cast<std::int32_t>(hits.size());
      hits.emplace_back();
      scratch.hit_codes.push_back(code);
      scratch.hit_keys.push_back(key);
    }
    VoxelAccumulator& acc = hits[static_cast<std::size_t>(entry->hit)];
    acc.sum_p += p;
    ++acc.points;
    ++stats.points_hit;
    if (std::isfinite(point.height_m)) {
      acc.height_sum += point.height_m;
      ++acc.height_count;
    }
    const int c = static_cast<int>(point.cls);
    if (c < 1 || c > 3) continue;  // unknown, undecided, don't-care: occupancy only
    ++acc.votes[c - 1];
    if (std::isfinite(point.slope_deg)) {
      acc.slope_sum += point.slope_deg;
      ++acc.slope_count;
    }
    if (std::isfinite(point.step_m)) {
      acc.step_sum += point.step_m;
      ++acc.step_count;
      acc.max_abs_step = std::max(acc.max_abs_step, static_cast<double>(std::abs(point.step_m)));
    }
  }

  // 2. Free space: where each ray ends, then every voxel the rays pass once (one bit per voxel
  // of the box the rays span, or a flat set of Morton codes if that box is too large); occupied
  // voxels of this frame win.
  const octomap::point3d origin(static_cast<float>(sensor_origin_world.x()),
                                static_cast<float>(sensor_origin_world.y()),
                                static_cast<float>(sensor_origin_world.z()));
  std::vector<octomap::point3d>& ray_ends = scratch.ray_ends;
  std::vector<octomap::OcTreeKey>& ray_end_keys = scratch.ray_end_keys;
  ray_ends.clear();
  ray_end_keys.clear();
  auto add_ray = [&](const Eigen::Vector3d& end) {
    const octomap::point3d e(static_cast<float>(end.x()), static_cast<float>(end.y()),
                             static_cast<float>(end.z()));
    octomap::OcTreeKey key_end;
    if (!tree.coordToKeyChecked(e, key_end)) return;  // as computeRayKeys: no ray
    ray_ends.push_back(e);
    ray_end_keys.push_back(key_end);
  };
  // Rays to surface points stop short where they graze the surface (free_space_clearance_m);
  // rays to obstacles stop only a depth-noise band short (free_space_obstacle_shortening_per_m2).
  constexpr double kMaxShorteningM = 2.0;
  for (const VoxelAccumulator& acc : hits) {
    const Eigen::Vector3d end = acc.sum_p / acc.points;
    const Eigen::Vector3d d = end - sensor_origin_world;
    const double length = d.norm();
    if (opt.free_space_clearance_m > 0.0 && length > 1e-9) {
      const double sin_elevation = std::max(std::abs(d.z()) / length, 1e-3);
      double shorten = std::min(opt.free_space_clearance_m / sin_elevation, kMaxShorteningM);
      if (EndsOnAnObstacle(acc, opt)) shorten = std::min(shorten, opt.free_space_obstacle_shortening_per_m2 * length * length);
      if (shorten < length) add_ray(sensor_origin_world + d * ((length - shorten) / length));
    } else {
      add_ray(end);
    }
  }
  for (const FarAccumulator& acc : far) {
    const Eigen::Vector3d direction = (acc.sum_p / acc.points - sensor_origin_world).normalized();
    add_ray(sensor_origin_world + direction * opt.max_range_m);
  }
  if (opt.free_space_ray_cell > 1) {
    // One ray per cell of free_space_ray_cell^3 voxels holding ray ends, to their mean.
    const int shift = opt.free_space_ray_cell == 2 ? 1 : opt.free_space_ray_cell == 4 ? 2 : 3;
    VoxelIndex& cells = scratch.ray_cells;
    auto& groups = scratch.ray_groups;
    cells.Clear();
    groups.clear();
    for (std::size_t r = 0; r < ray_ends.size(); ++r) {
      const octomap::OcTreeKey& k = ray_end_keys[r];
      const octomap::OcTreeKey cell(static_cast<octomap::key_type>(k[0] >> shift),
                                    static_cast<octomap::key_type>(k[1] >> shift),
                                    static_cast<octomap::key_type>(k[2] >> shift));
      VoxelIndex::Entry& e = cells.FindOrInsert(TravOcTree::MortonCode(cell));
      if (e.hit < 0) {
        e.hit = static_cast<std::int32_t>(groups.size());
        groups.emplace_back(Eigen::Vector3d::Zero(), 0u);
      }
      auto& group = groups[static_cast<std::size_t>(e.hit)];
      group.first += Eigen::Vector3d(ray_ends[r].x(), ray_ends[r].y(), ray_ends[r].z());
      ++group.second;
    }
    ray_ends.clear();
    ray_end_keys.clear();
    for (const auto& [sum, count] : groups) add_ray(sum / count);
  }
  scratch.free_space.Walk(tree, origin, ray_ends, ray_end_keys);

  // 3. Updates: every voxel of the frame (free or hit, disjoint) once, in one pass over the
  // tree in Z-order; the result equals updating them one by one.
  std::vector<std::pair<std::uint64_t, const VoxelAccumulator*>>& voxels = scratch.voxels;
  voxels.clear();
  scratch.free_space.TakeFreeVoxels(scratch.hit_keys, index,
                                    [&](std::uint64_t code) { voxels.emplace_back(code, nullptr); });
  stats.voxels_freed = voxels.size();
  for (std::size_t h = 0; h < hits.size(); ++h) {
    voxels.emplace_back(scratch.hit_codes[h], &hits[h]);
    if (MajorityClassIndex(hits[h].votes) >= 0) ++stats.voxels_with_class;
  }
  SortByCode(&voxels, &scratch.voxels_sort);
  std::vector<std::uint64_t>& codes = scratch.codes;
  codes.resize(voxels.size());
  for (std::size_t i = 0; i < voxels.size(); ++i) codes[i] = voxels[i].first;

  const double decay = opt.class_free_decay_log_odds;
  const bool keep_traversable = opt.free_space_keeps_traversable;
  const float clamp_min_log = tree.getClampingThresMinLog();
  auto update = [&](TravNode& node, std::size_t i) {
    const VoxelAccumulator* acc = voxels[i].second;
    if (acc == nullptr) {
      if (keep_traversable && HeldAsTraversable(node)) return;
      tree.integrateMiss(&node);
      for (float& l : node.class_log_odds) l = DecayTowardsZero(l, decay);
      return;
    }
    tree.integrateHit(&node);
    node.last_seen_ns = timestamp_ns;
    const int winner = MajorityClassIndex(acc->votes);
    if (winner < 0) return;
    for (int k = 0; k < 3; ++k) {
      const double delta = k == winner ? opt.class_hit_log_odds : opt.class_miss_log_odds;
      node.class_log_odds[k] =
          Clamp(node.class_log_odds[k] + delta, opt.class_clamp_min, opt.class_clamp_max);
    }
    ++node.observations;
    const double n = node.observations;
    if (acc->slope_count > 0) {
      const double v = acc->slope_sum / acc->slope_count;
      node.slope_deg = static_cast<float>(node.slope_deg + (v - node.slope_deg) / n);
    }
    if (acc->step_count > 0) {
      const double v = acc->step_sum / acc->step_count;
      node.step_m = static_cast<float>(node.step_m + (v - node.step_m) / n);
      node.max_step_m = std::max(node.max_step_m, static_cast<float>(acc->max_abs_step));
    }
  };
  // A free block at the lower clamp with no class evidence stays as it is under misses.
  auto unchanged = [&](const TravNode& block, std::size_t first, std::size_t last) {
    if (block.getLogOdds() != clamp_min_log) return false;
    for (const float l : block.class_log_odds) {
      if (l != 0.0f) return false;
    }
    for (std::size_t i = first; i < last; ++i) {
      if (voxels[i].second != nullptr) return false;
    }
    return true;
  };
  tree.UpdateLeaves(codes, update, unchanged);
  stats.voxels_hit = hits.size();
  ++impl_->frames_inserted;
  impl_->last_timestamp_ns = timestamp_ns;
  return stats;
}

const MapOptions& TraversabilityMap::options() const { return impl_->options; }
const MapMetadata& TraversabilityMap::metadata() const { return impl_->metadata; }

void TraversabilityMap::set_metadata(MapMetadata metadata) {
  std::string error;
  if (!metadata.vehicle.IsValid(&error)) throw Error("map vehicle: " + error);
  impl_->metadata = std::move(metadata);
}

std::uint64_t TraversabilityMap::frames_inserted() const { return impl_->frames_inserted; }
std::int64_t TraversabilityMap::last_timestamp_ns() const { return impl_->last_timestamp_ns; }
const std::string& TraversabilityMap::software_version() const { return impl_->software_version; }
std::size_t TraversabilityMap::NumNodes() const { return impl_->tree->size(); }

}  // namespace ssta
