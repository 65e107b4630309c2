#include "ssta/eval/grid_evaluator.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>

#include "eval/class_ids.h"
#include "eval/distance_bands.h"
#include "ssta/core/json_writer.h"
#include "eval/metrics_json.h"
#include "io/text_parsers.h"
#include "ssta/core/classes.h"
#include "ssta/core/error.h"
#include "ssta/eval/label_evaluator.h"
#include "ssta/files/file_util.h"

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

}  // namespace

std::vector<DistanceBand> ScoreGridByDistance(const ClassGrid& truth, const ClassGrid& predicted,
                                              const std::vector<Eigen::Vector2d>& path, double band_m) {
  internal::BandAccumulator bands(path, band_m);
  internal::CheckTruthIds(truth.classes, truth.source);
  internal::CheckPredictedIds(predicted.classes, predicted.source);
  for (int row = 0; row < truth.classes.height(); ++row) {
    for (int col = 0; col < truth.classes.width(); ++col) {
      const std::uint8_t t = truth.classes(row, col);
      if (!IsVerdict(t)) continue;
      const Eigen::Vector2d centre = truth.CellCentre({row, col});
      bands.Add(centre, t, predicted.ClassAt(centre));
    }
  }
  return bands.Finish();
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
  const std::string pose_csv = internal::FindPoseFile(gt_dir);
  if (!pose_csv.empty()) {
    summary.path_source = pose_csv;
    summary.path = internal::ReadPath(summary.path_source);
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
  out += internal::BandsReport(by_distance, path_source);
  return out;
}

std::string GridEvalSummary::ToJson() const {
  internal::JsonWriter json;
  internal::BeginSummaryJson("grid", "cells", prediction, truth, &json);
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
    internal::WriteBandsJson(by_distance, path_source, kDistanceBandM, &json);
  }
  json.EndObject();
  return json.Take();
}

}  // namespace ssta
