// What a voxel says: its class, class probability and cost (the formulas in the class comment
// of TraversabilityMap).

#include "ssta/mapping/traversability_map.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "mapping/map_impl.h"
#include "ssta/core/enum_table.h"

namespace ssta {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double Clamp01(double v) { return std::min(1.0, std::max(0.0, v)); }

/// How far `value` lies into the band (semi, max]: 0 at or below semi, 1 at or above max.
double BandFraction(double value, double semi, double max) {
  if (!std::isfinite(value)) return 0.0;
  if (max > semi) return Clamp01((value - semi) / (max - semi));
  return value > semi ? 1.0 : 0.0;
}

}  // namespace

namespace internal {

CellInfo DescribeCell(const TraversabilityMap& map, const TravOcTree& tree, const TravNode* node,
                      const octomap::OcTreeKey& key) {
  CellInfo cell;
  cell.center = KeyCenter(tree, key);
  if (node == nullptr) return cell;
  cell.observed = true;
  cell.occupancy = octomap::probability(node->getLogOdds());
  cell.occupied = NodeOccupied(tree, *node);
  cell.observations = node->observations;
  cell.last_seen_ns = node->last_seen_ns;
  const double resolution = tree.getResolution();
  if (node->surface_weight > 0.0f) {
    cell.surface_z_m = node->surface_z;
    cell.height_sigma_m = std::max(0.002, 1.0 / std::sqrt(static_cast<double>(node->surface_weight)));
  } else {
    cell.surface_z_m = cell.center.z();
    cell.height_sigma_m = resolution / std::sqrt(12.0);  // somewhere in the voxel
  }
  if (node->observations > 0) {
    cell.frame_mean_slope_deg = node->slope_deg;
    cell.frame_mean_step_m = node->step_m;
    cell.max_step_m = node->max_step_m;
  }
  if (!cell.occupied) return cell;  // free space has no class

  const auto& l = node->class_log_odds;
  if (!HasClassEvidence(l, map.options()) || WithheldVerdict(l, map.options()) != JudgeRule::kNone) {
    cell.cls = TravClass::kUndecided;
    return cell;
  }
  const std::array<double, 3> p = FrameClassProbabilities(l, map.options().class_prior_traversable_log_odds);
  int best = 0;
  for (int k = 1; k < 3; ++k) {
    if (p[k] >= p[best]) best = k;  // ties to the worse class
  }
  cell.cls = static_cast<TravClass>(best + 1);
  cell.decided_by = ClassJudge::kFrames;  // slope_deg and step_m stay NaN: the votes decided
  cell.probability = p[static_cast<std::size_t>(best)];
  cell.confidence = cell.probability;
  cell.cost = map.Cost(cell.cls, cell.slope_deg, cell.step_m, cell.confidence);
  return cell;
}

}  // namespace internal

const char* ClassJudgeName(ClassJudge judge) {
  static const EnumTable<ClassJudge> table("decided_by", {{ClassJudge::kNone, ""},
                                                          {ClassJudge::kFrames, "frames"},
                                                          {ClassJudge::kSurface, "surface"},
                                                          {ClassJudge::kBoth, "both"},
                                                          {ClassJudge::kExport, "export"}});
  return table.Name(judge).c_str();
}

double TraversabilityMap::Cost(TravClass cls, double slope_deg, double step_m, double confidence) const {
  const VehicleOptions& v = impl_->metadata.vehicle;
  switch (cls) {
    case TravClass::kTraversable:
      return std::isfinite(confidence) ? 0.25 * std::clamp(1.5 * (1.0 - confidence), 0.0, 1.0) : 0.0;
    case TravClass::kNonTraversable: return 1.0;
    case TravClass::kSemiTraversable: {
      // Without a slope or step that decided the class (the frames' votes did): mid-band.
      if (!std::isfinite(slope_deg) && !std::isfinite(step_m)) return 0.5;
      const double f = std::max(BandFraction(slope_deg, v.semi_slope_deg, v.max_slope_deg),
                                BandFraction(std::abs(step_m), v.semi_step_m, v.max_step_m));
      return 0.25 + 0.5 * f;
    }
    default: return kNaN;
  }
}

}  // namespace ssta
