#include "ssta/eval/grid_evaluator.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>

#include "eval/class_ids.h"
#include "core/json_writer.h"
#include "eval/metrics_json.h"
#include "io/text_parsers.h"
#include "ssta/core/classes.h"
#include "ssta/core/error.h"
#include "ssta/eval/label_evaluator.h"
#include "ssta/io/file_util.h"

namespace ssta {
namespace {

bool IsVerdict(std::uint8_t c) { return c >= 1 && c <= 3; }

void WriteGridJson(const ClassGrid& grid, internal::JsonWriter* json) {
  json->BeginObject();
  json->Key("width");
  json->Integer(grid.classes.width());
  json->Key("height");
  json->Integer(grid.classes.height());
  json->Key("resolution");
  json->Number(grid.resolution_m);
  json->Key("origin");
  json->BeginInlineArray();
  json->Number(grid.origin_m.x());
  json->Number(grid.origin_m.y());
  json->Number(0.0);
  json->EndArray();
  json->EndObject();
}

std::string GridText(const ClassGrid& grid) {
  char line[200];
  std::snprintf(line, sizeof line, "%dx%d cells of %.4g m, lower-left corner (%.4g, %.4g) m",
                grid.classes.width(), grid.classes.height(), grid.resolution_m, grid.origin_m.x(),
                grid.origin_m.y());
  return line;
}

/// Distance from `p` to the polyline `path` (at least one point).
double DistanceToPath(const Eigen::Vector2d& p, const std::vector<Eigen::Vector2d>& path) {
  if (path.size() == 1) return (p - path.front()).norm();
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 1; i < path.size(); ++i) {
    const Eigen::Vector2d a = path[i - 1], ab = path[i] - a;
    const double length_sq = ab.squaredNorm();
    const double t = length_sq > 0.0 ? std::clamp((p - a).dot(ab) / length_sq, 0.0, 1.0) : 0.0;
    best = std::min(best, (p - (a + t * ab)).norm());
  }
  return best;
}

/// The vehicle's (x, y) positions from a pose file, thinned to one per kPathSpacingM of travel
/// (the polyline between them is what ScoreGridByDistance measures to).
std::vector<Eigen::Vector2d> ReadPath(const std::string& pose_csv) {
  constexpr double kPathSpacingM = 0.25;
  std::vector<Eigen::Vector2d> path;
  const std::vector<PoseSample> poses = internal::ParseAslPoseCsv(ReadTextFile(pose_csv), pose_csv);
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const Eigen::Vector2d p = poses[i].world_p_body.head<2>();
    if (path.empty() || (p - path.back()).norm() >= kPathSpacingM || i + 1 == poses.size()) path.push_back(p);
  }
  return path;
}

}  // namespace

std::vector<DistanceBand> ScoreGridByDistance(const ClassGrid& truth, const ClassGrid& predicted,
                                              const std::vector<Eigen::Vector2d>& path, double band_m) {
  constexpr int kMaxBands = 10000;
  if (!(band_m > 0.0) || !std::isfinite(band_m)) throw Error("distance bands: band_m must be positive");
  if (path.empty()) throw Error("distance bands: the path has no points");
  for (const Eigen::Vector2d& p : path) {
    if (!p.allFinite()) throw Error("distance bands: the path has a point that is not finite");
  }
  internal::CheckTruthIds(truth.classes, truth.source);
  internal::CheckPredictedIds(predicted.classes, predicted.source);
  std::vector<DistanceBand> bands;
  for (int row = 0; row < truth.classes.height(); ++row) {
    for (int col = 0; col < truth.classes.width(); ++col) {
      const std::uint8_t t = truth.classes(row, col);
      if (!IsVerdict(t)) continue;
      const Eigen::Vector2d centre = truth.CellCentre({row, col});
      const double distance = DistanceToPath(centre, path);
      if (distance / band_m >= kMaxBands) {
        char message[200];
        std::snprintf(message, sizeof message,
                      "a scored cell lies %.0f m from the path (over %d bands of %g m): is the path this grid's?",
                      distance, kMaxBands, band_m);
        throw Error(std::string("distance bands: ") + message);
      }
      const auto band = static_cast<std::size_t>(std::floor(distance / band_m));
      while (bands.size() <= band) {
        DistanceBand b;
        b.from_m = static_cast<double>(bands.size()) * band_m;
        b.to_m = b.from_m + band_m;
        bands.push_back(b);
      }
      bands[band].matrix.Add(t, predicted.ClassAt(centre));
    }
  }
  std::int64_t scored = 0, correct = 0;  // of the bands so far
  for (DistanceBand& b : bands) {
    scored += b.matrix.Scored();
    correct += b.matrix.Correct();
    b.accuracy_within = scored > 0 ? static_cast<double>(correct) / static_cast<double>(scored)
                                   : std::numeric_limits<double>::quiet_NaN();
  }
  return bands;
}

