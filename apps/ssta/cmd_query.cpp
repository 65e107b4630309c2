// ssta query: answers from a map for planners, as CSV on stdout (docs/interfaces.md, section 5).

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>

#include "commands.h"
#include "map_arguments.h"
#include "ssta/mapping/confidence_bar.h"
#include "ssta/mapping/map_export.h"
#include "ssta/files/file_util.h"
#include "ssta/mapping/traversability_map.h"
#include "ssta/core/units.h"

namespace ssta::cli {
namespace {

struct QueryArgs {
  std::string map, points, path;
  std::vector<double> at, footprint;
  std::vector<std::string> config;
  double path_width_m = 0.0;
  bool as_exported = false;
  GridExportOptions exported;  // the export's steps, for --as-exported
  double min_confidence = 0.0;  // --min-confidence: drivable answers below it are undecided
};

// Runs a map query; its error names the option that asked it instead of the library's query
// ("footprint query: ..." -> "--footprint 1,1,0,1e9,0.5: ...").
template <typename Query>
auto NamingTheOption(const std::string& option, const std::string& library_prefix, Query&& query) {
  try {
    return query();
  } catch (const Error& e) {
    std::string message = e.what();
    if (message.rfind(library_prefix, 0) == 0) message.erase(0, library_prefix.size());
    throw Error(option + ": " + message);
  }
}

// --footprint X,Y,YAW_DEG,LENGTH,WIDTH: one row under its own header.
void AnswerFootprint(const TraversabilityMap& map, const QueryArgs& args) {
  const auto& f = args.footprint;
  for (double v : f) {
    if (!std::isfinite(v)) throw Error("--footprint: NaN or infinite value");
  }
  if (f[3] < 0 || f[4] < 0) throw Error("--footprint: LENGTH and WIDTH must be >= 0");
  const FootprintQuery q{f[0], f[1], DegToRad(f[2]), f[3], f[4]};
  const double r = 0.5 * std::hypot(q.length_m, q.width_m);  // the rectangle lies within r of (x, y)
  const Eigen::AlignedBox2d box(Eigen::Vector2d(q.x - r, q.y - r), Eigen::Vector2d(q.x + r, q.y + r));
  std::string option = "--footprint ";
  for (std::size_t i = 0; i < f.size(); ++i) option += (i ? "," : "") + PrintNumber(f[i], "%g");
  const FootprintResult result = NamingTheOption(option, "footprint query: ", [&] {
    const std::unique_ptr<ExportedSurface> exported =
        args.as_exported ? std::make_unique<ExportedSurface>(map, box, args.exported) : nullptr;
    return map.QueryFootprint(q, WithConfidenceBarOver(map, exported.get(), args.min_confidence));
  });
  std::cout << "worst,mean_cost,max_cost,fraction_observed,cells,observed_cells,pitch_deg,roll_deg,attitude,"
               "attitude_heights,drivable_confidence\n"
            << static_cast<int>(result.worst) << ',' << PrintNumber(result.mean_cost, "%.4f") << ','
            << PrintNumber(result.max_cost, "%.4f") << ',' << PrintNumber(result.fraction_observed, "%.4f") << ','
            << result.cells << ',' << result.observed_cells << ',' << PrintNumber(result.pitch_deg, "%.2f") << ','
            << PrintNumber(result.roll_deg, "%.2f") << ',' << static_cast<int>(result.attitude) << ','
            << result.attitude_heights << ',' << PrintNumber(result.drivable_confidence, "%.4f") << "\n";
}

// --path FILE.csv [--width W]: one row per sample; the verdict on stderr.
void AnswerPath(const TraversabilityMap& map, const std::vector<std::vector<double>>& vertices, const QueryArgs& args) {
  if (!(args.path_width_m >= 0.0 && std::isfinite(args.path_width_m))) throw Error("--width: must be >= 0");
  std::vector<Eigen::Vector2d> polyline;
  Eigen::AlignedBox2d box;
  for (const auto& v : vertices) {  // x,y each (ReadPoints)
    polyline.emplace_back(v[0], v[1]);
    box.extend(polyline.back());
  }
  if (polyline.empty()) throw Error(args.path + ": no vertices");
  const Eigen::Vector2d half_width = Eigen::Vector2d::Constant(0.5 * args.path_width_m);
  const std::string option = "--path " + args.path + " --width " + PrintNumber(args.path_width_m, "%g");
  const PathResult result = NamingTheOption(option, "path query: ", [&] {
    const std::unique_ptr<ExportedSurface> exported =
        args.as_exported ? std::make_unique<ExportedSurface>(
                               map, Eigen::AlignedBox2d(box.min() - half_width, box.max() + half_width), args.exported)
                         : nullptr;
    return map.QueryPath(polyline, args.path_width_m, WithConfidenceBarOver(map, exported.get(), args.min_confidence));
  });
  std::cout << "distance_m,x,y,class,cost,fraction_observed,drivable_confidence\n";
  for (const PathSample& sample : result.samples) {
    std::cout << PrintNumber(sample.distance_m, "%.4f") << ',' << PrintNumber(sample.point.x(), "%.4f") << ','
              << PrintNumber(sample.point.y(), "%.4f") << ',' << static_cast<int>(sample.cls) << ','
              << PrintNumber(sample.cost, "%.4f") << ',' << PrintNumber(sample.fraction_observed, "%.4f") << ','
              << PrintNumber(sample.drivable_confidence, "%.4f") << "\n";
  }
  std::cerr << "path " << PrintNumber(result.length_m, "%.2f") << " m, " << result.samples.size()
            << " samples, worst class " << static_cast<int>(result.worst) << ", "
            << (result.blocked ? "blocked at " + PrintNumber(result.first_non_traversable_distance_m, "%.2f") + " m"
                               : std::string("not blocked"))
            << ", " << PrintNumber(100.0 * result.fraction_observed, "%.0f") << " % observed\n";
}

// One point per line, `max_values` numbers (x,y, or x,y[,z] when 3), comma-separated; blank
// lines and a header (a first line whose every cell starts with a letter, such as "x,y") are
// skipped. Throws naming the file and line on anything else, and when no point is left.
std::vector<std::vector<double>> ReadPoints(const std::string& path, std::size_t max_values) {
  const std::string expected = max_values == 2 ? "x,y" : "x,y or x,y,z";
  std::istringstream in(ReadTextFile(path));  // names a missing file or a folder
  std::vector<std::vector<double>> out;
  std::string line;
  int n = 0;
  bool first = true, header = false;
  while (std::getline(in, line)) {
    ++n;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::stringstream ss(line);
    std::string cell;
    std::vector<std::string> cells;
    while (std::getline(ss, cell, ',')) cells.push_back(cell);
    const bool is_header = first && !cells.empty() && std::all_of(cells.begin(), cells.end(), [](const std::string& c) {
      const std::size_t at = c.find_first_not_of(" \t\r");
      return at != std::string::npos && std::isalpha(static_cast<unsigned char>(c[at])) != 0;
    });
    first = false;
    if (is_header) {
      header = true;
      continue;
    }
    const std::string where = path + ":" + std::to_string(n) + ": ";
    std::vector<double> values;
    for (const std::string& c : cells) {
      std::size_t used = 0;
      double v = 0.0;
      try {
        v = std::stod(c, &used);
      } catch (const std::out_of_range&) {
        throw Error(where + "'" + c + "' is out of the range of a double");
      } catch (const std::exception&) {
        used = 0;
      }
      if (used == 0 || c.find_first_not_of(" \t\r", used) != std::string::npos) {
        throw Error(where + "expected " + expected + " numbers, comma-separated, got '" + line + "'");
      }
      if (!std::isfinite(v)) throw Error(where + "NaN or infinite value");
      values.push_back(v);
    }
    if (values.size() < 2 || values.size() > max_values) {
      throw Error(where + "expected " + expected + ", got " + std::to_string(values.size()) + " values");
    }
    out.push_back(values);
  }
  if (out.empty()) throw Error(path + ": no points" + (header ? " after its header" : "") + " (expected " + expected + " per line)");
  return out;
}

// `exported`: the surface as exported (X,Y points only), or null for the map as observed;
// `min_confidence`: the planner's bar (0: none).
std::string Answer(const TraversabilityMap& map, const std::vector<double>& p, const ExportedSurface* exported,
                   double min_confidence) {
  const CellInfo cell = AtConfidenceBar(p.size() == 3         ? map.CellAt({p[0], p[1], p[2]})
                                        : exported != nullptr ? (*exported)(p[0], p[1])
                                                              : map.TopSurfaceAt(p[0], p[1]),
                                        min_confidence);
  if (cell.observed) return QueryCsvRow(cell);
  // Unobserved: class 0 at the asked point (docs/interfaces.md, section 5); with --as-exported, the
  // class of a filled hole.
  CellInfo unknown = cell;
  unknown.center = Eigen::Vector3d(p[0], p[1], p.size() == 3 ? p[2] : std::numeric_limits<double>::quiet_NaN());
  return QueryCsvRow(unknown);
}

/// The X,Y[,Z] points of --at or --points, checked.
std::vector<std::vector<double>> QueryPoints(const QueryArgs& args) {
  std::vector<std::vector<double>> points;
  if (!args.at.empty()) {
    if (args.at.size() < 2) throw Error("--at: expected X,Y or X,Y,Z");
    for (double v : args.at) {
      if (!std::isfinite(v)) throw Error("--at: NaN or infinite value");
    }
    points.push_back(args.at);
  } else {
    points = ReadPoints(args.points, 3);
  }
  for (const auto& p : points) {
    if (args.as_exported && p.size() == 3) {
      throw Error((args.at.empty() ? args.points + ": " : std::string("--at: ")) +
                  "--as-exported answers X,Y points (the exported grid is 2D), got X,Y,Z");
    }
  }
  return points;
}

/// `ssta query` once its options are parsed.
void RunQuery(const QueryArgs& args) {
  if (args.at.empty() && args.points.empty() && args.footprint.empty() && args.path.empty()) {
    throw Error("query needs --at X,Y[,Z], --points FILE.csv, --footprint X,Y,YAW_DEG,LENGTH,WIDTH or --path FILE.csv");
  }
  RequireProbability("--min-confidence", args.min_confidence);
  const TraversabilityMap map = LoadMapForConfig(args.map, args.config);
  if (!args.footprint.empty()) return AnswerFootprint(map, args);
  if (!args.path.empty()) return AnswerPath(map, ReadPoints(args.path, 2), args);
  const std::vector<std::vector<double>> points = QueryPoints(args);
  // As exported: one projection of the points' bounding box when it is not too large (each
  // answer is the same from any projection that holds it; ExportedSurface projects a point
  // outside on its own), else one per point.
  std::unique_ptr<ExportedSurface> exported;
  if (args.as_exported) {
    Eigen::AlignedBox2d box;
    for (const auto& p : points) box.extend(Eigen::Vector2d(p[0], p[1]));
    const double res = map.options().resolution_m;
    const bool one_projection = box.sizes().x() / res * (box.sizes().y() / res) <= 4e6;
    if (!one_projection) box = Eigen::AlignedBox2d(box.min(), box.min());
    exported = std::make_unique<ExportedSurface>(map, box, args.exported);
  }
  std::cout << kQueryCsvHeader << "\n";
  for (const auto& p : points) std::cout << Answer(map, p, exported.get(), args.min_confidence) << "\n";
}

}  // namespace

void RegisterQuery(CLI::App& app) {
  auto args = std::make_shared<QueryArgs>();
  CLI::App* cmd = app.add_subcommand("query", "Query map cells for a planner: CSV on stdout");
  cmd->footer(
      "Output header: x,y,z,class,cost,probability,slope_deg,step_m,observations,confidence,decided_by,\n"
      "frame_mean_slope_deg,frame_mean_step_m (confidence: the posterior probability of the class from the\n"
      "frames and the fused surface; decided_by: frames, surface, both, or export with --as-exported;\n"
      "slope_deg and step_m: those that decided the class, the fused surface's; nan where the frames' votes did).\n"
      "X,Y answers for the top observed surface of that column, X,Y,Z for the voxel at that point;\n"
      "x,y,z are then that voxel's centre. An unobserved cell is the point asked (z nan for X,Y), class 0\n"
      "with cost nan: the planner decides. --as-exported gives X,Y the class\n"
      "and cost of `export --format grid` (steps judged by the local ground: class 1, cost 0; a filled\n"
      "hole: its class, z and cost nan); without it, answers are the map as observed.\n"
      "--footprint and --path print their own headers (see their help) and take --as-exported too.\n"
      "--min-confidence C answers a traversable or semi-traversable cell less sure than C as undecided\n"
      "(class 4, no cost), and so every footprint and path sample with such a cell under it.");
  cmd->add_option("--map", args->map, "map file (.ot) written by build-map")->required();
  AddMapConfig(cmd, &args->config);
  auto* at = cmd->add_option("--at", args->at, "one point: X,Y or X,Y,Z [m, world frame]")
                 ->delimiter(',')
                 ->expected(1, 3)  // 1 only for the help's sake ("X,Y[,Z]", not "x 2"): refused below
                 ->type_name("X,Y[,Z]");
  auto* points = cmd->add_option("--points", args->points, "CSV file of points, one x,y or x,y,z per line");
  auto* footprint = cmd->add_option("--footprint", args->footprint,
                                    "the ground under a vehicle: X,Y [m], YAW_DEG [deg from +x towards +y], LENGTH "
                                    "(along the heading), WIDTH [m]; prints worst class, mean and max cost, "
                                    "observed share and cells")
                        ->delimiter(',')
                        ->expected(5);
  auto* path = cmd->add_option("--path", args->path,
                               "CSV of path vertices x,y: one row per sample every half resolution (distance, "
                               "point, worst class and max cost across --width, observed share); the verdict "
                               "(blocked where) on stderr");
  cmd->add_option("--width", args->path_width_m, "with --path: corridor width [m], sampled every resolution")
      ->capture_default_str()
      ->needs(path);
  at->excludes(points);
  for (CLI::Option* a : {at, points}) {
    footprint->excludes(a);
    path->excludes(a);
  }
  footprint->excludes(path);
  cmd->add_option("--min-confidence", args->min_confidence,
                  "drive only on answers this sure: a traversable or semi-traversable cell whose confidence is "
                  "below this is undecided, in points, footprints and paths (0: every answer)")
      ->capture_default_str();
  AddAsExported(cmd,
                "X,Y, footprints and paths: read the cells as the exported grid shows them (its local-ground and "
                "hole-filling steps)",
                &args->as_exported, &args->exported);
  cmd->callback([args] { RunQuery(*args); });
}

}  // namespace ssta::cli
