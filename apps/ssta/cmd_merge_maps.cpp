// ssta merge-maps: several maps of one site (one per recording) into one map.

#include <filesystem>
#include <iostream>
#include <system_error>

#include "commands.h"
#include "map_arguments.h"
#include "ssta/core/error.h"
#include "ssta/files/file_util.h"
#include "ssta/mapping/map_merge.h"

namespace ssta::cli {
namespace {

struct MergeMapsArgs {
  std::vector<std::string> inputs;
  std::string out;
  MergeOptions options;
  bool quiet = false;
};

void Run(const MergeMapsArgs& a) {
  // The output may replace an input only once every input is read; MergeMaps reads them all
  // before Save writes, and Save replaces the file atomically, so that is safe. An input named
  // twice would count its evidence twice: refused here before any file is read. A copy of an
  // input, or a merged map holding another input, MergeMaps refuses by the sources' checksums.
  for (std::size_t i = 0; i < a.inputs.size(); ++i) {
    for (std::size_t j = i + 1; j < a.inputs.size(); ++j) {
      std::error_code error;
      if (std::filesystem::equivalent(a.inputs[i], a.inputs[j], error)) {
        throw Error(a.inputs[j] + ": given twice (as " + a.inputs[i] + "); its evidence would count twice");
      }
    }
  }
  // One writer per map: held from before the inputs are read until the output is saved.
  const MapWriteLock lock(a.out);
  MergeSummary summary;
  const TraversabilityMap merged = MergeMaps(a.inputs, &summary, a.options);
  merged.Save(a.out);
  if (!a.quiet) std::cout << summary.BriefReport() << "map: " << a.out << "\n";
}

}  // namespace

void RegisterMergeMaps(CLI::App& app) {
  auto args = std::make_shared<MergeMapsArgs>();
  CLI::App* cmd = app.add_subcommand(
      "merge-maps",
      "add the evidence of maps of one site (same resolution, vehicle and world frame) into one map "
      "(docs/fleet.md)");
  cmd->add_option("maps", args->inputs, "map files (.ot) written by build-map or merge-maps")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", args->out, "merged map file to write (.ot), replaced atomically")
      ->required()
      ->check(OutputFile());
  cmd->add_flag("--allow-overlap", args->options.allow_overlap,
                "merge maps that share frames of a recording (same time and image: the same recording twice, "
                "every second frame of it, a bag and its folder); their evidence then counts twice");
  cmd->add_flag("--quiet,-q", args->quiet, "no report");
  cmd->callback([args] { Run(*args); });
}

}  // namespace ssta::cli
