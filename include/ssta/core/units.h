#pragma once

// Angles: radians inside the code, degrees in config files and printed reports
// (docs/conventions.md). Names carry their unit as a suffix: `max_step_m`, `roughness_deg`,
// `kMaxRangeM`.

namespace ssta {

inline constexpr double kPi = 3.14159265358979323846;

/// Degrees to radians.
constexpr double DegToRad(double deg) { return deg * kPi / 180.0; }

/// Radians to degrees.
constexpr double RadToDeg(double rad) { return rad * (180.0 / kPi); }

}  // namespace ssta
