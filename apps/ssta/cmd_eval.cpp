// `ssta eval`: scores classifications, exported grids and query answers against the ground
// truth of a synthetic sequence (INTERFACES section 6). Prints a report; --json writes the
// machine-readable summary.

#include <cstdio>
#include <iostream>
#include <memory>
#include <string>

#include <unistd.h>

#include "commands.h"
#include "ssta/eval/grid_evaluator.h"
#include "ssta/eval/label_evaluator.h"
#include "ssta/eval/query_evaluator.h"
#include "ssta/io/file_util.h"
#include "ssta/io/image_io.h"

namespace ssta::cli {
namespace {

struct EvalArguments {
  std::string prediction;
  std::string sequence;
  std::string json_path;
  std::string pictures_dir;
  std::string picture_path;
  bool skip_missing = false;
};

void AddCommon(CLI::App* command, EvalArguments* args, const std::string& pred_help) {
  command->add_option("--pred", args->prediction, pred_help)->required();
  command->add_option("--gt", args->sequence,
                      "synthetic sequence folder holding gt/ (or mav0/gt/)")
      ->required();
  command->add_option("--json", args->json_path, "also write the summary as JSON to this file");
}

// Progress on stderr when it is a terminal; one line, rewritten in place.
void ShowProgress(int done, int total) {
  static const bool is_terminal = ::isatty(STDERR_FILENO) != 0;
  if (!is_terminal) return;
  std::fprintf(stderr, "\rscoring frame %d / %d", done, total);
  if (done == total) std::fprintf(stderr, "\r%*s\r", 40, "");
  std::fflush(stderr);
}

template <typename Summary>
void Report(const Summary& summary, const EvalArguments& args) {
  std::cout << summary.BriefReport();
  if (!args.json_path.empty()) {
    WriteTextAtomically(args.json_path, summary.ToJson());
    std::cout << "JSON summary: " << args.json_path << "\n";
  }
}

}  // namespace

void RegisterEval(CLI::App& app) {
  CLI::App* eval = app.add_subcommand(
      "eval", "Score labels, an exported grid or query answers against synthetic ground truth");
  eval->require_subcommand(1);
  eval->footer(
      "Scored samples have truth 1..3 (255 = don't care, 0 and 4 are not scored). accuracy = "
      "correct / scored (a predicted 0 or 4 is wrong); coverage = share of scored samples with a "
      "verdict 1..3; IoU_c = TP / (TP + FP + FN); mean IoU over classes 1..3 present in the truth "
      "or prediction of scored samples.");

  auto labels_args = std::make_shared<EvalArguments>();
  CLI::App* labels = eval->add_subcommand(
      "labels", "Score per-pixel label images (output of `ssta classify`) frame by frame");
  AddCommon(labels, labels_args.get(),
            "classify output folder (PNGs in DIR/labels/) or a folder of label PNGs");
  labels->add_option("--pictures", labels_args->pictures_dir,
                     "write truth | prediction | errors pictures per frame to this folder");
  labels->add_flag("--skip-missing", labels_args->skip_missing,
                   "leave truth frames without a prediction out of the scores (default: score "
                   "them as all unknown); they are reported either way");
  labels->callback([labels_args] {
    LabelEvalOptions options;
    options.pictures_dir = labels_args->pictures_dir;
    options.progress = ShowProgress;
    options.missing_prediction = labels_args->skip_missing ? MissingPrediction::kSkip
                                                           : MissingPrediction::kScoreAsUnknown;
    Report(EvaluateLabelFolders(labels_args->prediction, labels_args->sequence, options),
           *labels_args);
    if (!labels_args->pictures_dir.empty()) {
      std::cout << "pictures: " << labels_args->pictures_dir << "\n";
    }
  });

  auto grid_args = std::make_shared<EvalArguments>();
  CLI::App* grid = eval->add_subcommand(
      "grid", "Score an exported grid (ssta export --format grid) against gt/grid_classes.png");
  AddCommon(grid, grid_args.get(), "export prefix: reads PREFIX_classes.png and PREFIX.yaml");
  grid->add_option("--picture", grid_args->picture_path,
                   "write a truth | prediction | errors PNG on the truth grid (north up), cropped to the scored cells");
  grid->callback([grid_args] {
    const GridEvalSummary summary = EvaluateExportedGrid(grid_args->prediction, grid_args->sequence);
    Report(summary, *grid_args);
    if (!grid_args->picture_path.empty()) {
      WriteImage(MakeGridComparisonPicture(summary.truth_grid, summary.predicted_grid),
                 grid_args->picture_path);
      std::cout << "picture: " << grid_args->picture_path << "\n";
    }
  });

  auto query_args = std::make_shared<EvalArguments>();
  CLI::App* query = eval->add_subcommand(
      "query", "Score the CSV answers of `ssta query` against the ground-truth grid");
  AddCommon(query, query_args.get(),
            "CSV written by ssta query (x,y,z,class,cost,probability,slope_deg,step_m,observations)");
  query->callback([query_args] {
    Report(EvaluateQueryCsv(query_args->prediction, query_args->sequence), *query_args);
  });
}

}  // namespace ssta::cli
