// A project outside SSTA: find_package(ssta), link ssta::ssta, use the public API.
#include <cmath>
#include <iostream>

#include "ssta/mapping/traversability_map.h"
#include "ssta/pipeline/config.h"

int main() {
  const ssta::Config config;
  std::string error;
  if (!config.IsValid(&error)) return 1;
  const ssta::TraversabilityMap map;  // empty: every column unobserved
  const ssta::CellInfo cell = map.TopSurfaceAt(1.0, 2.0);
  std::cout << "class " << static_cast<int>(cell.cls) << "\n";
  return cell.cls == ssta::TravClass::kUnknown && std::isnan(cell.cost) ? 0 : 2;
}