ImageU8 ResampleToGrid(const ClassGrid& predicted, const ClassGrid& truth) {
  ImageU8 out(truth.classes.width(), truth.classes.height());
  for (int row = 0; row < out.height(); ++row) {
    for (int col = 0; col < out.width(); ++col) {
      out(row, col) = predicted.ClassAt(truth.CellCentre({row, col}));
    }
  }
  return out;
}

ConfusionMatrix ScoreGrid(const ClassGrid& truth, const ClassGrid& predicted) {
  // Checked before resampling so that a bad value is reported at its own cell.
  internal::CheckTruthIds(truth.classes, truth.source);
  internal::CheckPredictedIds(predicted.classes, predicted.source);
  return ScoreLabels(truth.classes, ResampleToGrid(predicted, truth), truth.source,
                     predicted.source + " (resampled to the truth grid)");
}

ImageRgb MakeGridComparisonPicture(const ClassGrid& truth, const ClassGrid& predicted) {
  constexpr int kMinHeight = 360;  // [px] wanted panel height
  constexpr int kMaxWidth = 1200;  // [px] panel width not to exceed by enlarging
  constexpr int kMargin = 10;      // [cells] kept around the scored area
  internal::CheckTruthIds(truth.classes, truth.source);
  internal::CheckPredictedIds(predicted.classes, predicted.source);
  const ImageU8 resampled = ResampleToGrid(predicted, truth);
  // The scored area (truth 1..3) with a margin: the truth grid of a sequence spans every place
  // any frame could see, most of it don't-care, and the map would be a speck in it.
  const ImageU8& t = truth.classes;
  int u0 = t.width(), v0 = t.height(), u1 = -1, v1 = -1;
  for (int v = 0; v < t.height(); ++v) {
    for (int u = 0; u < t.width(); ++u) {
      if (t(v, u) < 1 || t(v, u) > 3) continue;
      u0 = std::min(u0, u);
      u1 = std::max(u1, u);
      v0 = std::min(v0, v);
      v1 = std::max(v1, v);
    }
  }
  if (u1 < 0) {  // nothing scored: the whole grid
    u0 = v0 = 0;
    u1 = t.width() - 1;
    v1 = t.height() - 1;
  } else {
    u0 = std::max(0, u0 - kMargin);
    v0 = std::max(0, v0 - kMargin);
    u1 = std::min(t.width() - 1, u1 + kMargin);
    v1 = std::min(t.height() - 1, v1 + kMargin);
  }
  const int w = std::max(1, u1 - u0 + 1);
  const int h = std::max(1, v1 - v0 + 1);
  const int scale = std::max(1, std::min((kMinHeight + h - 1) / h, kMaxWidth / w));
  auto crop_and_enlarge = [&](const ImageU8& in) {
    ImageU8 out(w * scale, h * scale);
    for (int v = 0; v < out.height(); ++v) {
      for (int u = 0; u < out.width(); ++u) out(v, u) = in(v0 + v / scale, u0 + u / scale);
    }
    return out;
  };
  return MakeComparisonPicture(crop_and_enlarge(t), crop_and_enlarge(resampled));
}

