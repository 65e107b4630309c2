#pragma once

// Costs that depend on the heading: the pitch and roll a vehicle would have on the ground under
// its footprint, judged against the vehicle's attitude limits (VehicleOptions::max_pitch_deg,
// max_descent_deg, max_roll_deg). They come on top of a cell's class, which keeps its meaning
// (docs/interfaces.md, section 3).

#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ssta/core/vehicle_options.h"
#include "ssta/core/classes.h"
#include "ssta/core/image.h"
#include "ssta/mapping/map_types.h"

namespace ssta {

/// The attitude of a vehicle standing on the plane fitted to the ground under its footprint.
struct VehicleAttitude {
  /// Pitch [deg]: the angle of the vehicle's forward axis (the heading, on the plane) above
  /// the horizontal; positive nose up. NaN without a plane.
  double pitch_deg = std::numeric_limits<double>::quiet_NaN();
  /// Roll [deg] about the forward axis (ZYX Euler angles of the body frame: x forward, z the
  /// plane's normal); positive when the left side is higher. NaN without a plane.
  double roll_deg = std::numeric_limits<double>::quiet_NaN();
  int heights = 0;  ///< fused heights the plane was fitted to
  /// Against the vehicle's limits, with f the largest of pitch / max_pitch_deg (nose up),
  /// -pitch / max_descent_deg (nose down) and |roll| / max_roll_deg: traversable for f <= 0.8,
  /// semi-traversable for 0.8 < f <= 1, non-traversable beyond; kUnknown without a plane.
  TravClass verdict = TravClass::kUnknown;
  /// The cost of the attitude alone: 0 for f <= 0.8, 0.25 + 0.5 (f - 0.8) / 0.2 in the band
  /// (as a semi-traversable cell's, [0.25, 0.75]), 1 beyond; NaN without a plane.
  double cost = std::numeric_limits<double>::quiet_NaN();

  /// Whether a plane was fitted and the verdict is not non-traversable.
  bool WithinLimits() const { return verdict == TravClass::kTraversable || verdict == TravClass::kSemiTraversable; }
};

/// Fits the plane z = a + b x + c y to `ground` (x, y, z in W [m]) by least squares and returns
/// the attitude on it of a vehicle heading `yaw` [rad, from +x towards +y], judged against
/// `vehicle`'s limits. With gradient g = (b, c), heading d = (cos yaw, sin yaw) and left
/// n = (-sin yaw, cos yaw): pitch = atan(g.d), roll = atan2(g.n, sqrt(1 + (g.d)^2)). Needs at
/// least 3 points whose x, y are not (nearly) collinear (the smaller eigenvalue of their
/// covariance at least 1e-6 m^2); otherwise pitch and roll are NaN and the verdict kUnknown.
/// Non-finite points are skipped.
VehicleAttitude AttitudeOnGround(const std::vector<Eigen::Vector3d>& ground, double yaw, const VehicleOptions& vehicle);

/// The verdict and cost of a pitch and roll [deg] (VehicleAttitude's rule); NaN: kUnknown, cost NaN.
void JudgeAttitude(const VehicleOptions& vehicle, VehicleAttitude* attitude);

/// A cell's cost for one heading: its class cost, raised to the attitude's cost where that is
/// higher (so to 1 where the attitude is beyond the limits). NaN where the class cost is NaN
/// (no class 1..3, or a filled hole); the class cost alone where the attitude is unknown.
double HeadingCost(double class_cost, const VehicleAttitude& attitude);

/// How the heading cost layers are made.
struct HeadingCostOptions {
  /// Headings, evenly spaced from yaw 0 (+x) towards +y: heading k has yaw 360 k / headings
  /// [deg]. 0: no heading layers.
  int headings = 0;
  /// The vehicle footprint the plane is fitted under, centred at each cell: its side along the
  /// heading and across it [m].
  double footprint_length_m = 1.0;
  double footprint_width_m = 0.6;

  /// headings in 0..360, footprint sides in (0, 100] m; else "key: requirement" in `*error`.
  bool IsValid(std::string* error) const;
};

/// Heading k's yaw [deg] (360 k / headings) as layer and file names print it: "%g" ("0",
/// "45", "22.5").
std::string HeadingName(int k, int headings);

/// The cost layers of `grid` per heading (options.headings of them, heading k at yaw
/// 2 pi k / headings): at each pixel, HeadingCost of its cost and the attitude on the grid's fused
/// surface heights (`grid.surface_z_m`) of the pixels the footprint centred at the pixel touches
/// (the pixels whose squares overlap the rectangle, the rule of TraversabilityMap::QueryFootprint,
/// so at the map's resolution both fit the same columns; pixels beyond the grid do not count),
/// judged against `vehicle`.
/// Throws ssta::Error naming the key when options are invalid, or when the grid has no
/// surface_z_m layer of its size.
std::vector<ImageF> HeadingCosts(const GridProjection& grid, const VehicleOptions& vehicle,
                                 const HeadingCostOptions& options);

}  // namespace ssta
