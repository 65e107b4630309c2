#include "ssta/mapping/confidence_bar.h"

#include <cstddef>
#include <cstdint>
#include <limits>
#include <utility>

#include "ssta/core/error.h"

namespace ssta {
namespace {

void CheckBar(double min_confidence) {
  if (!(min_confidence >= 0.0 && min_confidence <= 1.0)) {
    throw Error("confidence bar: min_confidence must be a probability in [0, 1]");
  }
}

}  // namespace

CellInfo AtConfidenceBar(const CellInfo& cell, double min_confidence) {
  CheckBar(min_confidence);
  const bool drivable = cell.cls == TravClass::kTraversable || cell.cls == TravClass::kSemiTraversable;
  // NaN compares false: a class without a confidence stays.
  if (!drivable || !(cell.confidence < min_confidence)) return cell;
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  CellInfo barred = cell;
  barred.cls = TravClass::kUndecided;
  barred.cost = barred.probability = barred.confidence = barred.slope_deg = barred.step_m = kNaN;
  barred.decided_by = ClassJudge::kNone;
  return barred;
}

int ApplyConfidenceBar(GridProjection* grid, double min_confidence) {
  CheckBar(min_confidence);
  SSTA_CHECK(grid != nullptr, "ApplyConfidenceBar: grid must not be null");
  const std::size_t n = grid->classes.size();
  SSTA_CHECK(grid->confidence.size() == n && grid->cost.size() == n && grid->slope_deg.size() == n &&
                 grid->step_m.size() == n,
             "ApplyConfidenceBar: the grid's confidence, cost, slope and step must have its classes' size");
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  int changed = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const auto cls = static_cast<TravClass>(grid->classes[i]);
    const bool drivable = cls == TravClass::kTraversable || cls == TravClass::kSemiTraversable;
    if (!drivable || !(grid->confidence[i] < min_confidence)) continue;  // NaN: no say
    grid->classes[i] = static_cast<std::uint8_t>(TravClass::kUndecided);
    grid->cost[i] = grid->confidence[i] = grid->slope_deg[i] = grid->step_m[i] = kNaN;
    ++changed;
  }
  return changed;
}

TraversabilityMap::SurfaceSource WithConfidenceBar(const TraversabilityMap& map, TraversabilityMap::SurfaceSource surface,
                                                   double min_confidence) {
  CheckBar(min_confidence);
  if (min_confidence == 0.0) return surface;  // every answer as it is
  return [&map, surface = std::move(surface), min_confidence](double x, double y) {
    return AtConfidenceBar(surface ? surface(x, y) : map.TopSurfaceAt(x, y), min_confidence);
  };
}

}  // namespace ssta
