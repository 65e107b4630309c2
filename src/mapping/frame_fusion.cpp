// The fusion of one frame into the map (TraversabilityMap::InsertFrame): the points grouped by
// voxel, the rays from the sensor to them and the voxels those pass, then one update of every
// voxel the frame touched, in one pass over the tree.

#include "ssta/mapping/traversability_map.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "mapping/free_space_walk.h"
#include "mapping/map_impl.h"
#include "mapping/voxel_containers.h"

namespace ssta {
namespace internal {
namespace {

/// Per-voxel accumulator of one frame's in-range points.
struct VoxelAccumulator {
  Eigen::Vector3d sum_p = Eigen::Vector3d::Zero();
  std::uint32_t points = 0;
  std::array<std::uint32_t, 3> votes{};  // classes 1..3
  std::array<float, 3> vote_weights{};   // their points' vote_weight, summed
  double slope_sum = 0.0;
  std::uint32_t slope_count = 0;
  double step_sum = 0.0;
  std::uint32_t step_count = 0;
  double max_abs_step = -1.0;  // < 0: none
  double height_sum = 0.0;
  std::uint32_t height_count = 0;
  double surface_z_sum = 0.0;    // world z of the points that carry a height sigma
  double surface_var_sum = 0.0;  // their height variances
  double surface_xy_var_sum = 0.0;  // their horizontal variances
  std::uint32_t surface_count = 0;

  /// Adds `point`, whose position in double is `p`.
  void Add(const ClassifiedPoint& point, const Eigen::Vector3d& p) {
    sum_p += p;
    ++points;
    if (std::isfinite(point.height_sigma_m)) {
      surface_z_sum += p.z();
      surface_var_sum += static_cast<double>(point.height_sigma_m) * point.height_sigma_m;
      surface_xy_var_sum += static_cast<double>(point.horizontal_sigma_m) * point.horizontal_sigma_m;
      ++surface_count;
    }
    if (std::isfinite(point.height_m)) {
      height_sum += point.height_m;
      ++height_count;
    }
    const int c = static_cast<int>(point.cls);
    if (c < 1 || c > 3) return;  // unknown, undecided, don't-care: occupancy only
    ++votes[c - 1];
    vote_weights[c - 1] += point.vote_weight;
    if (std::isfinite(point.slope_deg)) {
      slope_sum += point.slope_deg;
      ++slope_count;
    }
    if (std::isfinite(point.step_m)) {
      step_sum += point.step_m;
      ++step_count;
      max_abs_step = std::max(max_abs_step, static_cast<double>(std::abs(point.step_m)));
    }
  }
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

