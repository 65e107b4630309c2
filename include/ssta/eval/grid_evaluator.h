#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ssta/eval/class_grid.h"
#include "ssta/eval/confusion_matrix.h"
#include "ssta/eval/distance_band.h"

namespace ssta {

/// Scores a predicted world grid against a truth grid. Every truth cell is one sample: its
/// truth class against the predicted class of the predicted cell that contains the truth
/// cell's centre; a centre outside the predicted grid counts as predicted 0 (unknown), which
/// lowers accuracy and coverage. The grids may differ in origin, extent and resolution.
/// Throws ssta::Error naming `truth.source` / `predicted.source` when the truth holds a value
/// other than 0..4 or 255 or the prediction a value other than 0..4.
ConfusionMatrix ScoreGrid(const ClassGrid& truth, const ClassGrid& predicted);

/// The predicted classes sampled at the centres of the truth cells, 0 (unknown) where a centre
/// lies outside the prediction: an image the size of truth.classes, the prediction ScoreGrid
/// compares cell by cell.
ImageU8 ResampleToGrid(const ClassGrid& predicted, const ClassGrid& truth);

/// MakeComparisonPicture of the truth grid and the resampled prediction (north up: image row 0
/// is the largest y), cropped to the scored cells (truth 1..3) and 10 cells around them (the
/// whole grid when nothing is scored), cells enlarged to whole pixel blocks so that a panel is
/// at least 360 pixels high unless it would grow wider than 1200 pixels. Throws ssta::Error on
/// invalid class values as ScoreGrid.
ImageRgb MakeGridComparisonPicture(const ClassGrid& truth, const ClassGrid& predicted);

/// ScoreGrid split by each truth cell centre's distance from `path` (a polyline of world
/// (x, y) points; one point is a position): band k holds the cells at a distance in
/// [k * band_m, (k + 1) * band_m). Bands run from 0 to the farthest scored cell; a band
/// without scored cells is kept (its matrix is empty). A stereo map's error grows with the
/// square of range, so one accuracy over every cell mixes what the rig resolves with what it
/// cannot. Throws ssta::Error for an empty path, a non-finite point or band_m <= 0, a cell more
/// than 10000 bands from the path (not this grid's path), and on invalid class values as
/// ScoreGrid.
std::vector<DistanceBand> ScoreGridByDistance(const ClassGrid& truth, const ClassGrid& predicted,
                                              const std::vector<Eigen::Vector2d>& path, double band_m);

/// Result of EvaluateExportedGrid.
struct GridEvalSummary {
  std::string prediction;  ///< predicted class image
  std::string truth;       ///< truth class image
  ConfusionMatrix matrix;  ///< one sample per truth cell
  /// Scored truth cells (truth 1..3) whose centre lies outside the predicted grid.
  std::int64_t scored_cells_outside_prediction = 0;
  ClassGrid truth_grid;      ///< as read (for reports)
  ClassGrid predicted_grid;  ///< as read (for reports)
  /// Where the sequence has poses (SEQ/pose0/data.csv): the vehicle's positions, the file
  /// and the score by distance from them in bands of kDistanceBandM (ScoreGridByDistance).
  std::vector<Eigen::Vector2d> path;
  std::string path_source;
  std::vector<DistanceBand> by_distance;
  static constexpr double kDistanceBandM = 2.0;

  std::string BriefReport() const;
  /// {"kind": "grid", "unit": "cells", "prediction", "truth", "truth_grid": {width, height,
  ///  resolution, origin}, "prediction_grid": {...}, "scored_cells_outside_prediction",
  ///  "metrics": {...}} with "metrics" as described at ConfusionMatrix; with a path also
  ///  "by_distance_from_path": {"path", "band_m", "bands": [{"from_m", "to_m", "scored",
  ///  "accuracy", "coverage", "mean_iou", "accuracy_within"}, ...]}, accuracy_within over
  ///  every cell closer than to_m (figures of no cell are null).
  std::string ToJson() const;
};

/// Scores a grid exported by `ssta export --format grid --out PREFIX` (PREFIX_classes.png and
/// PREFIX.yaml) against SEQ/gt/grid_classes.png and SEQ/gt/grid.yaml, and by distance from the
/// path when SEQ has poses (pose0/data.csv next to gt/). Throws ssta::Error naming the file at
/// fault (a pose file that is there but cannot be read is an error too).
GridEvalSummary EvaluateExportedGrid(const std::string& prefix, const std::string& sequence);

}  // namespace ssta
