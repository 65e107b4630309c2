// ssta export: a map to the formats other tools read.

#include <iostream>

#include "commands.h"
#include "ssta/mapping/map_export.h"
#include "ssta/mapping/traversability_map.h"

namespace ssta::cli {
namespace {

struct ExportArgs {
  std::string map, format, out;
  double resolution_m = 0.0;
  std::vector<double> region;
  int fill_min_neighbours = GridExportOptions{}.fill_min_neighbours;
  double local_ground_radius_m = GridExportOptions{}.local_ground_radius_m;
};

}  // namespace

void AddGridExportSteps(CLI::App* cmd, const std::string& scope, int* fill_min_neighbours,
                        double* local_ground_radius_m) {
  cmd->add_option("--fill-holes", *fill_min_neighbours,
                  scope + "an unknown cell with at least N of its 8 neighbours classified takes their most frequent "
                          "class (ties: the worse); fills the cells far rows of pixels skip, not the edge of the "
                          "observed area. 0: off")
      ->check(CLI::Range(0, 8))
      ->capture_default_str();
  cmd->add_option("--local-ground", *local_ground_radius_m,
                  scope + "a level cell (slope below the vehicle's semi_slope_deg) called non-traversable for its "
                          "step over a frame's ground plane is traversable when it lies within one cell of the "
                          "height of the traversable ground within this radius [m]. 0: off")
      ->check(CLI::Range(0.0, 100.0))
      ->capture_default_str();
}

void RegisterExport(CLI::App& app) {
  auto args = std::make_shared<ExportArgs>();
  CLI::App* cmd = app.add_subcommand("export", "Export a map: a navigation grid, an octovis tree, point clouds or CSV");
  cmd->add_option("--map", args->map, "map file (.ot) written by build-map")->required();
  cmd->add_option("--format", args->format,
                  "grid (PREFIX.png, PREFIX_classes.png, PREFIX.pgm, PREFIX.yaml for map_server) | octovis "
                  "(PREFIX.ot ColorOcTree) | ply | pcd | csv")
      ->required()
      ->check(CLI::IsMember({"grid", "octovis", "ply", "pcd", "csv"}));
  cmd->add_option("--out", args->out, "output prefix (the extension is added)")->required();
  cmd->add_option("--resolution", args->resolution_m, "grid: pixel edge [m] (default: the map's)");
  cmd->add_option("--region", args->region, "grid: XMIN,YMIN,XMAX,YMAX [m] (default: the observed surface)")
      ->delimiter(',')
      ->expected(4);
  AddGridExportSteps(cmd, "grid: ", &args->fill_min_neighbours, &args->local_ground_radius_m);
  cmd->callback([args] {
    const TraversabilityMap map = TraversabilityMap::Load(args->map);
    const std::string& f = args->format;
    std::string written;
    if (f == "grid") {
      GridExportOptions options;
      options.resolution_m = args->resolution_m;
      options.fill_min_neighbours = args->fill_min_neighbours;
      options.local_ground_radius_m = args->local_ground_radius_m;
      if (!args->region.empty()) {
        const auto& r = args->region;
        if (!(r[2] > r[0] && r[3] > r[1])) throw Error("--region: needs XMIN < XMAX and YMIN < YMAX");
        options.region = Eigen::AlignedBox2d(Eigen::Vector2d(r[0], r[1]), Eigen::Vector2d(r[2], r[3]));
      }
      GridExportChanges changes;
      const GridProjection grid = ExportGrid(map, args->out, options, &changes);
      written = args->out + ".{png,_classes.png,pgm,yaml} (" + std::to_string(grid.width()) + "x" +
                std::to_string(grid.height()) + " cells; " + std::to_string(changes.judged_by_local_ground) +
                " judged traversable by the local ground, " + std::to_string(changes.holes_filled) +
                " holes filled)";
    } else if (f == "octovis") {
      ExportOctovis(map, args->out + ".ot");
      written = args->out + ".ot";
    } else if (f == "ply") {
      ExportPly(map, args->out + ".ply");
      written = args->out + ".ply";
    } else if (f == "pcd") {
      ExportPcd(map, args->out + ".pcd");
      written = args->out + ".pcd";
    } else {
      ExportCsv(map, args->out + ".csv");
      written = args->out + ".csv";
    }
    std::cout << "wrote " << written << "\n";
  });
}

}  // namespace ssta::cli
