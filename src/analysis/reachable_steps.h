#pragma once

#include <vector>

#include <Eigen/Core>

#include "ssta/analysis/surface_analyzer.h"
#include "ssta/core/vehicle_options.h"
#include "ssta/core/classes.h"
#include "ssta/core/image.h"

namespace ssta::internal {

/// Step classes by reachability from the ground segment, one entry per segment.
struct ReachableSteps {
  /// Traversable, semi-traversable or non-traversable (unreached); empty when not computed.
  std::vector<TravClass> step_class;
  /// The mean boundary height jump of the crossing that reached the segment [m]: 0 for the
  /// ground, NaN when unreached.
  std::vector<double> jump_m;
};

/// The steps of StepReference::kReachable (and kReachableLarge, where it applies): a segment's
/// class is the smallest class over the ways to reach it from the ground segment `ground_id`
/// across segment boundaries. Crossing a boundary costs the median height jump (along the unit
/// vector `up`) between its 4-adjacent points; a way leads on only from segments that have a
/// plane and are drivable by slope at the way's class. `segments` are AnalyzeSurfaces' segments
/// with their planes and slope classes set, in id order.
ReachableSteps ReachableStepClasses(const Image3f& cloud, const ImageI32& ids,
                                    const std::vector<SegmentResult>& segments, int ground_id,
                                    const Eigen::Vector3d& up, const VehicleOptions& vehicle);

}  // namespace ssta::internal
