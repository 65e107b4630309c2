#pragma once

// A planner's confidence bar: drivable answers the map is less sure of than the planner needs
// are undecided (docs/interfaces.md, section 5; docs/accuracy.md, "What is scored").

#include "ssta/mapping/map_export.h"
#include "ssta/mapping/map_types.h"
#include "ssta/mapping/traversability_map.h"

namespace ssta {

/// `cell` as a planner that drives only on answers at least `min_confidence` sure reads it: a
/// traversable or semi-traversable cell whose confidence is below the bar is undecided, as a
/// column the map cannot judge is (no cost, probability, confidence, slope or step; decided_by
/// kNone). Every other cell, and a drivable one without a confidence (NaN: a class an export
/// step gave), is returned as it is, as `ssta eval footprints --min-confidence` counts it.
/// 0 changes nothing. Throws ssta::Error unless 0 <= min_confidence <= 1.
CellInfo AtConfidenceBar(const CellInfo& cell, double min_confidence);

/// `surface` (empty: map.TopSurfaceAt) read through AtConfidenceBar, for QueryFootprint and
/// QueryPath: a footprint or a path sample with a drivable column under the bar is undecided
/// (an undecided column outranks drivable ones); at 0, `surface` itself. The map, and what
/// `surface` reads, must outlive the source. Throws ssta::Error unless 0 <= min_confidence <= 1.
TraversabilityMap::SurfaceSource WithConfidenceBar(const TraversabilityMap& map, TraversabilityMap::SurfaceSource surface,
                                                   double min_confidence);

/// WithConfidenceBar over `exported` (null: the map as observed), which must outlive the source:
/// what `query --as-exported` and the Python queries' as_exported read.
TraversabilityMap::SurfaceSource WithConfidenceBarOver(const TraversabilityMap& map, const ExportedSurface* exported,
                                                       double min_confidence);

/// AtConfidenceBar on every pixel of a projection: a traversable or semi-traversable pixel whose
/// confidence is below `min_confidence` becomes undecided (class 4; cost, confidence, slope and
/// step NaN). Returns the number of pixels changed. Throws ssta::Error unless
/// 0 <= min_confidence <= 1.
int ApplyConfidenceBar(GridProjection* grid, double min_confidence);

}  // namespace ssta
