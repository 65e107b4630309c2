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
  bool as_exported = false;
  GridExportOptions exported;  // the export's steps, for --as-exported
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

std::string Answer(const TraversabilityMap& map, const std::vector<double>& p, const QueryArgs& args) {
  const CellInfo cell = p.size() == 3     ? map.CellAt({p[0], p[1], p[2]})
                        : args.as_exported ? TopSurfaceAsExported(map, p[0], p[1], args.exported)
                                           : map.TopSurfaceAt(p[0], p[1]);
  if (cell.observed) return QueryCsvRow(cell);
  // Unobserved: class 0 at the asked point (INTERFACES section 5); with --as-exported, the
  // class of a filled hole.
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
      "an unobserved cell is class 0 with cost nan: the planner decides. --as-exported gives X,Y the class\n"
      "and cost of `export --format grid` (steps judged by the local ground: class 1, cost 0; a filled\n"
      "hole: its class, z and cost nan); without it, answers are the map as observed.");
  cmd->add_option("--map", args->map, "map file (.ot) written by build-map")->required();
  auto* at = cmd->add_option("--at", args->at, "one point: X,Y or X,Y,Z [m, world frame]")->delimiter(',')->expected(2, 3);
  auto* points = cmd->add_option("--points", args->points, "CSV file of points, one x,y or x,y,z per line");
  at->excludes(points);
  CLI::Option* as_exported = cmd->add_flag(
      "--as-exported", args->as_exported,
      "X,Y: answer as the exported grid shows the cell (its local-ground and hole-filling steps)");
  AddGridExportSteps(cmd, "with --as-exported: ", &args->exported.fill_min_neighbours,
                     &args->exported.local_ground_radius_m);
  cmd->get_option("--fill-holes")->needs(as_exported);
  cmd->get_option("--local-ground")->needs(as_exported);
  cmd->callback([args] {
    if (args->at.empty() && args->points.empty()) throw Error("query needs --at X,Y[,Z] or --points FILE.csv");
    const TraversabilityMap map = TraversabilityMap::Load(args->map);
    std::vector<std::vector<double>> points;
    if (!args->at.empty()) {
      for (double v : args->at) {
        if (!std::isfinite(v)) throw Error("--at: NaN or infinite value");
      }
      points.push_back(args->at);
    } else {
      points = ReadPoints(args->points);
    }
    for (const auto& p : points) {
      if (args->as_exported && p.size() == 3) {
        throw Error((args->at.empty() ? args->points + ": " : std::string("--at: ")) +
                    "--as-exported answers X,Y points (the exported grid is 2D), got X,Y,Z");
      }
    }
    std::cout << kQueryCsvHeader << "\n";
    for (const auto& p : points) std::cout << Answer(map, p, *args) << "\n";
  });
}

}  // namespace ssta::cli