  void Add(const Eigen::Vector3d& p) {
    sum_p += p;
    ++points;
  }
};

/// A voxel of the frame: its Morton code and its accumulator (null: a free voxel).
using FrameVoxel = std::pair<std::uint64_t, const VoxelAccumulator*>;

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

/// The worst class index whose votes, counted with the worse classes', reach `share` of all
/// votes; the plurality when `share` is 0 (MapOptions::class_worst_share); -1 when there are none.
int VoxelVerdictIndex(const std::array<std::uint32_t, 3>& votes, double share) {
  if (share <= 0.0) return MajorityClassIndex(votes);
  const double total = static_cast<double>(votes[0]) + votes[1] + votes[2];
  if (total == 0.0) return -1;
  double worse = 0.0;
  for (int k = 2; k > 0; --k) {
    worse += votes[k];
    if (worse > 0.0 && worse >= share * total) return k;
  }
  return 0;
}

float Clamp(double v, double lo, double hi) { return static_cast<float>(std::min(hi, std::max(lo, v))); }

float DecayTowardsZero(float l, double decay) {
  if (l > 0.0f) return static_cast<float>(std::max(0.0, l - decay));
  if (l < 0.0f) return static_cast<float>(std::min(0.0, l + decay));
  return l;
}

}  // namespace

/// InsertFrame's buffers, by step.
struct InsertScratch {
  // 1. The frame's points grouped by voxel.
  VoxelIndex voxel_index;                    ///< the frame's voxels -> accumulators
  std::vector<VoxelAccumulator> hits;        ///< in-range voxels, in order of first point
  std::vector<std::uint64_t> hit_codes;      ///< their Morton codes
  std::vector<octomap::OcTreeKey> hit_keys;  ///< and keys
  std::vector<FarAccumulator> far;           ///< voxels of points beyond range
  std::vector<Eigen::Vector3d> no_return;    ///< directions of rays that ranged nothing (unit)
  // 2. The rays and the voxels they pass.
  std::vector<octomap::point3d> ray_ends;  ///< where each ray stops
  std::vector<octomap::OcTreeKey> ray_end_keys;
  std::vector<octomap::point3d> open_ends;  ///< where each ray that ranged nothing stops at the latest
  std::vector<octomap::OcTreeKey> open_end_keys;
  VoxelIndex ray_cells;  ///< free_space_ray_cell > 1: cell -> group
  std::vector<std::pair<Eigen::Vector3d, std::uint32_t>> ray_groups;  ///< sum of ends, count
  FreeSpaceWalk free_space;  ///< the voxels the rays pass
  // 3. Every voxel of the frame, sorted by Morton code (voxels_sort: the sort's working space).
  std::vector<FrameVoxel> voxels, voxels_sort;
  std::vector<std::uint64_t> codes;  ///< the voxels' codes, as TravOcTree::UpdateLeaves takes them
};

namespace {

/// The steps of one InsertFrame call, in this order: GroupPointsByVoxel, PlaceRayEnds,
/// MergeRayEndsPerCell (only when free_space_ray_cell > 1), WalkRays, CollectVoxels,
/// UpdateVoxels. They share the tree, the options, the sensor origin and the buffers, and count
/// into the frame's InsertStats.
class FrameFusion {
 public:
  /// Precondition: `sensor_origin_world` is finite and inside the map.
  /// `vehicle`: the map's, whose max_step_m and step_radius_m scale the class votes' noise
  /// weighting.
  FrameFusion(TravOcTree& tree, const MapOptions& options, const VehicleOptions& vehicle,
              const Eigen::Vector3d& sensor_origin_world, InsertScratch* scratch, InsertStats* stats)
      : tree_(tree), options_(options), vote_sigma_m_(options.class_vote_noise_steps * vehicle.max_step_m),
        vote_smear_m_(options.class_vote_smear_radii * vehicle.step_radius_m), origin_world_(sensor_origin_world),
        scratch_(*scratch), stats_(*stats) {}

  /// 1. One accumulator per voxel of the in-range points (hits), one per voxel of the points
  /// beyond range (far), keyed by the voxel's Morton code.
  void GroupPointsByVoxel(const std::vector<ClassifiedPoint>& points);
  /// 2. Where each ray ends: one ray per hit voxel (to the mean of its points, shortened) and
  /// one per far voxel (up to the range).
  void PlaceRayEnds();
  /// One ray per cell of free_space_ray_cell^3 voxels holding ray ends, to their mean.
  void MergeRayEndsPerCell();
  /// Every voxel the rays pass, once (FreeSpaceWalk).
  void WalkRays();
  /// 3. Every voxel of the frame once, free or hit (disjoint: hit voxels are not free), sorted
  /// by Morton code.
  void CollectVoxels();
  /// Updates the collected voxels in one pass over the tree in Z-order; the result equals
  /// updating them one by one.
  void UpdateVoxels(std::int64_t timestamp_ns);

 private:
  // Called per ray and per voxel: defined inline, so that they compile into the loops.
  /// Appends a ray to `end` to `ends` and `end_keys`, unless `end` lies outside the map (as
  /// computeRayKeys: no ray).
  void AddRay(const Eigen::Vector3d& end, std::vector<octomap::point3d>* ends,
              std::vector<octomap::OcTreeKey>* end_keys) const;
  /// A ray to a point's end: AddRay into the rays to points.
  void AddRay(const Eigen::Vector3d& end) { AddRay(end, &scratch_.ray_ends, &scratch_.ray_end_keys); }
  /// A ray passed the voxel `node`: occupancy miss and class log-odds decay towards 0, unless
  /// free_space_keeps_traversable spares it as a voxel held as traversable.
  void UpdateFree(TravNode* node) const;
  /// Points of the frame, accumulated in `acc`, fell in the voxel `node`: occupancy hit and
  /// last_seen_ns; with a verdict also the class log-odds, the observation count and the means.
  void UpdateHit(const VoxelAccumulator& acc, std::int64_t timestamp_ns, TravNode* node) const;

