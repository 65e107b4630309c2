// ssta diff-maps: what changed between two maps of one site (docs/fleet.md).

#include <iostream>
#include <memory>

#include "commands.h"
#include "map_arguments.h"
#include "ssta/core/error.h"
#include "ssta/pictures/map_diff_picture.h"

namespace ssta::cli {
namespace {

struct DiffMapsArgs {
  std::string a, b;
  std::string out;
  MapDiffOptions options;
  bool quiet = false;
};

void Run(const DiffMapsArgs& args) {
  std::string error;
  if (!args.options.IsValid(&error)) throw Error("--" + error);
  const TraversabilityMap a = TraversabilityMap::Load(args.a);
  const TraversabilityMap b = TraversabilityMap::Load(args.b);
  const MapDiff diff = DiffMaps(a, args.a, b, args.b, args.options);
  WriteMapDiff(diff, args.out, "Changes from " + args.a + " to " + args.b);
  if (!args.quiet) std::cout << diff.summary.BriefReport() << "written: " << args.out << "/diff.csv, " << args.out << "/diff.png\n";
}

}  // namespace

void RegisterDiffMaps(CLI::App& app) {
  auto args = std::make_shared<DiffMapsArgs>();
  CLI::App* cmd = app.add_subcommand(
      "diff-maps",
      "what changed between two maps of one site (same resolution, world frame and vehicle): a picture and a "
      "CSV of the columns whose class changed (docs/fleet.md)");
  cmd->footer(
      "Writes OUT/diff.csv (x,y,class_a,class_b,confidence_a,confidence_b,change, one row per column whose\n"
      "class changed) and OUT/diff.png, and prints the count of each change. Changes: new_obstacle,\n"
      "cleared, harder (traversable -> semi), easier (semi -> traversable), newly_seen, no_longer_seen,\n"
      "and uncertain: a change where a map holds its class below --min-confidence, saw a surface it could\n"
      "not judge (undecided), a change to or from semi-traversable whose slope and step moved less\n"
      "than --slope-noise-deg and --step-noise-m, or a boundary between two classes that moved by up to\n"
      "--boundary-shift columns (the rim of an obstacle seen in both).");
  cmd->add_option("map_a", args->a, "the earlier map (.ot)")->required()->check(CLI::ExistingFile);
  cmd->add_option("map_b", args->b, "the later map (.ot)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--out", args->out, "folder to write diff.csv and diff.png into (created)")
      ->required()
      ->check(OutputFolder());
  cmd->add_option("--min-confidence", args->options.min_confidence,
                  "a change counts where both maps hold their class at least this sure, in [0, 1]")
      ->capture_default_str();
  cmd->add_option("--slope-noise-deg", args->options.slope_noise_deg,
                  "a change to or from semi-traversable counts where the slope moved more than this [deg]")
      ->capture_default_str();
  cmd->add_option("--step-noise-m", args->options.step_noise_m, "... or the step more than this [m]")
      ->capture_default_str();
  cmd->add_option("--boundary-shift", args->options.boundary_shift_columns,
                  "a change where each map holds the other's class within this many columns is uncertain: a\n"
                  "boundary that moved (0: off)")
      ->capture_default_str();
  cmd->add_flag("--quiet,-q", args->quiet, "no report");
  cmd->callback([args] { Run(*args); });
}

}  // namespace ssta::cli
