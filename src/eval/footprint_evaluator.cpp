#include "ssta/eval/footprint_evaluator.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <optional>
#include <utility>

#include "ssta/core/json_writer.h"
#include "eval/class_ids.h"
#include "eval/distance_bands.h"
#include "eval/metrics_json.h"
#include "ssta/core/classes.h"
#include "ssta/core/error.h"
#include "ssta/core/units.h"

namespace ssta {
namespace {


bool IsVerdict(std::uint8_t c) { return c >= 1 && c <= 3; }

/// The worst truth class under the footprint, or 0 when a cell under it is not 1..3; the
/// centre of the cell of that class nearest the footprint's centre into `*worst_at`.
std::uint8_t TruthUnder(const ClassGrid& truth, const FootprintPose& pose, double half_l, double half_w,
                        Eigen::Vector2d* worst_at) {
  const double c = std::cos(pose.yaw_rad), s = std::sin(pose.yaw_rad);
  const double extent_x = std::abs(c) * half_l + std::abs(s) * half_w;
  const double extent_y = std::abs(s) * half_l + std::abs(c) * half_w;
  const double res = truth.resolution_m;
  // Cell indices (column, row from the bottom) whose centres may lie in the rectangle.
  const long col_lo = static_cast<long>(std::ceil((pose.x_m - extent_x - truth.origin_m.x()) / res - 0.5 - 1e-9));
  const long col_hi = static_cast<long>(std::floor((pose.x_m + extent_x - truth.origin_m.x()) / res - 0.5 + 1e-9));
  const long bot_lo = static_cast<long>(std::ceil((pose.y_m - extent_y - truth.origin_m.y()) / res - 0.5 - 1e-9));
  const long bot_hi = static_cast<long>(std::floor((pose.y_m + extent_y - truth.origin_m.y()) / res - 0.5 + 1e-9));
  std::uint8_t worst = 0;
  double nearest2 = std::numeric_limits<double>::infinity();  // squared distance of *worst_at
  bool any = false;
  for (long col = col_lo; col <= col_hi; ++col) {
    for (long bot = bot_lo; bot <= bot_hi; ++bot) {
      const double cx = truth.origin_m.x() + (col + 0.5) * res, cy = truth.origin_m.y() + (bot + 0.5) * res;
      const double dx = cx - pose.x_m, dy = cy - pose.y_m;
      const double along = c * dx + s * dy, across = -s * dx + c * dy;
      // The same test as QueryFootprint's, with a rounding allowance for centres on an edge.
      if (std::abs(along) > half_l + 1e-9 || std::abs(across) > half_w + 1e-9) continue;
      any = true;
      if (col < 0 || col >= truth.classes.width() || bot < 0 || bot >= truth.classes.height()) return 0;
      const std::uint8_t t = truth.classes(truth.classes.height() - 1 - static_cast<int>(bot), static_cast<int>(col));
      if (!IsVerdict(t)) return 0;
      const double distance2 = dx * dx + dy * dy;
      if (t > worst || (t == worst && distance2 < nearest2)) {
        worst = t;
        nearest2 = distance2;
        *worst_at = Eigen::Vector2d(cx, cy);
      }
    }
  }
  if (!any) {
    const std::optional<GridCell> under = truth.CellAt({pose.x_m, pose.y_m});
    if (!under) return 0;
    *worst_at = truth.CellCentre(*under);
    const std::uint8_t t = truth.classes(under->row, under->col);
    return IsVerdict(t) ? t : 0;
  }
  return worst;
}

std::string Fixed(double value, int digits) {
  if (!std::isfinite(value)) return "nan";
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", digits, value);
  return buffer;
}

/// FootprintEvalSummary::by_min_confidence as the poses come: a drivable answer counts at
/// every bar its confidence reaches (no confidence reaches all of them).
class ConfidenceBars {
 public:
  ConfidenceBars() {
    for (const double bar : FootprintEvalSummary::kConfidenceBars) bars_.push_back({bar, 0, 0});
  }

  void Add(std::uint8_t truth, bool drivable, double confidence) {
    if (!drivable) return;
    for (FootprintEvalSummary::ConfidenceBar& bar : bars_) {
      if (!(confidence < bar.min_confidence)) ++(truth == 3 ? bar.unsafe : bar.free_drivable);
    }
  }

