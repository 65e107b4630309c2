#include "ssta/mapping/confidence_bar.h"

#include <cstddef>
#include <cstdint>
#include <functional>
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

/// Whether a cell of class `cls` and `confidence` falls below the bar: a drivable one less sure
/// than it (NaN compares false: a class without a confidence stays).
bool BelowBar(TravClass cls, double confidence, double min_confidence) {
  return IsDrivable(cls) && confidence < min_confidence;
}

}  // namespace

CellInfo AtConfidenceBar(const CellInfo& cell, double min_confidence) {
  CheckBar(min_confidence);
  if (!BelowBar(cell.cls, cell.confidence, min_confidence)) return cell;
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
    if (!BelowBar(static_cast<TravClass>(grid->classes[i]), grid->confidence[i], min_confidence)) continue;
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

TraversabilityMap::SurfaceSource WithConfidenceBarOver(const TraversabilityMap& map, const ExportedSurface* exported,
                                                       double min_confidence) {
  return WithConfidenceBar(map, exported != nullptr ? TraversabilityMap::SurfaceSource(std::cref(*exported)) : nullptr,
                           min_confidence);
}

}  // namespace ssta