  /// The weight of a frame's class vote for a voxel (class_vote_noise_steps,
  /// class_vote_smear_radii).
  double VoteWeight(const VoxelAccumulator& acc) const;

  TravOcTree& tree_;
  const MapOptions& options_;
  double vote_sigma_m_;  ///< height sigma at which a vote counts half; 0: every vote counts 1
  double vote_smear_m_;  ///< horizontal sigma at which a vote counts half; 0: no such weighting
  const Eigen::Vector3d& origin_world_;
  InsertScratch& scratch_;
  InsertStats& stats_;
};

void FrameFusion::GroupPointsByVoxel(const std::vector<ClassifiedPoint>& points) {
  VoxelIndex& index = scratch_.voxel_index;
  std::vector<VoxelAccumulator>& hits = scratch_.hits;
  std::vector<FarAccumulator>& far = scratch_.far;
  index.Clear();
  hits.clear();
  scratch_.hit_codes.clear();
  scratch_.hit_keys.clear();
  far.clear();
  scratch_.no_return.clear();
  const RangeTest range(options_.max_range_m);
  std::uint64_t last_code = ~std::uint64_t{0};
  VoxelIndex::Entry* entry = nullptr;  // of last_code (image neighbours share voxels)
  for (const ClassifiedPoint& point : points) {
    const Eigen::Vector3d p = point.world_p.cast<double>();
    if (point.no_return) {
      const Eigen::Vector3d d = p - origin_world_;
      const double length = d.norm();
      if (std::isfinite(length) && length > 0.0) {
        scratch_.no_return.push_back(d / length);
        ++stats_.rays_without_return;
      } else {
        ++stats_.points_rejected;
      }
      continue;
    }
    octomap::OcTreeKey key;
    if (!p.allFinite() || !tree_.CoordToKeyChecked(p.x(), p.y(), p.z(), &key)) {
      ++stats_.points_rejected;
      continue;
    }
    const std::uint64_t code = TravOcTree::MortonCode(key);
    if (code != last_code) {
      entry = &index.FindOrInsert(code);
      last_code = code;
    }
    if (BeyondRange((p - origin_world_).squaredNorm(), range)) {
      if (entry->far < 0) {
        entry->far = static_cast<std::int32_t>(far.size());
        far.emplace_back();
      }
      far[static_cast<std::size_t>(entry->far)].Add(p);
      ++stats_.points_beyond_range;
      continue;
    }
    if (entry->hit < 0) {
      entry->hit = static_cast<std::int32_t>(hits.size());
      hits.emplace_back();
      scratch_.hit_codes.push_back(code);
      scratch_.hit_keys.push_back(key);
    }
    hits[static_cast<std::size_t>(entry->hit)].Add(point, p);
    ++stats_.points_hit;
  }
}

inline void FrameFusion::AddRay(const Eigen::Vector3d& end, std::vector<octomap::point3d>* ends,
                                std::vector<octomap::OcTreeKey>* end_keys) const {
  const octomap::point3d e(static_cast<float>(end.x()), static_cast<float>(end.y()),
                           static_cast<float>(end.z()));
  octomap::OcTreeKey key_end;
  if (!tree_.coordToKeyChecked(e, key_end)) return;  // as computeRayKeys: no ray
  ends->push_back(e);
  end_keys->push_back(key_end);
}

void FrameFusion::PlaceRayEnds() {
  const MapOptions& opt = options_;
  scratch_.ray_ends.clear();
  scratch_.ray_end_keys.clear();
  // Rays to surface points stop short where they graze the surface (free_space_clearance_m);
  // rays to obstacles stop only a depth-noise band short (free_space_obstacle_shortening_per_m2).
  constexpr double kMaxShorteningM = 2.0;
  for (const VoxelAccumulator& acc : scratch_.hits) {
    const Eigen::Vector3d end = acc.sum_p / acc.points;
    const Eigen::Vector3d d = end - origin_world_;
    const double length = d.norm();
    if (opt.free_space_clearance_m > 0.0 && length > 1e-9) {
      const double sin_elevation = std::max(std::abs(d.z()) / length, 1e-3);
      double shorten = std::min(opt.free_space_clearance_m / sin_elevation, kMaxShorteningM);
      if (EndsOnAnObstacle(acc, opt)) shorten = std::min(shorten, opt.free_space_obstacle_shortening_per_m2 * length * length);
      if (shorten < length) AddRay(origin_world_ + d * ((length - shorten) / length));
    } else {
      AddRay(end);
    }
  }
  for (const FarAccumulator& acc : scratch_.far) {
    const Eigen::Vector3d direction = (acc.sum_p / acc.points - origin_world_).normalized();
    AddRay(origin_world_ + direction * opt.max_range_m);
  }
  scratch_.open_ends.clear();
  scratch_.open_end_keys.clear();
  for (const Eigen::Vector3d& direction : scratch_.no_return) {
    AddRay(origin_world_ + direction * opt.max_range_m, &scratch_.open_ends, &scratch_.open_end_keys);
  }
}

void FrameFusion::MergeRayEndsPerCell() {
  const int shift = options_.free_space_ray_cell == 2 ? 1 : options_.free_space_ray_cell == 4 ? 2 : 3;
  std::vector<octomap::point3d>& ray_ends = scratch_.ray_ends;
  std::vector<octomap::OcTreeKey>& ray_end_keys = scratch_.ray_end_keys;
  VoxelIndex& cells = scratch_.ray_cells;
  auto& groups = scratch_.ray_groups;
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
  for (const auto& [sum, count] : groups) AddRay(sum / count);
}

void FrameFusion::WalkRays() {
  const octomap::point3d origin(static_cast<float>(origin_world_.x()),
                                static_cast<float>(origin_world_.y()),
                                static_cast<float>(origin_world_.z()));
  scratch_.free_space.Walk(tree_, origin, scratch_.ray_ends, scratch_.ray_end_keys, scratch_.open_ends,
                           scratch_.open_end_keys, octomap::logodds(options_.free_space_no_return_stop_prob));
}

void FrameFusion::CollectVoxels() {
  std::vector<FrameVoxel>& voxels = scratch_.voxels;
  const std::vector<VoxelAccumulator>& hits = scratch_.hits;
  voxels.clear();
  scratch_.free_space.TakeFreeVoxels(scratch_.hit_keys, scratch_.voxel_index,
                                     [&](std::uint64_t code) { voxels.emplace_back(code, nullptr); });
  stats_.voxels_freed = voxels.size();
  for (std::size_t h = 0; h < hits.size(); ++h) {
    voxels.emplace_back(scratch_.hit_codes[h], &hits[h]);
    if (MajorityClassIndex(hits[h].votes) >= 0) ++stats_.voxels_with_class;
  }
  stats_.voxels_hit = hits.size();
  SortByCode(&voxels, &scratch_.voxels_sort);
  std::vector<std::uint64_t>& codes = scratch_.codes;
  codes.resize(voxels.size());
  for (std::size_t i = 0; i < voxels.size(); ++i) codes[i] = voxels[i].first;
}

inline void FrameFusion::UpdateFree(TravNode* node) const {
  if (options_.free_space_keeps_traversable && HeldAsTraversable(*node)) return;
  tree_.integrateMiss(node);
  for (float& l : node->class_log_odds) l = DecayTowardsZero(l, options_.class_free_decay_log_odds);
  node->surface_weight *= 0.5f;  // a surface seen through loses its say to the next one seen
}

inline double FrameFusion::VoteWeight(const VoxelAccumulator& acc) const {
  if (acc.surface_count == 0) return 1.0;
  double weight = 1.0;
  if (vote_sigma_m_ > 0.0) {
    const double variance = acc.surface_var_sum / acc.surface_count;
    weight /= 1.0 + variance / (vote_sigma_m_ * vote_sigma_m_);
  }
  // Points given a height sigma but no horizontal one (InsertFrame's callers may) are not
  // weighed by it.
  const double xy_variance = acc.surface_xy_var_sum / acc.surface_count;
  if (vote_smear_m_ > 0.0 && std::isfinite(xy_variance)) {
    weight /= 1.0 + xy_variance / (vote_smear_m_ * vote_smear_m_);
  }
  return weight;
}

inline void FrameFusion::UpdateHit(const VoxelAccumulator& acc, std::int64_t timestamp_ns, TravNode* node) const {
  const MapOptions& opt = options_;
  tree_.integrateHit(node);
  node->last_seen_ns = timestamp_ns;
  if (acc.surface_count > 0) {
    // One measurement per frame: the points of a frame in one voxel share their errors (the
    // matcher's window spans them), so they count once, with their mean variance.
    const double z = acc.surface_z_sum / acc.surface_count;
    const double weight = acc.surface_count / acc.surface_var_sum;
    const float xy_sigma = static_cast<float>(std::sqrt(acc.surface_xy_var_sum / acc.surface_count));
    if (node->surface_weight == 0.0f || xy_sigma < node->surface_xy_sigma_m) node->surface_xy_sigma_m = xy_sigma;
    const double total = node->surface_weight + weight;
    node->surface_z = static_cast<float>((node->surface_weight * node->surface_z + weight * z) / total);
    // Frames that see a voxel from alike ranges share the matcher's bias there: together they
    // are worth a few views, not all of them, so the weight stops at four of this frame's.
    node->surface_weight = static_cast<float>(std::min(total, std::max<double>(node->surface_weight, 4.0 * weight)));
  }
  const int winner = VoxelVerdictIndex(acc.votes, opt.class_worst_share);
  if (winner < 0) return;
  // Votes for an obstacle weigh more (class_obstacle_gain); far, noisy views less (VoteWeight).
  const double weight = VoteWeight(acc) * (winner == 2 ? opt.class_obstacle_gain : 1.0) *
                        acc.vote_weights[winner] / acc.votes[winner];
  for (int k = 0; k < 3; ++k) {
    const double delta = weight * (k == winner ? opt.class_hit_log_odds : opt.class_miss_log_odds);
    node->class_log_odds[k] =
        Clamp(node->class_log_odds[k] + delta, opt.class_clamp_min, opt.class_clamp_max);
  }
  ++node->observations;
  const double n = node->observations;
  if (acc.slope_count > 0) {
    const double v = acc.slope_sum / acc.slope_count;
    node->slope_deg = static_cast<float>(node->slope_deg + (v - node->slope_deg) / n);
  }
  if (acc.step_count > 0) {
    const double v = acc.step_sum / acc.step_count;
    node->step_m = static_cast<float>(node->step_m + (v - node->step_m) / n);
    node->max_step_m = std::max(node->max_step_m, static_cast<float>(acc.max_abs_step));
  }
}

void FrameFusion::UpdateVoxels(std::int64_t timestamp_ns) {
  const std::vector<FrameVoxel>& voxels = scratch_.voxels;
  auto update = [&](TravNode& node, std::size_t i) {
    const VoxelAccumulator* acc = voxels[i].second;
    if (acc == nullptr) {
      UpdateFree(&node);
    } else {
      UpdateHit(*acc, timestamp_ns, &node);
    }
  };
  // A free block at the lower clamp with no class evidence stays as it is under misses.
  const float clamp_min_log = tree_.getClampingThresMinLog();
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
  tree_.UpdateLeaves(scratch_.codes, update, unchanged);
}

}  // namespace
}  // namespace internal

InsertStats TraversabilityMap::InsertFrame(const std::vector<ClassifiedPoint>& points,
                                           const Eigen::Vector3d& sensor_origin_world,
                                           std::int64_t timestamp_ns) {
  internal::TravOcTree& tree = *impl_->tree;
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
  internal::FrameFusion fusion(tree, impl_->options, impl_->metadata.vehicle, sensor_origin_world,
                               impl_->insert_scratch.get(), &stats);
  fusion.GroupPointsByVoxel(points);
  fusion.PlaceRayEnds();
  if (impl_->options.free_space_ray_cell > 1) fusion.MergeRayEndsPerCell();
  fusion.WalkRays();
  fusion.CollectVoxels();
  fusion.UpdateVoxels(timestamp_ns);
  ++impl_->frames_inserted;
  const std::vector<Eigen::Vector3d>& path = impl_->sensor_path.points();
  if (path.empty() || (path.back() - sensor_origin_world).norm() >= impl_->options.resolution_m) {
    impl_->sensor_path.Append(sensor_origin_world);
  }
  impl_->last_timestamp_ns = timestamp_ns;
  return stats;
}

}  // namespace ssta