  /// The bars with their rates over the truly blocked and truly free poses of `matrix`.
  std::vector<FootprintEvalSummary::ConfidenceBar> Finish(const ConfusionMatrix& matrix) {
    const std::int64_t blocked = matrix.TruthTotal(3), free = matrix.TruthTotal(1) + matrix.TruthTotal(2);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (FootprintEvalSummary::ConfidenceBar& bar : bars_) {
      bar.unsafe_rate = blocked > 0 ? static_cast<double>(bar.unsafe) / blocked : nan;
      bar.free_drivable_rate = free > 0 ? static_cast<double>(bar.free_drivable) / free : nan;
    }
    return std::move(bars_);
  }

 private:
  std::vector<FootprintEvalSummary::ConfidenceBar> bars_;
};

/// The miss of a pose with truth `t` answered `answered`: for an unsafe one the truth's worst
/// cell under it, for a falsely blocked one the cell the answer names.
FootprintMiss MakeMiss(const ClassGrid& truth, const FootprintPose& pose, std::uint8_t t, std::uint8_t answered,
                       const FootprintAnswer& answer, const Eigen::Vector2d& truth_cell, double distance) {
  FootprintMiss miss;
  miss.unsafe = ConfusionMatrix::IsUnsafe(t, answered);
  miss.pose = pose;
  miss.truth = t;
  miss.answer = answered;
  miss.fraction_known = answer.fraction_known;
  miss.distance_from_path_m = distance;
  if (miss.unsafe) {  // TruthUnder's cell, whose class is t
    miss.cell_x_m = truth_cell.x();
    miss.cell_y_m = truth_cell.y();
    miss.cell_truth = t;
  } else {
    miss.cell_x_m = answer.worst_x_m;
    miss.cell_y_m = answer.worst_y_m;
    if (std::isfinite(miss.cell_x_m) && std::isfinite(miss.cell_y_m)) {
      miss.cell_truth = truth.ClassAt({miss.cell_x_m, miss.cell_y_m});
    }
  }
  return miss;
}

}  // namespace

bool FootprintEvalOptions::IsValid(std::string* error) const {
  if (!(std::isfinite(length_m) && length_m > 0.0)) return Fail(error, "length_m: must be a positive number of metres");
  if (!(std::isfinite(width_m) && width_m > 0.0)) return Fail(error, "width_m: must be a positive number of metres");
  if (!(std::isfinite(step_m) && step_m > 0.0)) return Fail(error, "step_m: must be a positive number of metres");
  if (!(std::isfinite(padding_m) && padding_m >= 0.0)) {
    return Fail(error, "padding_m: must be a number of metres >= 0");
  }
  if (!(min_confidence >= 0.0 && min_confidence <= 1.0)) {
    return Fail(error, "min_confidence: must be a probability in [0, 1]");
  }
  if (yaws_deg.empty()) return Fail(error, "yaws_deg: needs at least one heading");
  for (const double yaw : yaws_deg) {
    if (!std::isfinite(yaw)) return Fail(error, "yaws_deg: headings must be finite numbers of degrees");
  }
  return true;
}

FootprintEvalSummary ScoreFootprints(const ClassGrid& truth, const FootprintEvalOptions& options,
                                     const FootprintOracle& oracle, const std::vector<Eigen::Vector2d>& path) {
  std::string error;
  if (!options.IsValid(&error)) throw Error("footprint evaluation: " + error);
  SSTA_CHECK(oracle != nullptr, "ScoreFootprints: no oracle");
  SSTA_CHECK(truth.resolution_m > 0.0, "ScoreFootprints: truth grid without a resolution");
  internal::CheckTruthIds(truth.classes, truth.source);
  FootprintEvalSummary summary;
  summary.truth = truth.source;
  summary.options = options;
  const int k = std::max(1, static_cast<int>(std::lround(options.step_m / truth.resolution_m)));
  const double half_l = 0.5 * options.length_m, half_w = 0.5 * options.width_m;
  double known_sum = 0.0;
  ConfidenceBars bars;
  std::unique_ptr<internal::BandAccumulator> bands;
  if (!path.empty()) bands = std::make_unique<internal::BandAccumulator>(path, FootprintEvalSummary::kDistanceBandM);
  const int height = truth.classes.height();
  for (int bot = k / 2; bot < height; bot += k) {
    for (int col = k / 2; col < truth.classes.width(); col += k) {
      const GridCell cell{height - 1 - bot, col};
      if (!IsVerdict(truth.classes(cell.row, cell.col))) continue;
      const Eigen::Vector2d centre = truth.CellCentre(cell);
      for (const double yaw_deg : options.yaws_deg) {
        const FootprintPose pose{centre.x(), centre.y(), DegToRad(yaw_deg)};
        ++summary.poses;
        Eigen::Vector2d truth_cell = Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
        const std::uint8_t t = TruthUnder(truth, pose, half_l, half_w, &truth_cell);
        if (t == 0) {
          ++summary.partly_unseen;
          continue;
        }
        const FootprintAnswer answer = oracle(pose);
        SSTA_CHECK(answer.worst <= 4, "ScoreFootprints: the oracle answered a class above 4");
        SSTA_CHECK(answer.fraction_known >= 0.0 && answer.fraction_known <= 1.0,
                   "ScoreFootprints: the oracle's fraction_known is not in [0, 1]");
        SSTA_CHECK(!(answer.confidence < 0.0 || answer.confidence > 1.0),
                   "ScoreFootprints: the oracle's confidence is not in [0, 1]");
        const bool drivable = answer.worst == 1 || answer.worst == 2;
        const double confidence = std::isnan(answer.confidence) ? 1.0 : answer.confidence;
        bars.Add(t, drivable, confidence);
        // Below the planner's bar a drivable answer is no answer: undecided.
        const std::uint8_t answered = drivable && confidence < options.min_confidence ? 4 : answer.worst;
        summary.matrix.Add(t, answered);
        if (bands) bands->Add(centre, t, answered);
        if (ConfusionMatrix::IsUnsafe(t, answered) || ConfusionMatrix::IsFalselyBlocked(t, answered)) {
          const double distance = path.empty() ? std::numeric_limits<double>::quiet_NaN()
                                               : internal::DistanceToPath(centre, path);
          summary.misses.push_back(MakeMiss(truth, pose, t, answered, answer, truth_cell, distance));
        }
        if (answer.fraction_known < 1.0) ++summary.partly_known;
        known_sum += answer.fraction_known;
      }
    }
  }
  // Unsafe first, each kind nearest to the path first; stable, so lattice order otherwise.
  std::stable_sort(summary.misses.begin(), summary.misses.end(), [](const FootprintMiss& a, const FootprintMiss& b) {
    if (a.unsafe != b.unsafe) return a.unsafe;
    return a.distance_from_path_m < b.distance_from_path_m;
  });
  summary.unsafe = summary.matrix.Unsafe();
  summary.falsely_blocked = summary.matrix.FalselyBlocked();
  if (bands) summary.by_distance = bands->Finish();
  summary.by_min_confidence = bars.Finish(summary.matrix);
  const std::int64_t scored = summary.matrix.Scored();
  summary.mean_fraction_known = scored > 0 ? known_sum / static_cast<double>(scored)
                                           : std::numeric_limits<double>::quiet_NaN();
  return summary;
}

std::string FootprintEvalSummary::MissesCsv() const {
  std::string out =
      "kind,x_m,y_m,yaw_deg,truth,answer,fraction_known,distance_from_path_m,cell_x_m,cell_y_m,cell_truth,cell_class,cell_rule\n";
  for (const FootprintMiss& m : misses) {
    out += std::string(m.unsafe ? "unsafe" : "falsely_blocked") + "," + Fixed(m.pose.x_m, 3) + "," +
           Fixed(m.pose.y_m, 3) + "," + Fixed(RadToDeg(m.pose.yaw_rad), 1) + "," + std::to_string(m.truth) + "," +
           std::to_string(m.answer) + "," + Fixed(m.fraction_known, 3) + "," + Fixed(m.distance_from_path_m, 2) +
           "," + Fixed(m.cell_x_m, 3) + "," + Fixed(m.cell_y_m, 3) + "," + std::to_string(m.cell_truth) + "," +
           m.cell_class + "," + m.cell_rule + "\n";
  }
  return out;
}

std::vector<FootprintEvalSummary::RuleCount> FootprintEvalSummary::MissesByRule() const {
  std::vector<RuleCount> rows;
  for (const FootprintMiss& m : misses) {
    const std::string rule = m.cell_rule.empty() ? "unknown" : m.cell_rule;
    auto row = std::find_if(rows.begin(), rows.end(), [&](const RuleCount& r) { return r.rule == rule; });
    if (row == rows.end()) row = rows.insert(rows.end(), RuleCount{rule});
    ++(m.unsafe ? row->unsafe : row->falsely_blocked);
    if (!m.unsafe && m.cell_truth == 3) ++row->falsely_blocked_by_a_true_obstacle;
  }
  std::stable_sort(rows.begin(), rows.end(), [](const RuleCount& a, const RuleCount& b) {
    return a.unsafe + a.falsely_blocked > b.unsafe + b.falsely_blocked;
  });
  return rows;
}

std::string FootprintEvalSummary::BriefReport() const {
  std::string out = "eval footprints: " + prediction + " against " + truth + "\n";
  std::string yaws;
  for (const double yaw : options.yaws_deg) yaws += (yaws.empty() ? "" : ", ") + Fixed(yaw, 1);
  out += "footprint " + Fixed(options.length_m, 2) + " x " + Fixed(options.width_m, 2) + " m, every " +
         Fixed(options.step_m, 2) + " m, headings " + yaws + " deg";
  if (options.padding_m > 0.0) out += ", the map asked with " + Fixed(options.padding_m, 2) + " m of padding";
  out += "\n";
  out += "poses: " + std::to_string(poses) + ", partly unseen in the truth (unscored): " +
         std::to_string(partly_unseen) + "\n";
  const std::int64_t scored = matrix.Scored();
  auto share = [&](std::int64_t n) { return scored > 0 ? Fixed(static_cast<double>(n) / scored, 4) : "nan"; };
  out += "partly known to the map: " + std::to_string(partly_known) + " (" + share(partly_known) +
         "), mean known share " + Fixed(mean_fraction_known, 3) + "\n";
  out += matrix.BriefReport("footprints");
  out += internal::BandsReport(by_distance, path_source);
  if (!by_min_confidence.empty()) {
    out += "driving only on answers at least this confident (unsafe / free answered drivable):";
    for (const ConfidenceBar& bar : by_min_confidence) {
      out += " " + Fixed(bar.min_confidence, 2) + ": " + Fixed(100.0 * bar.unsafe_rate, 1) + " % / " +
             Fixed(100.0 * bar.free_drivable_rate, 1) + " %;";
    }
    out.back() = '\n';
  }
  const std::vector<RuleCount> rules = MissesByRule();
  if (!rules.empty() && !(rules.size() == 1 && rules.front().rule == "unknown")) {
    out += "misses by what decided their cell (unsafe / falsely blocked):";
    for (const RuleCount& r : rules) {
      out += " " + r.rule + " " + std::to_string(r.unsafe) + " / " + std::to_string(r.falsely_blocked) + ";";
    }
    out.back() = '\n';
  }
  return out;
}

std::string FootprintEvalSummary::ToJson() const {
  internal::JsonWriter json;
  internal::BeginSummaryJson("footprints", "footprints", prediction, truth, &json);
  json.Key("footprint");
  json.BeginObject();
  json.Key("length_m");
  json.Number(options.length_m);
  json.Key("width_m");
  json.Number(options.width_m);
  json.Key("step_m");
  json.Number(options.step_m);
  json.Key("padding_m");
  json.Number(options.padding_m);
  json.Key("min_confidence");
  json.Number(options.min_confidence);
  json.Key("yaws_deg");
  json.BeginInlineArray();
  for (const double yaw : options.yaws_deg) json.Number(yaw);
  json.EndArray();
  json.EndObject();
  json.Key("poses");
  json.Integer(poses);
  json.Key("partly_unseen");
  json.Integer(partly_unseen);
  json.Key("unsafe");
  json.Integer(unsafe);
  json.Key("falsely_blocked");
  json.Integer(falsely_blocked);
  json.Key("partly_known");
  json.Integer(partly_known);
  json.Key("mean_fraction_known");
  json.Number(mean_fraction_known);
  json.Key("metrics");
  internal::WriteMetricsJson(matrix, &json);
  if (!by_distance.empty()) {
    json.Key("by_distance_from_path");
    internal::WriteBandsJson(by_distance, path_source, kDistanceBandM, &json);
  }
  json.Key("by_min_confidence");
  json.BeginArray();
  for (const ConfidenceBar& bar : by_min_confidence) {
    json.BeginObject();
    json.Key("min_confidence");
    json.Number(bar.min_confidence);
    json.Key("unsafe");
    json.Integer(bar.unsafe);
    json.Key("unsafe_rate");
    json.Number(bar.unsafe_rate);
    json.Key("free_drivable");
    json.Integer(bar.free_drivable);
    json.Key("free_drivable_rate");
    json.Number(bar.free_drivable_rate);
    json.EndObject();
  }
  json.EndArray();
  json.Key("misses_by_rule");
  json.BeginArray();
  for (const RuleCount& r : MissesByRule()) {
    json.BeginObject();
    json.Key("rule");
    json.String(r.rule);
    json.Key("unsafe");
    json.Integer(r.unsafe);
    json.Key("falsely_blocked");
    json.Integer(r.falsely_blocked);
    json.Key("falsely_blocked_by_a_true_obstacle");
    json.Integer(r.falsely_blocked_by_a_true_obstacle);
    json.EndObject();
  }
  json.EndArray();
  json.EndObject();
  return json.Take();
}

}  // namespace ssta
