#pragma once

#include <array>
#include <string>

#include "ssta/core/classes.h"

namespace ssta {

/// What the vehicle can drive over (INTERFACES section 4, YAML section `vehicle`).
struct VehicleOptions {
  double max_slope_deg = 25.0;   ///< steeper than this: non-traversable [deg]
  double semi_slope_deg = 15.0;  ///< steeper than this (up to max): semi-traversable [deg]
  double max_step_m = 0.20;      ///< step to the ground plane above this: non-traversable [m]
  double semi_step_m = 0.10;     ///< step above this (up to max): semi-traversable [m]
  /// Plausible height of the left camera above the dominant ground plane [m]; a frame whose
  /// ground plane lies outside this band fails the quality check.
  double min_camera_height_m = 0.2;
  double max_camera_height_m = 3.0;

  /// Slope class per eq. 3: <= semi traversable, <= max semi-traversable, else non-traversable.
  TravClass ClassifySlope(double slope_deg) const;
  /// Step class per eq. 5 on the absolute step height [m].
  TravClass ClassifyStep(double step_m) const;
  /// On failure names the offending key (e.g. "semi_slope_deg: must not exceed max_slope_deg").
  bool IsValid(std::string* error) const;
};

/// One key of the vehicle section: its YAML name and its field.
struct VehicleKey {
  const char* name;
  double VehicleOptions::*field;
};
/// Every key of the vehicle section, in the order of INTERFACES section 4.
const std::array<VehicleKey, 6>& VehicleKeys();
/// Whether two values of a vehicle key are the same (relative tolerance 1e-9).
bool SameVehicleValue(double a, double b);
/// The first key (VehicleKeys order) whose values differ between `a` and `b`; null when none.
const VehicleKey* FirstDifferingKey(const VehicleOptions& a, const VehicleOptions& b);

}  // namespace ssta
