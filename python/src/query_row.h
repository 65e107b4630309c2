#pragma once

// One row of ssta.Map.query, in the columns of `ssta query` (x .. confidence), then the surface
// height and whether the map saw a surface there. Shared with the C++ half of the query
// benchmark, so both sides fill the same bytes.

#include <cstdint>

namespace ssta::python {

struct QueryRow {
  double x, y, z;
  std::uint8_t cls;
  double cost, probability, slope_deg, step_m;
  std::uint32_t observations;
  double confidence, height_m;
  bool observed;
};

}  // namespace ssta::python
