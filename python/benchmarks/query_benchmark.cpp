// The C++ half of python/benchmarks/query_benchmark.py: the same N-point top-surface query as
// ssta.Map.query, with the same points and the same output row, timed without Python.
//   query_benchmark_cpp MAP.ot N REPEATS    prints the best wall time of REPEATS runs [s]
// The points are a regular grid over the map's surface bounds, as the Python script makes them.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "../src/query_row.h"
#include "ssta/mapping/traversability_map.h"

using ssta::python::QueryRow;  // the row ssta.Map.query fills

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: query_benchmark_cpp MAP.ot N REPEATS\n");
    return 2;
  }
  try {
    const ssta::TraversabilityMap map = ssta::TraversabilityMap::Load(argv[1]);
    const long n = std::atol(argv[2]);
    const int repeats = std::atoi(argv[3]);
    const Eigen::AlignedBox3d bounds = map.SurfaceBounds();
    // side x side points over the bounds, side = ceil(sqrt(n)), the first n of them.
    const long side = static_cast<long>(std::ceil(std::sqrt(static_cast<double>(n))));
    std::vector<double> points(2 * n);
    for (long i = 0; i < n; ++i) {
      const double fx = static_cast<double>(i % side) / static_cast<double>(side);
      const double fy = static_cast<double>(i / side) / static_cast<double>(side);
      points[2 * i] = bounds.min().x() + fx * bounds.sizes().x();
      points[2 * i + 1] = bounds.min().y() + fy * bounds.sizes().y();
    }
    std::vector<QueryRow> rows(n);
    double best = 1e300;
    for (int r = 0; r < repeats; ++r) {
      const auto start = std::chrono::steady_clock::now();
      for (long i = 0; i < n; ++i) {
        const ssta::CellInfo c = map.TopSurfaceAt(points[2 * i], points[2 * i + 1]);
        const Eigen::Vector3d at =
            c.observed ? c.center : Eigen::Vector3d(points[2 * i], points[2 * i + 1], std::nan(""));
        rows[i] = ssta::python::MakeQueryRow(c, at);
      }
      best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    long observed = 0;
    for (const QueryRow& row : rows) observed += row.observed;
    std::printf("%.6f %ld\n", best, observed);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "query_benchmark_cpp: %s\n", e.what());
    return 2;
  }
  return 0;
}
