#pragma once

#include <vector>

#include <Eigen/Geometry>

#include "ssta/core/vehicle_options.h"
#include "ssta/core/classes.h"
#include "ssta/synth/scene.h"

namespace ssta::synth {

/// The true class of every surface point of a Scene by the rule of docs/interfaces.md,
/// section 3: a point is judged by the geometry within `vehicle.step_radius_m` of it.
///  - step at p: the range (highest minus lowest) of the heights of the objects and pits
///    within step_radius_m of p, each measured from the smooth base ground under it (boxes,
///    curbs, rocks, trunks and logs above it; pits, trenches and drop-offs below it). Smooth
///    ground, however steep, has no step; level ground is traversable at any height.
///  - slope at p: the angle of the surface normal to up; on a face (a pit's wall, or the side of
///    an object steeper than max_slope_deg) the slope of the base ground at its foot, so that a
///    face is as bad as the jump it spans.
///  - class: the worse of the two.
/// Heights are sampled on a grid of at most step_radius_m / 4 over `region`; a point outside
/// it has no truth. Immutable once built; thread-safe to read.
class TerrainTruth {
 public:
  /// Samples the top surface over `region` (world x, y [m]) on `threads` threads (0: all).
  TerrainTruth(const Scene& scene, const VehicleOptions& vehicle, const Eigen::AlignedBox2d& region, int threads = 0);

  /// The class of a visible surface point; kDontCare (255) outside the region.
  std::uint8_t ClassOf(const SurfaceHit& hit) const;
  /// The class of the top surface at (x, y); kDontCare (255) outside the region.
  std::uint8_t ClassAt(double x, double y) const;
  /// The step at (x, y) [m]; NaN outside the region.
  double StepAt(double x, double y) const;
  double resolution_m() const { return resolution_m_; }

  static constexpr std::uint8_t kDontCare = 255;

 private:
  bool Cell(double x, double y, int* i, int* j) const;
  double SlopeDeg(const SurfaceHit& hit) const;

  const Scene& scene_;
  VehicleOptions vehicle_;
  Eigen::Vector2d origin_;  // lower-left corner of cell (0, 0)
  double resolution_m_ = 0.05;
  int nx_ = 0, ny_ = 0;
  std::vector<float> step_m_;  // per cell, row-major from origin_ (i along x, j along y)
};

}  // namespace ssta::synth
