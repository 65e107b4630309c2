#include "ssta/eval/grid_evaluator.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "eval/class_ids.h"
#include "core/json_writer.h"
#include "eval/metrics_json.h"
#include "ssta/core/classes.h"
#include "ssta/eval/label_evaluator.h"

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
  constexpr int kMinHeight = 240;  // [px] wanted panel height
  constexpr int kMaxWidth = 4096;  // [px] panel width not to exceed by enlarging
  internal::CheckTruthIds(truth.classes, truth.source);
  internal::CheckPredictedIds(predicted.classes, predicted.source);
  const ImageU8 resampled = ResampleToGrid(predicted, truth);
  const int h = std::max(1, truth.classes.height());
  const int w = std::max(1, truth.classes.width());
  const int scale = std::max(1, std::min((kMinHeight + h - 1) / h, kMaxWidth / w));
  auto enlarge = [scale](const ImageU8& in) {
    ImageU8 out(in.width() * scale, in.height() * scale);
    for (int v = 0; v < out.height(); ++v) {
      for (int u = 0; u < out.width(); ++u) out(v, u) = in(v / scale, u / scale);
    }
    return out;
  };
  return MakeComparisonPicture(enlarge(truth.classes), enlarge(resampled));
}

GridEvalSummary EvaluateExportedGrid(const std::string& prefix, const std::string& sequence) {
  GridEvalSummary summary;
  summary.truth_grid = ReadGroundTruthGrid(sequence);
  summary.predicted_grid = ReadClassGrid(prefix + ".yaml", prefix + "_classes.png");
  summary.truth = summary.truth_grid.source;
  summary.prediction = summary.predicted_grid.source;
  summary.matrix = ScoreGrid(summary.truth_grid, summary.predicted_grid);
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
  json.EndObject();
  return json.Take();
}

}  // namespace ssta
