// A planner outside SSTA that takes the map alone: find_package(ssta COMPONENTS map), link
// ssta::map. Builds a small map (a floor with a box), saves and opens it, asks a footprint and a
// column, and exports the grid. Prints what it found; exits 0 only when the answers are right.
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "ssta/mapping/map_export.h"
#include "ssta/mapping/traversability_map.h"

namespace {

ssta::ClassifiedPoint Point(double x, double y, double z, ssta::TravClass cls, float slope_deg, float step_m) {
  ssta::ClassifiedPoint p;
  p.world_p = Eigen::Vector3f(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
  p.cls = cls;
  p.slope_deg = slope_deg;
  p.step_m = step_m;
  return p;
}

/// A floor over x, y in [0, 3) at 0.1 m, with a 0.3 m box of obstacle on x, y in [2.0, 2.3).
std::vector<ssta::ClassifiedPoint> FloorAndBox() {
  std::vector<ssta::ClassifiedPoint> points;
  for (int ix = 0; ix < 30; ++ix) {
    for (int iy = 0; iy < 30; ++iy) {
      const double x = 0.05 + 0.1 * ix, y = 0.05 + 0.1 * iy;
      if (ix >= 20 && ix < 23 && iy >= 20 && iy < 23) {
        for (int iz = 0; iz < 3; ++iz) points.push_back(Point(x, y, 0.05 + 0.1 * iz, ssta::TravClass::kNonTraversable, 80.0f, 0.3f));
      } else {
        points.push_back(Point(x, y, 0.05, ssta::TravClass::kTraversable, 2.0f, 0.01f));
      }
    }
  }
  return points;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: map_consumer WORK_FOLDER\n";
    return 2;
  }
  const std::string dir = argv[1];
  {
    ssta::TraversabilityMap built;
    for (int frame = 0; frame < 5; ++frame) {
      built.InsertFrame(FloorAndBox(), Eigen::Vector3d(1.5, 1.5, 3.0), 1000000000LL * (frame + 1));
    }
    built.Save(dir + "/site.ot");
  }
  const ssta::TraversabilityMap map = ssta::TraversabilityMap::Load(dir + "/site.ot");

  ssta::FootprintQuery open_ground;
  open_ground.x = 1.0;
  open_ground.y = 1.0;
  open_ground.length_m = 0.8;
  open_ground.width_m = 0.6;
  const ssta::FootprintResult ground = map.QueryFootprint(open_ground);
  const ssta::CellInfo box = map.TopSurfaceAt(2.15, 2.15);
  const ssta::CellInfo outside = map.TopSurfaceAt(10.0, 10.0);
  ssta::ExportGrid(map, dir + "/grid");

  std::cout << "frames " << map.frames_inserted() << "\n"
            << "footprint at (1, 1): worst class " << static_cast<int>(ground.worst) << ", " << ground.observed_cells
            << " of " << ground.cells << " columns observed\n"
            << "column (2.15, 2.15): class " << static_cast<int>(box.cls) << "\n"
            << "column (10, 10): class " << static_cast<int>(outside.cls) << "\n";
  const bool right = map.frames_inserted() == 5 && ground.worst == ssta::TravClass::kTraversable &&
                     ground.cells > 0 && ground.observed_cells == ground.cells &&
                     box.cls == ssta::TravClass::kNonTraversable && !outside.observed &&
                     std::filesystem::file_size(dir + "/grid.png") > 0 &&
                     std::filesystem::exists(dir + "/grid.pgm");
  std::cout << (right ? "map consumer: answers as expected\n" : "map consumer: WRONG answers\n");
  return right ? 0 : 1;
}
