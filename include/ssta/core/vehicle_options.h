#pragma once

#include <string>

#include "ssta/core/option_fields.h"
#include "ssta/core/classes.h"

namespace ssta {

/// What the vehicle can drive over (docs/interfaces.md, section 4, YAML section `vehicle`).
struct VehicleOptions {
  double max_slope_deg = 25.0;   ///< steeper than this: non-traversable [deg]
  double semi_slope_deg = 15.0;  ///< steeper than this (up to max): semi-traversable [deg]
  double max_step_m = 0.20;      ///< a height jump above this: non-traversable [m]
  double semi_step_m = 0.10;     ///< a height jump above this (up to max): semi-traversable [m]
  /// A surface point is judged by the height jumps within this horizontal distance of it
  /// (docs/interfaces.md, section 3) [m].
  double step_radius_m = 0.20;
  /// Plausible height of the left camera above the dominant ground plane [m]; a frame whose
  /// ground plane lies outside this band fails the quality check.
  double min_camera_height_m = 0.2;
  double max_camera_height_m = 3.0;
  /// Attitude limits for the costs that depend on the heading (docs/interfaces.md, section 5):
  /// the vehicle's pitch and roll on the plane fitted to the ground under its footprint. They
  /// come on top of the class and never change it. The defaults equal max_slope_deg's default, so
  /// on ground whose class already allows it the heading adds nothing until they are lowered.
  double max_pitch_deg = 25.0;    ///< steepest climb (nose up) along the heading [deg]
  double max_descent_deg = 25.0;  ///< steepest descent (nose down) along the heading [deg]
  double max_roll_deg = 25.0;     ///< steepest cross-slope (either side down) [deg]

  /// Slope class per eq. 3: <= semi traversable, <= max semi-traversable, else non-traversable.
  TravClass ClassifySlope(double slope_deg) const;
  /// Step class per eq. 5 on the absolute step height [m].
  TravClass ClassifyStep(double step_m) const;
  /// Every field: its key, unit, range and meaning (reading, writing and IsValid come from it).
  static const OptionFields<VehicleOptions>& Fields();
  /// The first field out of its range, as "key: requirement" in `*error`.
  bool IsValid(std::string* error) const;
};

/// Throws ssta::Error "<a_says> vehicle.<key> <a's value>, but <b_says> <b's value><b_note>;
/// <advice>" at the first key (Fields order) whose values differ between `a` and `b` (relative tolerance
/// 1e-9); returns when they are the same vehicle. Classes fused or scored for one vehicle must
/// not meet another's: every such check reads the same.
void RequireSameVehicle(const VehicleOptions& a, const std::string& a_says, const VehicleOptions& b,
                        const std::string& b_says, const std::string& b_note, const std::string& advice);

}  // namespace ssta
