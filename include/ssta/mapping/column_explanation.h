#pragma once

// Why a column of the map has its class: the frames' votes, the free-space evidence, the fused
// surface's verdict and the rule that combined them (TraversabilityMap::ExplainColumn,
// `ssta explain`).

#include <array>
#include <cstdint>
#include <limits>

#include "ssta/mapping/map_types.h"
#include "ssta/mapping/surface_judgement.h"

namespace ssta {

/// How a column's class came from its two judges, the frames' class votes and the fused
/// surface around it (maps/README.md, "top surface").
enum class JudgeRule : std::uint8_t {
  kNone,           ///< no class: the column is unobserved, or neither judge has evidence
  kSurfaceAlone,   ///< no frame gave the voxel a class; the fused surface judged alone
  kFramesAlone,    ///< too few columns around it hold a fused height for the surface to judge
  /// The surface found open ground but does not hold a height in every column that meets the
  /// disc of the step radius, so it cannot vouch for it: the frames decided.
  kFramesSurfacePartial,
  kWorseOfTwo,  ///< the surface found a slope or a jump: the worse of the two verdicts
  /// The surface, seeing the whole disc, found open ground: its class probabilities multiplied
  /// the frames'.
  kProduct,
  /// The frames decided, and their votes lean to an obstacle, but hold fewer clear views than
  /// MapOptions::class_prior_min_evidence_views: the open-ground prior does not answer for the
  /// column, which is undecided.
  kPriorWithheld,
  /// The frames decided an obstacle, on fewer clear views of obstacle evidence than
  /// MapOptions::class_obstacle_min_evidence_views: stereo noise at the views' range can make
  /// that much, so the column is undecided rather than blocked.
  kObstacleWithheld,
  /// The fused heights are smeared sideways (far ground), and over the disc their horizontal
  /// sigma widens the step radius to, the surface finds a jump or slope beyond max that noise
  /// does not explain: a hazard stereo cannot place within the step radius or beyond it. Unless
  /// the frames call the column non-traversable, it is undecided.
  kSmearedHazard,
};

/// Lower-case name, as `ssta explain` prints it: "none", "surface alone", "frames alone",
/// "frames (surface partial)", "worse of two", "product", "prior withheld",
/// "obstacle withheld", "smeared hazard".
const char* JudgeRuleName(JudgeRule rule);

/// The evidence behind TopSurfaceAt(x, y).
struct ColumnExplanation {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  CellInfo cell;                  ///< TopSurfaceAt's answer (class, confidence, decided_by, ...)
  JudgeRule rule = JudgeRule::kNone;
  /// The top voxel's class log-odds for classes 1..3: the frames' weighted votes (a lip or an
  /// obstacle counts more than open ground; docs: maps/README.md, "fusion"). 0 without votes.
  std::array<double, 3> frame_log_odds{0.0, 0.0, 0.0};
  /// That evidence in clear views (the largest |L_k| over one clear vote's, obstacle gain
  /// included); under MapOptions::class_min_evidence_views the frames give no verdict.
  double evidence_views = 0.0;
  /// The frames' class probabilities (with the open-ground prior); NaN without votes.
  std::array<double, 3> frame_probability{kNaN, kNaN, kNaN};
  /// Free-space evidence: the top voxel's occupancy log-odds (hits raise it, rays that pass
  /// through lower it) and its probability; NaN unobserved.
  double occupancy_log_odds = kNaN;
  double occupancy = kNaN;
  double occupied_threshold = kNaN;  ///< the occupancy at and above which a voxel is a surface
  SurfaceVerdict surface;            ///< the fused surface's verdict around the column
  int surface_columns = 0;           ///< columns within SurfaceDiscRadius holding a fused height
  bool disc_fully_seen = false;      ///< every column meeting the disc holds a fused height
  /// Where `surface` is smeared and MapOptions::class_smeared_surface_hazards is on: the verdict
  /// over the region its smear widens the disc to (JudgeSmearedSurface) and that region; else
  /// a region of zero size.
  SurfaceVerdict smeared_surface;
  SurfaceRegion smeared_region;
  /// The combined class probabilities (traversable, semi, non-traversable); NaN without a class.
  std::array<double, 3> posterior{kNaN, kNaN, kNaN};
};

}  // namespace ssta
