#pragma once

// One row of ssta.Map.query, in the columns of `ssta query` (x .. frame_mean_step_m), then the
// surface height and whether the map saw a surface there. Shared with the C++ half of the query
// benchmark, so both sides fill the same bytes.

#include <cstdint>

#include <Eigen/Core>

#include "ssta/mapping/map_types.h"

namespace ssta::python {

/// Characters of the decided_by field: the longest ClassJudgeName ("surface", "frames", ...).
inline constexpr int kDecidedByChars = 7;

struct QueryRow {
  double x, y, z;
  std::uint8_t cls;
  double cost, probability, slope_deg, step_m;
  std::uint32_t observations;
  double confidence;
  /// ClassJudgeName in UTF-32, zero-padded: NumPy's '<U7' on a little-endian machine.
  char32_t decided_by[kDecidedByChars];
  double frame_mean_slope_deg, frame_mean_step_m;
  double height_m;
  bool observed;
};

/// The row of `cell`, answered at `at` (the cell's centre, or the point asked where unobserved).
inline QueryRow MakeQueryRow(const CellInfo& cell, const Eigen::Vector3d& at) {
  QueryRow row{};
  row.x = at.x();
  row.y = at.y();
  row.z = at.z();
  row.cls = static_cast<std::uint8_t>(cell.cls);
  row.cost = cell.cost;
  row.probability = cell.probability;
  row.slope_deg = cell.slope_deg;
  row.step_m = cell.step_m;
  row.observations = cell.observations;
  row.confidence = cell.confidence;
  const char* name = ClassJudgeName(cell.decided_by);
  for (int i = 0; i < kDecidedByChars && name[i] != '\0'; ++i) row.decided_by[i] = static_cast<char32_t>(name[i]);
  row.frame_mean_slope_deg = cell.frame_mean_slope_deg;
  row.frame_mean_step_m = cell.frame_mean_step_m;
  row.height_m = cell.surface_z_m;
  row.observed = cell.observed;
  return row;
}

}  // namespace ssta::python
