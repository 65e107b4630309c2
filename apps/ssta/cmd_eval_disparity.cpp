// `ssta eval disparity` scores disparity PNGs against disparity truth; `ssta eval stereo` runs
// the config's stereo matcher over pairs with disparity truth, scores and times it
// (scripts/stereo_benchmark.sh, docs/performance.md).

#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "ssta/bench/stereo_bench.h"
#include "ssta/eval/disparity_evaluator.h"
#include "ssta/files/file_util.h"
#include "ssta/pipeline/config.h"

namespace ssta::cli {
namespace {

struct DisparityArgs {
  std::string prediction, truth, data, json;
  std::vector<std::string> config;
  StereoBenchOptions bench;
};

void AddRule(CLI::App* command, DisparityEvalOptions* rule) {
  command->add_option("--max-error-px", rule->max_error_px,
                      "a pixel is bad when off by more than this [px] and by more than --max-error-ratio")
      ->capture_default_str();
  command->add_option("--max-error-ratio", rule->max_error_ratio,
                      "... and by more than this share of its true disparity (0.05 = 5 %)")
      ->capture_default_str();
}

// The rule's IsValid message, named by the option that set the key.
void CheckRule(const DisparityEvalOptions& rule) {
  std::string error;
  if (rule.IsValid(&error)) return;
  for (const auto& [key, flag] : {std::pair<std::string, std::string>{"max_error_px", "--max-error-px"},
                                  {"max_error_ratio", "--max-error-ratio"}}) {
    if (error.rfind(key, 0) == 0) error = flag + error.substr(key.size());
  }
  throw Error(error);
}

template <typename Report>
void Print(const Report& report, const std::string& json_path) {
  std::cout << report.BriefReport();
  if (!json_path.empty()) {
    WriteTextAtomically(json_path, report.ToJson());
    std::cout << "JSON summary: " << json_path << "\n";
  }
}

const char* const kRuleFooter =
    "D1: share of truth pixels (truth > 0) that are bad: off by more than --max-error-px AND\n"
    "--max-error-ratio of the truth (KITTI: 3 px and 5 %), or without a disparity; also over the\n"
    "matched pixels only. End-point error: mean |estimate - truth| over matched pixels. Density:\n"
    "share of truth pixels with a disparity. Pixels of all pairs are pooled.";

}  // namespace

void AddDisparityEval(CLI::App* eval) {
  auto args = std::make_shared<DisparityArgs>();
  CLI::App* disparity = eval->add_subcommand(
      "disparity", "Score disparity PNGs (16 bit, disparity * 256, 0 = none) against disparity truth");
  disparity
      ->add_option("--pred", args->prediction,
                   "estimate: a PNG, or a folder of PNGs (its disparity/ subfolder when it has one, as "
                   "`classify --disparity` writes)")
      ->required();
  disparity
      ->add_option("--gt", args->truth,
                   "truth: a PNG, or a folder of PNGs paired with --pred by file name (its disparity/ "
                   "subfolder when it has one, as in a synthetic sequence's gt/)")
      ->required();
  AddRule(disparity, &args->bench.rule);
  disparity->add_option("--json", args->json, "also write the summary as JSON to this file")->check(OutputFile());
  disparity->footer(kRuleFooter);
  disparity->callback([args] {
    CheckRule(args->bench.rule);
    Print(EvaluateDisparityFiles(args->prediction, args->truth, args->bench.rule), args->json);
  });

  auto bench_args = std::make_shared<DisparityArgs>();
  CLI::App* stereo = eval->add_subcommand(
      "stereo", "Run the config's stereo matcher over pairs with disparity truth: D1, end-point error, density "
                "and matching time");
  stereo->add_option("--data", bench_args->data, "folder with left/, right/ and gt/ (PNGs of the same names)")
      ->required();
  stereo->add_option("--config", bench_args->config,
                     "YAML config whose stereo section is run (as given to classify); repeatable, later files win");
  stereo->add_option("--pairs", bench_args->bench.max_pairs, "score at most this many pairs (0: all)")
      ->capture_default_str();
  stereo->add_option("--warmup", bench_args->bench.warmup_pairs, "untimed runs on the first pair first")
      ->capture_default_str();
  AddRule(stereo, &bench_args->bench.rule);
  stereo->add_option("--json", bench_args->json, "also write the report as JSON to this file")->check(OutputFile());
  stereo->footer(std::string(kRuleFooter) +
                 "\nTime: the median wall time of the matcher per pair (reading the images is not timed).\n"
                 "The stereo section is used as it is: with no rig, stereo.auto_num_disparities\n"
                 "cannot widen the search range. scripts/stereo_benchmark.sh runs it per setting.");
  stereo->callback([bench_args] {
    CheckRule(bench_args->bench.rule);
    if (bench_args->bench.max_pairs < 0) throw Error("--pairs: must be >= 0");
    if (bench_args->bench.warmup_pairs < 0) throw Error("--warmup: must be >= 0");
    const Config config = LoadLayeredConfig(nullptr, bench_args->config);
    Print(RunStereoBench(bench_args->data, config.stereo, bench_args->bench), bench_args->json);
  });
}

}  // namespace ssta::cli
