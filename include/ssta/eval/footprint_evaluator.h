#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ssta/eval/class_grid.h"
#include "ssta/eval/confusion_matrix.h"
#include "ssta/eval/distance_band.h"

namespace ssta {

/// Where and how large the footprints are that ScoreFootprints asks about.
struct FootprintEvalOptions {
  double length_m = 1.0;  ///< along the heading [m], > 0
  double width_m = 0.6;   ///< across it [m], > 0
  /// Footprint centres sit on every k-th truth cell centre in x and in y, k = max(1,
  /// round(step_m / resolution)): the lattice is the truth grid's own.
  double step_m = 0.5;
  /// Headings [deg from +x towards +y]; a rectangle is the same at yaw and yaw + 180.
  std::vector<double> yaws_deg = {0.0, 45.0, 90.0, 135.0};
  /// The map is asked about the rectangle grown by this on every side, as a planner pads its
  /// robot's footprint; the truth stays the robot's own rectangle [m], >= 0.
  double padding_m = 0.0;
  /// A planner's bar for driving: a footprint answered traversable or semi-traversable with a
  /// FootprintAnswer::confidence below this counts as undecided (neither unsafe nor drivable),
  /// in [0, 1]; 0 takes every answer as it is.
  double min_confidence = 0.0;

  /// True when every field is finite and in range; otherwise `*error` (when not null) gets a
  /// message that starts with the key ("length_m: must be positive").
  bool IsValid(std::string* error) const;
};

/// A footprint: centre (x, y) [m] in the world frame and heading [rad from +x towards +y].
struct FootprintPose {
  double x_m = 0.0;
  double y_m = 0.0;
  double yaw_rad = 0.0;
};

/// What the scored method (a map's footprint query) says about a footprint: the worst class
/// among the cells it knows (1..3, or 4 where an undecided cell outranks the verdicts 1 and 2),
/// 0 when it knows none of them, and the share of the cells it knows. An undecided answer is
/// neither unsafe nor falsely blocked.
struct FootprintAnswer {
  std::uint8_t worst = 0;
  double fraction_known = 0.0;
  /// Centre (x, y) [m] of a cell under the footprint that has the `worst` class, the one
  /// nearest its centre; NaN when the method does not say (or knows no cell).
  double worst_x_m = std::numeric_limits<double>::quiet_NaN();
  double worst_y_m = std::numeric_limits<double>::quiet_NaN();
  /// How sure the method is of a traversable or semi-traversable answer, in [0, 1]
  /// (FootprintResult::drivable_confidence); NaN when it does not say (then it is taken as 1).
  double confidence = std::numeric_limits<double>::quiet_NaN();
};

using FootprintOracle = std::function<FootprintAnswer(const FootprintPose&)>;

/// A scored footprint the method answered unsafely (truly non-traversable, answered
/// traversable or semi) or blocked falsely (truly free, answered non-traversable): where a
/// planner would be misled, for a person to look at (`ssta explain` on its cells).
struct FootprintMiss {
  bool unsafe = false;  ///< true: unsafe; false: falsely blocked
  FootprintPose pose;
  std::uint8_t truth = 0;   ///< the worst truth class under it
  std::uint8_t answer = 0;  ///< FootprintAnswer::worst
  double fraction_known = 0.0;
  /// Its centre's distance from the path [m]; NaN without a path.
  double distance_from_path_m = std::numeric_limits<double>::quiet_NaN();
  /// The cell that makes it a miss, centre (x, y) [m]: for an unsafe footprint a truly
  /// non-traversable cell under it, for a falsely blocked one the cell the method answered
  /// non-traversable (FootprintAnswer::worst_x_m); the one nearest the footprint's centre, NaN
  /// when the method did not say.
  double cell_x_m = std::numeric_limits<double>::quiet_NaN();
  double cell_y_m = std::numeric_limits<double>::quiet_NaN();
  /// The truth's class at that cell (0 when unknown): for a falsely blocked footprint, 3 says
  /// the method's obstacle is real and only touches the footprint's edge (the method counts
  /// every cell the rectangle touches, the truth the cells whose centres lie inside it), 1 or
  /// 2 that the obstacle is false.
  std::uint8_t cell_truth = 0;
  /// What the method says about that cell, filled in by the caller that can ask it (`ssta eval
  /// footprints` asks the map: its class there and the rule that decided it, as `ssta explain`
  /// names them); empty when unknown.
  std::string cell_class;
  std::string cell_rule;
};

/// Result of ScoreFootprints.
struct FootprintEvalSummary {
  std::string prediction;          ///< what answered (the map file)
  std::string truth;               ///< the truth class image
  FootprintEvalOptions options;
  std::int64_t poses = 0;          ///< lattice poses whose centre cell has truth 1..3
  /// Of those, poses with a truth cell under them that is not 1..3 (seen by no frame, or
  /// outside the truth grid): not scored.
  std::int64_t partly_unseen = 0;
  /// Scored poses (every truth cell under them 1..3): truth = the worst of those cells,
  /// predicted = FootprintAnswer::worst. Every scored pose is a sample of the matrix.
  ConfusionMatrix matrix;
  /// Scored poses the method called traversable or semi-traversable whose truth is
  /// non-traversable: the footprint would be driven into an obstacle or off a step
  /// (matrix.Unsafe(); matrix.UnsafeRate() is its share of the truly blocked poses).
  std::int64_t unsafe = 0;
  /// Scored poses the method called non-traversable whose truth is traversable or
  /// semi-traversable (matrix.FalselyBlocked(); the rate is over the truly free poses).
  std::int64_t falsely_blocked = 0;
  /// Scored poses the method did not know in full (fraction_known < 1), and the mean
  /// fraction_known over scored poses (NaN with none).
  std::int64_t partly_known = 0;
  double mean_fraction_known = 0.0;
  /// With a path (the sequence's poses): the scored poses by their centre's distance from it,
  /// in bands of kDistanceBandM, and the pose file.
  std::vector<DistanceBand> by_distance;
  std::string path_source;
  static constexpr double kDistanceBandM = 2.0;
  /// Every unsafe and falsely blocked pose: the unsafe ones first, each kind nearest to the
  /// path first (in lattice order without a path).
  std::vector<FootprintMiss> misses;
  /// What a planner that drives only on answers at least this confident is told, for each of
  /// kConfidenceBars (FootprintEvalOptions::min_confidence as it would set it): the truly
  /// blocked poses it would drive into, the truly free ones it would drive on.
  struct ConfidenceBar {
    double min_confidence = 0.0;
    std::int64_t unsafe = 0;         ///< of the truly blocked scored poses
    std::int64_t free_drivable = 0;  ///< of the truly free (traversable or semi) scored poses
    double unsafe_rate = 0.0;        ///< unsafe / truly blocked; NaN without any
    double free_drivable_rate = 0.0; ///< free_drivable / truly free; NaN without any
  };
  std::vector<ConfidenceBar> by_min_confidence;
  static constexpr double kConfidenceBars[] = {0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.95, 0.99};

