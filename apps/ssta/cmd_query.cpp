// ssta query: answers from a map for planners, as CSV on stdout (INTERFACES section 5).

#include <fstream>
#include <iostream>
#include <sstream>

#include "commands.h"
#include "ssta/mapping/map_export.h"
#include "ssta/mapping/traversability_map.h"

namespace ssta::cli {
namespace {

struct QueryArgs {
  std::string map, points;
  std::vector<double> at;
};

// x,y[,z] per line; a header line and blank lines are skipped.
std::vector<std::vector<double>> ReadPoints(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(path + ": file not found");
  std::vector<std::vector<double>> out;
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::stringstream ss(line);
    std::string cell;
    std::vector<double> values;
    bool numeric = true;
    while (std::getline(ss, cell, ',')) {
      try {
        std::size_t used = 0;
        values.push_back(std::stod(cell, &used));
        if (cell.find_first_not_of(" \t\r", used) != std::string::npos) numeric = false;
      } catch (const std::exception&) {
        numeric = false;
      }
    }
    if (!numeric) {
      if (n == 1) continue;  // header
      throw Error(path + ":" + std::to_string(n) + ": expected x,y or x,y,z numbers");
    }
    if (values.size() != 2 && values.size() != 3) {
      throw Error(path + ":" + std::to_string(n) + ": expected 2 or 3 values, found " + std::to_string(values.size()));
    }
    for (double v : values) {
      if (!std::isfinite(v)) throw Error(path + ":" + std::to_string(n) + ": NaN or infinite value");
    }
    out.push_back(values);
  }
  return out;
}

std::string Answer(const TraversabilityMap& map, const std::vector<double>& p) {
  const CellInfo cell = p.size() == 3 ? map.CellAt({p[0], p[1], p[2]}) : map.TopSurfaceAt(p[0], p[1]);
  if (cell.observed) return QueryCsvRow(cell);
  // Unobserved: class 0 at the asked point (INTERFACES section 5).
  CellInfo unknown = cell;
  unknown.center = Eigen::Vector3d(p[0], p[1], p.size() == 3 ? p[2] : std::numeric_limits<double>::quiet_NaN());
  return QueryCsvRow(unknown);
}

}  // namespace

void RegisterQuery(CLI::App& app) {
  auto args = std::make_shared<QueryArgs>();
  CLI::App* cmd = app.add_subcommand("query", "Query map cells for a planner: CSV on stdout");
  cmd->footer(
      "Output header: x,y,z,class,cost,probability,slope_deg,step_m,observations.\n"
      "X,Y answers for the top observed surface of that column, X,Y,Z for the voxel at that point;\n"
      "an unobserved cell is class 0 with cost nan: the planner decides.");
  cmd->add_option("--map", args->map, "map file (.ot) written by build-map")->required();
  auto* at = cmd->add_option("--at", args->at, "one point: X,Y or X,Y,Z [m, world frame]")->delimiter(',')->expected(2, 3);
  auto* points = cmd->add_option("--points", args->points, "CSV file of points, one x,y or x,y,z per line");
  at->excludes(points);
  cmd->callback([args] {
    if (args->at.empty() && args->points.empty()) throw Error("query needs --at X,Y[,Z] or --points FILE.csv");
    const TraversabilityMap map = TraversabilityMap::Load(args->map);
    std::cout << kQueryCsvHeader << "\n";
    if (!args->at.empty()) {
      for (double v : args->at) {
        if (!std::isfinite(v)) throw Error("--at: NaN or infinite value");
      }
      std::cout << Answer(map, args->at) << "\n";
    } else {
      for (const auto& p : ReadPoints(args->points)) std::cout << Answer(map, p) << "\n";
    }
  });
}

}  // namespace ssta::cli
