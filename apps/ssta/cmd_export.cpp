// ssta export: a map to the formats other tools read.

#include <map>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <iterator>
#include <sstream>
#include <system_error>

#include "commands.h"
#include "map_arguments.h"
#include "ssta/mapping/map_export.h"
#include "ssta/pictures/map_picture.h"
#include "ssta/mapping/traversability_map.h"
#include "ssta/pipeline/config.h"

namespace ssta::cli {
namespace {

struct ExportArgs {
  std::string map, format, out;
  double resolution_m = 0.0;
  std::vector<double> region;
  std::vector<std::string> config;
  int fill_min_neighbours = GridExportOptions{}.fill_min_neighbours;
  double local_ground_radius_m = GridExportOptions{}.local_ground_radius_m;
  bool flat = false;
  std::string compression = "zstd";
  std::string frame = McapExportOptions{}.map_frame;
  int headings = 0;
  double min_confidence = 0.0;  // --min-confidence: the planner's bar (GridExportOptions::min_confidence)
  std::vector<double> heading_footprint = {HeadingCostOptions{}.footprint_length_m, HeadingCostOptions{}.footprint_width_m};
};

// True when `a` and `b` name the same file (or would, once written).
bool SameFile(const std::string& a, const std::string& b) {
  std::error_code error;
  if (std::filesystem::exists(a, error) && std::filesystem::exists(b, error)) {
    return std::filesystem::equivalent(a, b, error);
  }
  return std::filesystem::weakly_canonical(a, error) == std::filesystem::weakly_canonical(b, error);
}

}  // namespace

void AddMapConfig(CLI::App* cmd, std::vector<std::string>* config_files) {
  cmd->add_option("--config", *config_files,
                  "YAML config, as given to build-map; repeatable, later files win. Its vehicle section must be "
                  "the vehicle the map was built for (the map's classes are that vehicle's)");
}

void RequireVehicle(const VehicleOptions& expected, const std::vector<std::string>& config_files,
                    const std::string& expected_for, const std::string& source, const std::string& advice) {
  // The files are read over the expected vehicle, so a key they leave out matches; the message
  // names the last file that made the vehicle differ.
  Config config;
  config.vehicle = expected;
  std::map<std::string, std::string> set_by;  // key -> the last file that changed it
  for (const std::string& file : config_files) {
    const VehicleOptions before = config.vehicle;
    ApplyConfigFile(file, &config);
    for (const OptionField<VehicleOptions>& f : VehicleOptions::Fields()) {
      if (f.get(before) != f.get(config.vehicle)) set_by[f.key] = file;
    }
  }
  const auto* differing = FirstDifferingField(config.vehicle, expected, VehicleOptions::Fields());
  if (differing == nullptr) return;
  RequireSameVehicle(config.vehicle, set_by[differing->key] + ": gives", expected, expected_for,
                     source.empty() ? "" : " (" + source + ")", advice);
}

TraversabilityMap LoadMapForConfig(const std::string& map_path, const std::vector<std::string>& config_files) {
  TraversabilityMap map = TraversabilityMap::Load(map_path);
  RequireVehicle(map.metadata().vehicle, config_files, map_path + " was built for", "",
                 "its classes are that vehicle's: build the map with this config to query it for this vehicle");
  return map;
}

void AddAsExported(CLI::App* cmd, const std::string& help, bool* as_exported, GridExportOptions* exported) {
  CLI::Option* flag = cmd->add_flag("--as-exported", *as_exported, help);
  AddGridExportSteps(cmd, "with --as-exported: ", &exported->fill_min_neighbours, &exported->local_ground_radius_m);
  cmd->get_option("--fill-holes")->needs(flag);
  cmd->get_option("--local-ground")->needs(flag);
}

void RequireProbability(const std::string& flag, double value) {
  if (!(value >= 0.0 && value <= 1.0)) throw Error(flag + ": must be a probability in [0, 1]");
}

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

namespace {

/// The options that `--format` ignores are errors naming them, as are bad values of the grid's.
void CheckFormatOptions(const ExportArgs& args, const CLI::App& cmd) {
  const std::string& f = args.format;
  const bool gridded = f == "grid" || f == "picture" || f == "mcap";
  if (!gridded) {  // the grid's options would be ignored: say so instead
    for (const char* option : {"--resolution", "--region", "--fill-holes", "--local-ground", "--min-confidence"}) {
      if (cmd.count(option) > 0) throw Error(std::string(option) + ": only for --format grid, picture or mcap");
    }
  }
  if (f != "picture" && args.flat) throw Error("--flat: only for --format picture");
  for (const char* option : {"--headings", "--heading-footprint"}) {
    if (f != "grid" && f != "mcap" && cmd.count(option) > 0) {
      throw Error(std::string(option) + ": only for --format grid or mcap");
    }
  }
  if (cmd.count("--heading-footprint") > 0 && cmd.count("--headings") == 0) {
    throw Error("--heading-footprint: only with --headings");
  }
  for (const char* option : {"--compression", "--frame"}) {
    if (f != "mcap" && cmd.count(option) > 0) throw Error(std::string(option) + ": only for --format mcap");
  }
  if (args.frame.empty()) throw Error("--frame: must not be empty");
  RequireProbability("--min-confidence", args.min_confidence);
  if (cmd.count("--resolution") > 0 && !(args.resolution_m > 0.0 && std::isfinite(args.resolution_m))) {
    throw Error("--resolution: must be a positive number of metres");
  }
}

/// What `--format` writes after the prefix: one suffix per file.
std::vector<std::string> ExportSuffixes(const ExportArgs& args) {
  const std::string& f = args.format;
  std::vector<std::string> suffixes =
      f == "grid"      ? std::vector<std::string>{".png", "_classes.png", ".pgm", ".yaml"}
      : f == "picture" ? std::vector<std::string>{".png"}
      : f == "mcap"    ? std::vector<std::string>{".mcap"}
                       : std::vector<std::string>{f == "octovis" ? ".ot" : "." + f};
  if (f == "grid") {
    for (int k = 0; k < args.headings; ++k) suffixes.push_back(HeadingCostPath("", k, args.headings));
  }
  return suffixes;
}

/// The grid's options from the command line; the heading footprint and the region checked.
GridExportOptions GridOptionsOf(const ExportArgs& args) {
  GridExportOptions options;
  options.resolution_m = args.resolution_m;
  options.fill_min_neighbours = args.fill_min_neighbours;
  options.local_ground_radius_m = args.local_ground_radius_m;
  options.min_confidence = args.min_confidence;
  options.headings.headings = args.headings;
  options.headings.footprint_length_m = args.heading_footprint[0];
  options.headings.footprint_width_m = args.heading_footprint[1];
  std::string heading_error;
  if (!options.headings.IsValid(&heading_error)) {
    throw Error("--heading-footprint: " + heading_error.substr(heading_error.find(':') + 2));
  }
  if (!args.region.empty()) {
    const auto& r = args.region;
    if (!(r[2] > r[0] && r[3] > r[1])) throw Error("--region: needs XMIN < XMAX and YMIN < YMAX");
    options.region = Eigen::AlignedBox2d(Eigen::Vector2d(r[0], r[1]), Eigen::Vector2d(r[2], r[3]));
  }
  return options;
}

/// Writes `map` in args.format under args.out; what was written, for people.
std::string WriteExport(const TraversabilityMap& map, const ExportArgs& args, const GridExportOptions& options,
                        const std::vector<std::string>& suffixes) {
  const std::string& f = args.format;
  std::string written;
  if (f == "picture") {
    MapPictureOptions picture_options;
    picture_options.grid = options;
    picture_options.hillshade = !args.flat;
    picture_options.title = std::filesystem::path(args.map).filename().string();
    const MapPicture picture = ExportPicture(map, args.out + ".png", picture_options);
    written = args.out + ".png (" + std::to_string(picture.grid.width()) + "x" +
              std::to_string(picture.grid.height()) + " cells of " + std::to_string(picture.grid.resolution_m).substr(0, 5) +
              " m)";
  } else if (f == "grid") {
    GridExportChanges changes;
    const GridProjection grid = ExportGrid(map, args.out, options, &changes);
    std::string files;  // each file whole: a brace expansion would read "yard._classes.png"
    for (const std::string& suffix : suffixes) files += (files.empty() ? "" : ", ") + args.out + suffix;
    written = files + " (" + std::to_string(grid.width()) + "x" +
              std::to_string(grid.height()) + " cells; " + std::to_string(changes.judged_by_local_ground) +
              " judged traversable by the local ground, " + std::to_string(changes.holes_filled) +
              " holes filled" +
              (options.min_confidence > 0.0
                   ? ", " + std::to_string(changes.below_confidence_bar) + " drivable cells below the confidence bar"
                   : std::string()) +
              ")";
  } else if (f == "mcap") {
    McapExportOptions mcap;
    mcap.grid = options;
    mcap.zstd = args.compression == "zstd";
    mcap.map_frame = args.frame;
    const McapExportSummary s = ExportMcap(map, args.out + ".mcap", mcap);
    written = args.out + ".mcap (" + std::to_string(s.bytes) + " bytes in " + std::to_string(s.chunks) +
              " chunks; " + std::to_string(s.grid_width) + "x" + std::to_string(s.grid_height) + " cells" +
              (args.headings > 0 ? " with " + std::to_string(args.headings) + " heading cost layers" : "") + ", " +
              std::to_string(s.voxels) + " voxels, " + std::to_string(s.path_poses) + " path poses)";
  } else if (f == "octovis") {
    ExportOctovis(map, args.out + ".ot");
    written = args.out + ".ot";
  } else if (f == "ply") {
    ExportPly(map, args.out + ".ply");
    written = args.out + ".ply";
  } else if (f == "pcd") {
    ExportPcd(map, args.out + ".pcd");
    written = args.out + ".pcd";
  } else {
    ExportCsv(map, args.out + ".csv");
    written = args.out + ".csv";
  }
  return written;
}

/// `ssta export` once its options are parsed.
void RunExport(ExportArgs* args, const CLI::App& cmd) {
  CheckFormatOptions(*args, cmd);
  // mcap: `--out map.mcap` names the file itself.
  const bool named_mcap = args->format == "mcap" && args->out.size() > 5 && args->out.substr(args->out.size() - 5) == ".mcap";
  if (named_mcap) args->out.resize(args->out.size() - 5);
  const std::vector<std::string> suffixes = ExportSuffixes(*args);
  for (const std::string& suffix : suffixes) {
    if (SameFile(args->out + suffix, args->map)) {
      throw Error("--out " + args->out + ": would write " + args->out + suffix + " over the map it reads (" +
                  args->map + "); choose another prefix, e.g. " + args->out + "_" + args->format);
    }
  }
  const TraversabilityMap map = LoadMapForConfig(args->map, args->config);
  std::cout << "wrote " << WriteExport(map, *args, GridOptionsOf(*args), suffixes) << "\n";
}

}  // namespace

void RegisterExport(CLI::App& app) {
  auto args = std::make_shared<ExportArgs>();
  CLI::App* cmd = app.add_subcommand(
      "export", "Export a map: a navigation grid, a ROS 2 bag, an octovis tree, point clouds or CSV");
  cmd->add_option("--map", args->map, "map file (.ot) written by build-map")->required();
  AddMapConfig(cmd, &args->config);
  cmd->add_option("--format", args->format,
                  "grid (PREFIX.png, PREFIX_classes.png, PREFIX.pgm, PREFIX.yaml for map_server) | picture "
                  "(PREFIX.png for people: the grid with legend, scale, axes, sensor path, relief) | mcap "
                  "(PREFIX.mcap, a ROS 2 bag: /map OccupancyGrid, /traversability GridMap, /traversability/voxels "
                  "PointCloud2, /sensor_path, /tf_static; latched) | octovis (PREFIX.ot ColorOcTree) | ply | pcd | csv")
      ->required()
      ->check(CLI::IsMember({"grid", "picture", "mcap", "octovis", "ply", "pcd", "csv"}));
  cmd->add_option("--out", args->out, "output prefix (the extension is added; mcap also takes FILE.mcap)")
      ->required()
      ->check(OutputPrefix());
  cmd->add_option("--resolution", args->resolution_m,
                  "grid, picture, mcap: pixel edge [m] (default: the map's; a picture of a large map coarsens to 1500 "
                  "cells along its longer side); a coarser pixel takes the worst class of the map columns it holds");
  cmd->add_option("--region", args->region, "grid, picture, mcap: XMIN,YMIN,XMAX,YMAX [m] (default: the observed surface)")
      ->delimiter(',')
      ->expected(4);
  AddGridExportSteps(cmd, "grid, picture, mcap: ", &args->fill_min_neighbours, &args->local_ground_radius_m);
  cmd->add_option("--min-confidence", args->min_confidence,
                  "grid, picture, mcap: a planner's bar: a traversable or semi-traversable cell whose confidence "
                  "is below this is exported undecided (unknown in the PGM and the OccupancyGrid), as `query "
                  "--min-confidence` answers it. 0: every cell as the map has it")
      ->capture_default_str();
  cmd->add_option("--headings", args->headings,
                  "grid, mcap: also a cost layer per heading, N headings evenly spaced from +x towards +y: the class "
                  "cost raised where the vehicle's pitch or roll on the ground under its footprint nears or passes "
                  "its max_pitch_deg, max_descent_deg or max_roll_deg (grid: PREFIX_cost_heading_<deg>.png each; mcap: "
                  "GridMap layers cost_heading_<deg>)")
      ->check(CLI::Range(1, 360));
  cmd->add_option("--heading-footprint", args->heading_footprint,
                  "with --headings: LENGTH,WIDTH [m] of the footprint, centred at each cell, whose ground gives the "
                  "pitch and roll")
      ->delimiter(',')
      ->expected(2)
      ->capture_default_str();
  cmd->add_flag("--flat", args->flat, "picture: flat class colours, without the relief shading");
  cmd->add_option("--compression", args->compression, "mcap: how its chunks are compressed")
      ->check(CLI::IsMember({"zstd", "none"}))
      ->capture_default_str();
  cmd->add_option("--frame", args->frame,
                  "mcap: the frame of its messages; /tf_static places the map's world frame in it (identity)")
      ->capture_default_str();
  cmd->callback([args, cmd] { RunExport(args.get(), *cmd); });
}

}  // namespace ssta::cli