  std::string BriefReport() const;
  /// {"kind": "footprints", "unit": "footprints", "prediction", "truth", "footprint":
  ///  {"length_m", "width_m", "step_m", "padding_m", "min_confidence", "yaws_deg"}, "poses",
  ///  "partly_unseen", "unsafe", "falsely_blocked", "partly_known", "mean_fraction_known",
  ///  "metrics": {...}, "by_distance_from_path" (with a path), "by_min_confidence": [{"min_confidence",
  ///  "unsafe", "unsafe_rate", "free_drivable", "free_drivable_rate"}...], "misses_by_rule": [...]}
  /// with "metrics" as described at ConfusionMatrix.
  std::string ToJson() const;
  /// `misses` as CSV: a header line "kind,x_m,y_m,yaw_deg,truth,answer,fraction_known,
  /// distance_from_path_m,cell_x_m,cell_y_m,cell_truth,cell_class,cell_rule", then one line
  /// per miss (kind "unsafe" or "falsely_blocked"; "nan" for a distance or a cell not known, an
  /// empty field for a class or rule not filled in).
  std::string MissesCsv() const;
  /// The misses of each kind counted by their cell_rule ("" counts as "unknown"), most misses
  /// first: which of the method's rules the misleading answers come from.
  struct RuleCount {
    std::string rule;
    std::int64_t unsafe = 0;
    std::int64_t falsely_blocked = 0;
    /// Of the falsely blocked, those whose cell is truly non-traversable (cell_truth 3): a
    /// real obstacle that touches the footprint's edge, not a false one.
    std::int64_t falsely_blocked_by_a_true_obstacle = 0;
  };
  std::vector<RuleCount> MissesByRule() const;
};

/// Asks `oracle` about every footprint of the lattice (FootprintEvalOptions) whose centre cell
/// has truth 1..3, each heading in turn, and scores its worst class against the truth's: the
/// worst of the truth cells whose centres lie inside the rectangle (edges included; the cell
/// under the centre when none does, as TraversabilityMap::QueryFootprint picks map columns).
/// Throws ssta::Error on invalid options (naming the key) or a truth value other than 0..4 or
/// 255 (naming truth.source), and ssta::InternalError when the oracle answers a class above 3
/// or a fraction outside [0, 1].
/// With a non-empty `path` (world (x, y) points of the vehicle's path) the scored poses are
/// also split by their centre's distance from it (FootprintEvalSummary::by_distance).
FootprintEvalSummary ScoreFootprints(const ClassGrid& truth, const FootprintEvalOptions& options,
                                     const FootprintOracle& oracle, const std::vector<Eigen::Vector2d>& path = {});

}  // namespace ssta
