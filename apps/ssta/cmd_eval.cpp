// `ssta eval`: scores classifications, exported grids, query answers and a map's footprint
// verdicts against the ground truth of a synthetic sequence (docs/interfaces.md, section 6). Prints a
// report; --json writes the machine-readable summary.

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <unistd.h>

#include "commands.h"
#include "map_arguments.h"
#include "ssta/eval/class_grid.h"
#include "ssta/eval/footprint_evaluator.h"
#include "ssta/eval/grid_evaluator.h"
#include "ssta/eval/label_evaluator.h"
#include "ssta/eval/query_evaluator.h"
#include "ssta/files/file_util.h"
#include "ssta/io/image_io.h"
#include "ssta/mapping/column_explanation.h"
#include "ssta/mapping/map_export.h"
#include "ssta/mapping/traversability_map.h"
#include "ssta/pipeline/config.h"

namespace ssta::cli {
namespace {

struct EvalArguments {
  std::string prediction;
  std::string sequence;
  std::string json_path;
  std::string pictures_dir;
  std::string picture_path;
  std::vector<std::string> config;
  bool skip_missing = false;
  double depth_band_m = 5.0;
};

void AddCommon(CLI::App* command, EvalArguments* args, const std::string& pred_help) {
  command->add_option("--pred", args->prediction, pred_help)->required();
  command->add_option("--gt", args->sequence,
                      "synthetic sequence folder holding gt/ (or mav0/gt/)")
      ->required();
  command->add_option("--config", args->config,
                      "YAML config, as given to the command that made --pred; repeatable, later files win. Its "
                      "vehicle section must be the one the truth was rendered for (the sequence's vehicle.yaml)");
  command->add_option("--json", args->json_path, "also write the summary as JSON to this file")->check(OutputFile());
}

// The vehicle the truth of `sequence` was classed for: its vehicle.yaml (ssta synth writes it
// beside gt/), read over the defaults; nullopt when the sequence has none.
struct TruthVehicle {
  VehicleOptions vehicle;
  std::string yaml;
};
std::optional<TruthVehicle> ReadTruthVehicle(const std::string& sequence) {
  namespace fs = std::filesystem;
  const fs::path gt = FindGroundTruthDir(sequence);
  for (const fs::path& candidate : {gt.parent_path() / "vehicle.yaml", fs::path(sequence) / "vehicle.yaml"}) {
    if (!fs::is_regular_file(candidate)) continue;
    Config truth;
    ApplyConfigFile(candidate.string(), &truth);
    return TruthVehicle{truth.vehicle, candidate.string()};
  }
  return std::nullopt;
}

const char* const kTwoVehiclesAdvice =
    "scores against it would compare the classes of two vehicles: classify for that vehicle, or render the "
    "sequence for this one (ssta synth --config)";

// Scores mean something only for classes made for the truth's vehicle: --config files read
// over it must leave it as it is, and so must the config.yaml that `ssta classify` writes
// beside its labels (`prediction_config`, when there is one). Without a vehicle.yaml the
// --config files are only checked for bad keys and values.
void RequireTruthVehicle(const EvalArguments& args, const std::string& prediction_config = "") {
  if (args.config.empty() && prediction_config.empty()) return;
  const std::optional<TruthVehicle> truth = ReadTruthVehicle(args.sequence);
  if (!truth) {
    LoadLayeredConfig(nullptr, args.config);  // bad keys and values still name their file
    return;
  }
  const std::string expected_for = "the truth in " + FindGroundTruthDir(args.sequence) + " was classed for";
  RequireVehicle(truth->vehicle, args.config, expected_for, truth->yaml, kTwoVehiclesAdvice);
  if (!prediction_config.empty()) {
    RequireVehicle(truth->vehicle, {prediction_config}, expected_for, truth->yaml, kTwoVehiclesAdvice);
  }
}

// A map's classes are its vehicle's (its metadata): the truth's vehicle must be the same.
void RequireMapForTruthVehicle(const TraversabilityMap& map, const std::string& map_path, const std::string& sequence) {
  const std::optional<TruthVehicle> truth = ReadTruthVehicle(sequence);
  if (!truth) return;
  RequireSameVehicle(map.metadata().vehicle, map_path + ": the map was built for", truth->vehicle,
                     "the truth in " + FindGroundTruthDir(sequence) + " was classed for", " (" + truth->yaml + ")",
                     kTwoVehiclesAdvice);
}

// The config.yaml that `ssta classify` wrote with the labels of --pred (DIR, or DIR/labels), or
// "" when there is none (a folder of label PNGs from elsewhere).
std::string ClassifyConfigOf(const std::string& prediction) {
  namespace fs = std::filesystem;
  fs::path dir = fs::path(prediction).lexically_normal();
  if (dir.filename().empty()) dir = dir.parent_path();  // trailing slash
  std::vector<fs::path> candidates{dir / "config.yaml"};
  if (dir.filename() == "labels") candidates.push_back(dir.parent_path() / "config.yaml");
  for (const fs::path& candidate : candidates) {
    if (fs::is_regular_file(candidate)) return candidate.string();
  }
  return "";
}

// Progress on stderr when it is a terminal; one line, rewritten in place.
void ShowProgress(int done, int total) {
  static const bool is_terminal = ::isatty(STDERR_FILENO) != 0;
  if (!is_terminal) return;
  std::fprintf(stderr, "\rscoring frame %d / %d", done, total);
  if (done == total) std::fprintf(stderr, "\r%*s\r", 40, "");
  std::fflush(stderr);
}

struct FootprintArguments {
  EvalArguments eval;
  std::vector<std::string> config;
  FootprintEvalOptions footprint;
  bool as_exported = false;
  GridExportOptions exported;  // the export's steps, for --as-exported
  std::string misses_path;     // --misses: the unsafe and falsely blocked poses as CSV
};

// Tells on stderr when the truth grid predates the seen mask of today's renderer.
void WarnIfStale(const ClassGrid& truth) {
  const std::string warning = StaleTruthGridWarning(truth);
  if (!warning.empty()) std::cerr << warning << "\n";
}

// A map's footprint verdicts over the truth grid: QueryFootprint, reading the surface as the
// grid export shows it with --as-exported (one projection of the truth grid's area).
FootprintEvalSummary EvaluateMapFootprints(const FootprintArguments& args) {
  std::string error;
  if (!args.footprint.IsValid(&error)) {  // named by the option that set the key
    for (const auto& [key, flag] : {std::pair<std::string, std::string>{"length_m", "--length"},
                                    {"width_m", "--width"}, {"step_m", "--step"}, {"yaws_deg", "--yaws"},
                                    {"padding_m", "--padding"}, {"min_confidence", "--min-confidence"}}) {
      if (error.rfind(key, 0) == 0) error = flag + error.substr(key.size());
    }
    throw Error(error);
  }
  const ClassGrid truth = ReadGroundTruthGrid(args.eval.sequence);
  const TraversabilityMap map = LoadMapForConfig(args.eval.prediction, args.config);
  RequireMapForTruthVehicle(map, args.eval.prediction, args.eval.sequence);
  WarnIfStale(truth);
  // The rectangle the map is asked about: the robot's, grown by the padding on every side.
  const double query_length_m = args.footprint.length_m + 2.0 * args.footprint.padding_m;
  const double query_width_m = args.footprint.width_m + 2.0 * args.footprint.padding_m;
  std::unique_ptr<ExportedSurface> exported;
  if (args.as_exported) {
    const double reach = 0.5 * std::hypot(query_length_m, query_width_m);
    const Eigen::Vector2d size(truth.classes.width() * truth.resolution_m, truth.classes.height() * truth.resolution_m);
    const Eigen::Vector2d margin = Eigen::Vector2d::Constant(reach);
    exported = std::make_unique<ExportedSurface>(
        map, Eigen::AlignedBox2d(truth.origin_m - margin, truth.origin_m + size + margin), args.exported);
  }
  const DrivenPath path = ReadDrivenPath(args.eval.sequence);
  const auto oracle = [&](const FootprintPose& pose) {
    const FootprintQuery q{pose.x_m, pose.y_m, pose.yaw_rad, query_length_m, query_width_m};
    const FootprintResult r = exported ? map.QueryFootprint(q, *exported) : map.QueryFootprint(q);
    return FootprintAnswer{static_cast<std::uint8_t>(r.worst), r.fraction_observed, r.worst_x_m, r.worst_y_m,
                           r.drivable_confidence};
  };
  FootprintEvalSummary summary;
  try {
    summary = ScoreFootprints(truth, args.footprint, oracle, path.points);
  } catch (const Error& e) {
    // A pose too far from the lattice is the pose file's fault: name it.
    if (path.source.empty() || std::string(e.what()).rfind("distance bands", 0) != 0) throw;
    throw Error(path.source + ": " + e.what());
  }
  summary.path_source = path.source;
  summary.prediction = args.eval.prediction + (args.as_exported ? " (as exported)" : " (as observed)");
  // What the map says about each miss's cell, and which of its rules decided it (`ssta explain`).
  for (FootprintMiss& miss : summary.misses) {
    if (!std::isfinite(miss.cell_x_m) || !std::isfinite(miss.cell_y_m)) continue;
    const ColumnExplanation why = map.ExplainColumn(miss.cell_x_m, miss.cell_y_m);
    const CellInfo cell = exported ? (*exported)(miss.cell_x_m, miss.cell_y_m) : why.cell;
    miss.cell_class = std::to_string(static_cast<int>(cell.cls));
    if (why.cell.observed) {
      miss.cell_rule = JudgeRuleName(why.rule);
    } else {
      miss.cell_rule = cell.decided_by == ClassJudge::kExport ? "filled by the export" : "unobserved";
    }
  }
  return summary;
}

template <typename Summary>
void Report(const Summary& summary, const EvalArguments& args) {
  std::cout << summary.BriefReport();
  if (!args.json_path.empty()) {
    WriteTextAtomically(args.json_path, summary.ToJson());
    std::cout << "JSON summary: " << args.json_path << "\n";
  }
}

/// `eval labels`: per-pixel label images, frame by frame.
void AddLabelsEval(CLI::App* eval) {
  auto labels_args = std::make_shared<EvalArguments>();
  CLI::App* labels = eval->add_subcommand(
      "labels", "Score per-pixel label images (output of `ssta classify`) frame by frame");
  AddCommon(labels, labels_args.get(),
            "classify output folder (PNGs in DIR/labels/) or a folder of label PNGs");
  labels->add_option("--pictures", labels_args->pictures_dir,
                     "write truth | prediction | errors pictures per frame to this folder")
      ->check(OutputFolder());
  labels->add_flag("--skip-missing", labels_args->skip_missing,
                   "leave truth frames without a prediction out of the scores (default: score "
                   "them as all unknown); they are reported either way");
  labels->add_option("--depth-band", labels_args->depth_band_m,
                     "also score the pixels in bands of this many metres of true depth (f b / the true "
                     "disparity of gt/disparity/, with gt/rig.yaml); 0: no bands")
      ->check(CLI::Range(0.0, 1000.0))
      ->capture_default_str();
  labels->callback([labels_args] {
    RequireTruthVehicle(*labels_args, ClassifyConfigOf(labels_args->prediction));
    LabelEvalOptions options;
    options.pictures_dir = labels_args->pictures_dir;
    options.progress = ShowProgress;
    options.depth_band_m = labels_args->depth_band_m;
    options.missing_prediction = labels_args->skip_missing ? MissingPrediction::kSkip
                                                           : MissingPrediction::kScoreAsUnknown;
    Report(EvaluateLabelFolders(labels_args->prediction, labels_args->sequence, options),
           *labels_args);
    if (!labels_args->pictures_dir.empty()) {
      std::cout << "pictures: " << labels_args->pictures_dir << "\n";
    }
  });
}

/// `eval grid`: an exported grid against gt/grid_classes.png.
void AddGridEval(CLI::App* eval) {
  auto grid_args = std::make_shared<EvalArguments>();
  CLI::App* grid = eval->add_subcommand(
      "grid", "Score an exported grid (ssta export --format grid) against gt/grid_classes.png");
  AddCommon(grid, grid_args.get(), "export prefix: reads PREFIX_classes.png and PREFIX.yaml");
  grid->add_option("--picture", grid_args->picture_path,
                   "write a truth | prediction | errors PNG on the truth grid (north up), cropped to the scored cells")
      ->check(OutputFile());
  grid->callback([grid_args] {
    RequireTruthVehicle(*grid_args);
    const GridEvalSummary summary = EvaluateExportedGrid(grid_args->prediction, grid_args->sequence);
    WarnIfStale(summary.truth_grid);
    Report(summary, *grid_args);
    if (!grid_args->picture_path.empty()) {
      WriteImage(MakeGridComparisonPicture(summary.truth_grid, summary.predicted_grid),
                 grid_args->picture_path);
      std::cout << "picture: " << grid_args->picture_path << "\n";
    }
  });
}

/// `eval query`: the CSV answers of `ssta query`.
void AddQueryEval(CLI::App* eval) {
  auto query_args = std::make_shared<EvalArguments>();
  CLI::App* query = eval->add_subcommand(
      "query", "Score the CSV answers of `ssta query` against the ground-truth grid");
  AddCommon(query, query_args.get(),
            "CSV written by ssta query (x,y,z,class,...: its header names the columns)");
  query->callback([query_args] {
    RequireTruthVehicle(*query_args);
    const ClassGrid truth = ReadGroundTruthGrid(query_args->sequence);  // read once: warned about, then scored
    WarnIfStale(truth);
    Report(EvaluateQueryCsv(query_args->prediction, truth), *query_args);
  });
}

/// `eval footprints`: a map's footprint verdicts, the answers a planner gets.
void AddFootprintsEval(CLI::App* eval) {
  auto fp_args = std::make_shared<FootprintArguments>();
  CLI::App* footprints = eval->add_subcommand(
      "footprints",
      "Score a map's footprint verdicts (query --footprint) against the ground-truth grid: worst class "
      "under a robot rectangle at poses over the seen area");
  footprints->add_option("--map", fp_args->eval.prediction, "map file (.ot) written by build-map")->required();
  AddMapConfig(footprints, &fp_args->config);
  footprints->add_option("--gt", fp_args->eval.sequence, "synthetic sequence folder holding gt/ (or mav0/gt/)")
      ->required();
  footprints->add_option("--length", fp_args->footprint.length_m, "footprint length along the heading [m]")
      ->capture_default_str();
  footprints->add_option("--width", fp_args->footprint.width_m, "footprint width [m]")->capture_default_str();
  footprints->add_option("--step", fp_args->footprint.step_m,
                         "footprint centres every this far in x and y [m], on the truth grid's cell centres "
                         "(rounded to whole cells)")
      ->capture_default_str();
  footprints->add_option("--yaws", fp_args->footprint.yaws_deg, "headings [deg], comma-separated")
      ->delimiter(',')
      ->capture_default_str();
  footprints->add_option("--padding", fp_args->footprint.padding_m,
                         "ask the map about the rectangle grown by this on every side, as a planner pads its "
                         "footprint; the truth stays --length x --width [m]")
      ->capture_default_str();
  footprints->add_option("--min-confidence", fp_args->footprint.min_confidence,
                         "drive only on answers this sure: a footprint answered traversable or semi-traversable "
                         "whose least confident drivable cell is below this counts as undecided, as for a planner "
                         "with that bar (the report lists the trade for a range of bars either way)")
      ->capture_default_str();
  AddAsExported(footprints,
                "read the map as the exported grid shows it (its local-ground and hole-filling steps), as query "
                "--as-exported does",
                &fp_args->as_exported, &fp_args->exported);
  footprints->add_option("--json", fp_args->eval.json_path, "also write the summary as JSON to this file")->check(OutputFile());
  footprints->add_option("--misses", fp_args->misses_path,
                         "also write every unsafe and falsely blocked footprint to this CSV file (kind, x, y, yaw, "
                         "truth, answer, fraction known, distance from the path), unsafe first, nearest the path "
                         "first: where to look with `ssta explain`")
      ->check(OutputFile());
  footprints->footer(
      "A pose is scored when every truth cell under it is 1..3 (seen); its truth is their worst class, "
      "the map's answer the worst class of the cells it knows (non-traversable, then undecided, then semi, then "
      "traversable; 0 when it knows none). unsafe: truly "
      "non-traversable footprints answered traversable or semi-traversable; falsely blocked: truly "
      "traversable ones answered non-traversable.");
  footprints->callback([fp_args] {
    const FootprintEvalSummary summary = EvaluateMapFootprints(*fp_args);
    Report(summary, fp_args->eval);
    if (!fp_args->misses_path.empty()) {
      WriteTextAtomically(fp_args->misses_path, summary.MissesCsv());
      std::cout << "misses: " << fp_args->misses_path << " (" << summary.unsafe << " unsafe, "
                << summary.falsely_blocked << " falsely blocked)\n";
    }
  });
}

}  // namespace

void RegisterEval(CLI::App& app) {
  CLI::App* eval = app.add_subcommand(
      "eval", "Score labels, an exported grid or query answers against synthetic ground truth, and disparities "
              "against disparity truth");
  eval->require_subcommand(1);
  eval->footer(
      "Scored samples have truth 1..3 (255 = don't care, 0 and 4 are not scored). accuracy = "
      "correct / scored (a predicted 0 or 4 is wrong); coverage = share of scored samples with a "
      "verdict 1..3; IoU_c = TP / (TP + FP + FN); mean IoU over classes 1..3 present in the truth "
      "or prediction of scored samples.");

  AddLabelsEval(eval);
  AddGridEval(eval);
  AddQueryEval(eval);
  AddFootprintsEval(eval);
  AddDisparityEval(eval);
}

}  // namespace ssta::cli
