#pragma once

// The verdict of a map cell from the fused surface around it: the rule of docs/interfaces.md,
// section 3 (slope of the surface, height jumps within step_radius_m) applied to surface heights
// that carry their stereo uncertainty, so that the verdict comes with how sure it is.

#include <array>
#include <vector>

#include <Eigen/Core>

#include "ssta/core/vehicle_options.h"

namespace ssta {

/// One map column's top surface near the cell being judged.
struct SurfaceSample {
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();  ///< column centre in W [m]
  double height_m = 0.0;                         ///< fused height of its top surface [m]
  double sigma_m = 0.0;                          ///< 1-sigma of that height [m], > 0
  /// How far off its column that height may belong, 1-sigma [m] (range noise smears far
  /// surfaces sideways).
  double xy_sigma_m = 0.0;
};

/// What the surface around a cell says about it.
struct SurfaceVerdict {
  bool determined = false;  ///< enough columns around the cell to fit a surface
  /// The columns' heights may come from more than half the step radius away (stereo's range
  /// error smears them sideways, their median horizontal sigma says): they show no slope or
  /// step of this cell, and the surface is not determined.
  bool smeared = false;
  /// The median of the columns' xy_sigma_m [m] (0 when too few columns were seen).
  double xy_sigma_m = 0.0;
  /// Share of the disc's columns that hold a fused height, in [0, 1]: below 1 the surface
  /// cannot vouch for ground next to what it does not see (a lip's hidden side, a rock's top).
  double coverage = 0.0;
  double slope_deg = 0.0;   ///< slope of the fitted local plane [deg]
  double slope_sigma_deg = 0.0;
  /// The largest height jump within the step radius not explained by that plane [m]: the
  /// range of the columns' residuals, each taken one sigma towards the plane.
  double step_m = 0.0;
  double step_sigma_m = 0.0;
  /// Probability of traversable, semi-traversable and non-traversable (the worse of the slope
  /// and the step classes), from the two estimates and their sigmas; sums to 1.
  std::array<double, 3> probability{1.0 / 3, 1.0 / 3, 1.0 / 3};
};

/// The class distribution of the worse of two independent verdicts `a` and `b` (probabilities
/// of traversable, semi-traversable, non-traversable): P(class <= k) is the product of the two.
std::array<double, 3> WorseOfClasses(const std::array<double, 3>& a, const std::array<double, 3>& b);

/// The radius [m] about a cell's centre within which the centres of the columns that judge it
/// lie: `step_radius_m` plus half a cell. A cell's class is the worst class of the ground in it
/// (docs/interfaces.md, section 3), and its ground reaches half a cell from its centre, so a
/// jump up to half a cell beyond the step radius of the centre is within the step radius of
/// some of that ground. A straight edge a step radius from the centre then has two columns or
/// more beyond it in the disc, as LargestJump needs to see it.
double SurfaceDiscRadius(double step_radius_m, double spacing_m);

/// Judges the cell at `centre` from the `samples` of the columns (a grid `spacing_m` apart)
/// whose centres lie within SurfaceDiscRadius of it, the cell's own included. A plane is
/// fitted by iteratively reweighted least squares (weights 1 / sigma^2, Huber on the residuals)
/// to the columns on the cell's side of any jump: its slope is the slope class's; the range of
/// the columns' heights about it (LargestJump) the step's. Not determined when fewer than half
/// the disc's columns, or fewer than 4, are seen, or they lie on one line, or their heights
/// are smeared sideways (SurfaceVerdict::smeared).
SurfaceVerdict JudgeSurface(const Eigen::Vector2d& centre, const std::vector<SurfaceSample>& samples,
                            double spacing_m, const VehicleOptions& vehicle);

/// An ellipse about a cell's centre in the map's x-y plane: semi-axis `along_m` [m] along the
/// unit vector `axis`, `across_m` across it (a disc when the two are equal).
struct SurfaceRegion {
  Eigen::Vector2d axis = Eigen::Vector2d::UnitX();
  double along_m = 0.0;
  double across_m = 0.0;
  /// Whether the point `offset` [m] from the centre lies within the ellipse (its edge included).
  bool Contains(const Eigen::Vector2d& offset) const;
};

/// The region a smeared surface is judged over (JudgeSmearedSurface): stereo's range error moves
/// a point along its ray, so the step radius's disc is widened along the horizontal direction
/// `ray` from the view to the cell by the columns' horizontal sigma `xy_sigma_m`, at most to
/// twice the step radius, and not across it (a ray's direction is known to a pixel). Both
/// semi-axes add half a cell, as SurfaceDiscRadius does. A zero `ray` widens it every way.
SurfaceRegion SmearedRegion(double step_radius_m, double spacing_m, double xy_sigma_m, const Eigen::Vector2d& ray);

/// JudgeSurface for a cell whose heights are smeared sideways, over the columns of `samples`
/// that lie in `region` (SmearedRegion), but for the step each side of a jump must hold an
/// eighth of those columns (JudgeSurface: two), so that a stray column or two of far noise
/// makes none. Stereo cannot place a far jump within the step radius, but it measures the
/// heights on its two sides: a jump over max_step_m within the smear of the cell's own heights
/// may lie within the step radius of its ground. The verdict keeps `smeared` set.
SurfaceVerdict JudgeSmearedSurface(const Eigen::Vector2d& centre, const std::vector<SurfaceSample>& samples,
                                   double spacing_m, const SurfaceRegion& region, const VehicleOptions& vehicle);

}  // namespace ssta