GridEvalSummary EvaluateExportedGrid(const std::string& prefix, const std::string& sequence) {
  GridEvalSummary summary;
  const std::string gt_dir = FindGroundTruthDir(sequence);
  summary.truth_grid = ReadGroundTruthGrid(gt_dir);
  summary.predicted_grid = ReadClassGrid(prefix + ".yaml", prefix + "_classes.png");
  summary.truth = summary.truth_grid.source;
  summary.prediction = summary.predicted_grid.source;
  summary.matrix = ScoreGrid(summary.truth_grid, summary.predicted_grid);
  const std::filesystem::path pose_csv =
      std::filesystem::path(gt_dir).lexically_normal().parent_path() / "pose0" / "data.csv";
  if (std::filesystem::exists(pose_csv)) {
    summary.path_source = pose_csv.string();
    summary.path = ReadPath(summary.path_source);
    if (!summary.path.empty()) {
      try {
        summary.by_distance = ScoreGridByDistance(summary.truth_grid, summary.predicted_grid, summary.path,
                                                  GridEvalSummary::kDistanceBandM);
      } catch (const Error& e) {  // the path is the pose file's: name it
        throw Error(summary.path_source + ": " + e.what());
      }
    }
  }
  const ClassGrid& truth = summary.truth_grid;
  for (int row = 0; row < truth.classes.height(); ++row) {
    for (int col = 0; col < truth.classes.width(); ++col) {
      if (IsVerdict(truth.classes(row, col)) &&
          !summary.predicted_grid.CellAt(truth.CellCentre({row, col}))) {
        ++summary.scored_cells_outside_prediction;
      }
    }
  }
  return summary;
}

std::string GridEvalSummary::BriefReport() const {
  std::string out = "eval grid: " + prediction + " against " + truth + "\n";
  out += "truth grid:      " + GridText(truth_grid) + "\n";
  out += "predicted grid:  " + GridText(predicted_grid) + "\n";
  out += "scored truth cells outside the predicted grid (scored as unknown): " +
         std::to_string(scored_cells_outside_prediction) + "\n";
  out += matrix.BriefReport("cells");
  if (!by_distance.empty()) {
    out += "by distance from the path (" + path_source + "):\n";
    out += "distance [m]   scored   accuracy   coverage   mean IoU   accuracy within\n";
    for (const DistanceBand& b : by_distance) {
      char line[200];
      const ConfusionMatrix& m = b.matrix;
      char within[32] = "-";
      if (std::isfinite(b.accuracy_within)) std::snprintf(within, sizeof within, "%.4f", b.accuracy_within);
      if (m.Scored() == 0) {
        std::snprintf(line, sizeof line, "%5.0f - %-5.0f %8d          -          -          - %17s\n", b.from_m,
                      b.to_m, 0, within);
      } else {
        std::snprintf(line, sizeof line, "%5.0f - %-5.0f %8lld %10.4f %10.4f %10.4f %17s\n", b.from_m, b.to_m,
                      static_cast<long long>(m.Scored()), m.Accuracy(), m.Coverage(), m.MeanIou(), within);
      }
      out += line;
    }
  }
  return out;
}

std::string GridEvalSummary::ToJson() const {
  internal::JsonWriter json;
  json.BeginObject();
  json.Key("kind");
  json.String("grid");
  json.Key("unit");
  json.String("cells");
  json.Key("prediction");
  json.String(prediction);
  json.Key("truth");
  json.String(truth);
  json.Key("truth_grid");
  WriteGridJson(truth_grid, &json);
  json.Key("prediction_grid");
  WriteGridJson(predicted_grid, &json);
  json.Key("scored_cells_outside_prediction");
  json.Integer(scored_cells_outside_prediction);
  json.Key("metrics");
  internal::WriteMetricsJson(matrix, &json);
  if (!by_distance.empty()) {
    json.Key("by_distance_from_path");
    json.BeginObject();
    json.Key("path");
    json.String(path_source);
    json.Key("band_m");
    json.Number(kDistanceBandM);
    json.Key("bands");
    json.BeginArray();
    constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
    for (const DistanceBand& b : by_distance) {
      const bool any = b.matrix.Scored() > 0;
      json.BeginObject();
      json.Key("from_m");
      json.Number(b.from_m);
      json.Key("to_m");
      json.Number(b.to_m);
      json.Key("scored");
      json.Integer(b.matrix.Scored());
      json.Key("accuracy");
      json.Number(any ? b.matrix.Accuracy() : kNaN);
      json.Key("coverage");
      json.Number(any ? b.matrix.Coverage() : kNaN);
      json.Key("mean_iou");
      json.Number(any ? b.matrix.MeanIou() : kNaN);
      json.Key("accuracy_within");
      json.Number(b.accuracy_within);  // NaN: null
      json.EndObject();
    }
    json.EndArray();
    json.EndObject();
  }
  json.EndObject();
  return json.Take();
}

}  // namespace ssta
