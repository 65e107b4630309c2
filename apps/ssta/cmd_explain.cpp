// ssta explain: why a map cell has its class, for people (docs/interfaces.md, CLI).

#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>

#include "commands.h"
#include "map_arguments.h"
#include "ssta/core/classes.h"
#include "ssta/core/units.h"
#include "ssta/mapping/column_explanation.h"
#include "ssta/mapping/surface_judgement.h"
#include "ssta/mapping/traversability_map.h"

namespace ssta::cli {
namespace {

struct ExplainArgs {
  std::string map;
  std::vector<double> at;
  std::vector<std::string> config;
};

std::string Fixed(double v, int decimals) {
  const std::string format = "%." + std::to_string(decimals) + "f";
  return PrintNumber(v, format.c_str());
}

std::string Three(const std::array<double, 3>& v, int decimals) {
  return Fixed(v[0], decimals) + " / " + Fixed(v[1], decimals) + " / " + Fixed(v[2], decimals);
}

/// What the combining rule did, in a sentence.
const char* RuleSentence(JudgeRule rule) {
  switch (rule) {
    case JudgeRule::kSurfaceAlone: return "no frame gave the voxel a class; the fused surface judged alone";
    case JudgeRule::kFramesAlone:
      return "the surface could not judge (too few columns hold a fused height, or their heights are smeared "
             "sideways); the frames decided";
    case JudgeRule::kFramesSurfacePartial:
      return "the surface found open ground but does not see every column of the disc, so it cannot vouch "
             "for it; the frames decided";
    case JudgeRule::kWorseOfTwo: return "the surface found a slope or a jump: the worse of the two verdicts counts";
    case JudgeRule::kProduct:
      return "the surface sees the whole disc and found open ground: its probabilities, mixed with "
             "class_surface_miss_prob of a uniform one, multiply the frames'";
    case JudgeRule::kPriorWithheld:
      return "the frames' votes lean to an obstacle, too weakly (under class_prior_min_evidence_views) for "
             "the open-ground prior to overrule them: undecided";
    case JudgeRule::kObstacleWithheld:
      return "the frames' votes call an obstacle on fewer clear views than class_obstacle_min_evidence_views "
             "(as much as stereo noise at their range can make): undecided, not blocked";
    case JudgeRule::kSmearedHazard:
      return "the surface's heights are smeared sideways, and within their smear it finds a jump or slope "
             "beyond max that noise does not explain, which stereo cannot place within the step radius or "
             "beyond it: undecided";
    default: return "no class: nothing observed here, or no evidence to judge by";
  }
}

void Explain(const ExplainArgs& args) {
  if (args.at.size() != 2) throw Error("--at: give X,Y (a column of the map)");
  for (double v : args.at) {
    if (!std::isfinite(v)) throw Error("--at: NaN or infinite value");
  }
  const TraversabilityMap map = LoadMapForConfig(args.map, args.config);
  const ColumnExplanation why = map.ExplainColumn(args.at[0], args.at[1]);
  const CellInfo& c = why.cell;
  std::cout << "column " << Fixed(c.center.x(), 4) << ", " << Fixed(c.center.y(), 4) << " (asked "
            << Fixed(args.at[0], 4) << ", " << Fixed(args.at[1], 4) << ")\n";
  if (!c.observed) {
    std::cout << "class: 0 (unknown): no surface observed in this column\n";
    return;
  }
  std::cout << "top voxel: z " << Fixed(c.center.z(), 3) << " m, fused height " << Fixed(c.surface_z_m, 3)
            << " +- " << Fixed(c.height_sigma_m, 3) << " m\n";
  std::cout << "class: " << static_cast<int>(c.cls) << " (" << ClassName(c.cls) << "), confidence "
            << Fixed(c.confidence, 3) << ", cost " << Fixed(c.cost, 3) << ", decided by: "
            << (c.decided_by == ClassJudge::kNone ? "nothing" : ClassJudgeName(c.decided_by)) << "\n";
  std::cout << "rule: " << JudgeRuleName(why.rule) << ": " << RuleSentence(why.rule) << "\n";
  std::cout << "posterior (traversable / semi / non-traversable): " << Three(why.posterior, 3) << "\n";
  std::cout << "frames: " << c.observations << " gave a class; votes as class log-odds " << Three(why.frame_log_odds, 2)
            << "; probabilities " << Three(why.frame_probability, 3) << " (with the open-ground prior "
            << Fixed(map.options().class_prior_traversable_log_odds, 2) << ")\n";
  if (why.evidence_views > 0.0) {  // the frames voted
    const double views = why.evidence_views;
    const double needed = map.options().class_min_evidence_views;
    std::cout << "evidence: " << Fixed(views, 2) << " clear views (a verdict from " << Fixed(needed, 2) << ")"
              << (views < needed ? ": too weak, no view resolved this ground: no verdict from the frames" : "")
              << "\n";
  }
  // A point's step is its segment's height above its frame's ground plane, not a jump beside it.
  std::cout << "frames' means: slope " << Fixed(c.frame_mean_slope_deg, 2) << " deg, step to the ground plane "
            << Fixed(c.frame_mean_step_m, 3) << " m (largest a frame saw " << Fixed(c.max_step_m, 3) << " m)\n";
  std::cout << "free space: occupancy log-odds " << Fixed(why.occupancy_log_odds, 2) << " (probability "
            << Fixed(why.occupancy, 3) << "; a surface from " << Fixed(why.occupied_threshold, 3)
            << "): hits raise it, rays passing through lower it\n";
  const SurfaceVerdict& s = why.surface;
  const double radius = SurfaceDiscRadius(map.metadata().vehicle.step_radius_m, map.options().resolution_m);
  std::cout << "surface: " << why.surface_columns << " columns within " << Fixed(radius, 2)
            << " m hold a fused height (coverage " << Fixed(s.coverage, 2) << ", whole disc seen: "
            << (why.disc_fully_seen ? "yes" : "no") << ")";
  if (s.determined) {
    std::cout << "; slope " << Fixed(s.slope_deg, 2) << " +- " << Fixed(s.slope_sigma_deg, 2) << " deg, step "
              << Fixed(s.step_m, 3) << " +- " << Fixed(s.step_sigma_m, 3) << " m; probabilities "
              << Three(s.probability, 3) << "\n";
  } else {
    std::cout << (s.smeared ? "; their heights may come from more than half the radius away (stereo's range "
                              "error smears them sideways): no judgement\n"
                            : "; too few to judge\n");
  }
  const SurfaceRegion& region = why.smeared_region;
  if (region.along_m > 0.0) {
    const SurfaceVerdict& w = why.smeared_surface;
    std::cout << "smeared surface: the columns within " << Fixed(region.along_m, 2) << " m along the view's ray (heading "
              << Fixed(RadToDeg(std::atan2(region.axis.y(), region.axis.x())), 0) << " deg) and "
              << Fixed(region.across_m, 2) << " m across it (coverage " << Fixed(w.coverage, 2)
              << "; the step radius widened by their horizontal sigma " << Fixed(s.xy_sigma_m, 3) << " m)";
    if (w.determined) {
      std::cout << "; slope " << Fixed(w.slope_deg, 2) << " +- " << Fixed(w.slope_sigma_deg, 2) << " deg, step "
                << Fixed(w.step_m, 3) << " +- " << Fixed(w.step_sigma_m, 3) << " m; probabilities "
                << Three(w.probability, 3) << "\n";
    } else {
      std::cout << "; too few to judge\n";
    }
  }
}

}  // namespace

void RegisterExplain(CLI::App& app) {
  auto args = std::make_shared<ExplainArgs>();
  CLI::App* cmd = app.add_subcommand("explain", "Why a map column has its class: the evidence and the rule");
  cmd->footer(
      "Prints the column's class, confidence and cost, which judge decided and by which rule, the frames'\n"
      "class votes, the free-space evidence and the fused surface's slope and step with their sigmas\n"
      "(maps/README.md, \"top surface\").");
  cmd->add_option("--map", args->map, "map file (.ot) written by build-map")->required();
  AddMapConfig(cmd, &args->config);
  cmd->add_option("--at", args->at, "the column: X,Y [m, world frame]")
      ->delimiter(',')
      ->expected(1, 2)
      ->type_name("X,Y")
      ->required();
  cmd->callback([args] { Explain(*args); });
}

}  // namespace ssta::cli
