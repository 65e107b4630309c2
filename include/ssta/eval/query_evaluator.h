#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "ssta/eval/class_grid.h"
#include "ssta/eval/confusion_matrix.h"

namespace ssta {

/// One row of the CSV written by `ssta query` (docs/interfaces.md, section 5). Only the columns the
/// scorer needs are kept.
struct QueryRow {
  double x_m = 0.0;            ///< world x [m]
  double y_m = 0.0;            ///< world y [m]
  std::uint8_t predicted = 0;  ///< class id 0..4
  int line = 0;                ///< 1-based line number in the file
};

/// Reads a query CSV. The first non-empty line is the header; columns are found by name and
/// `x`, `y` and `class` must be among them (the full header of `ssta query` is
/// x,y,z,class,cost,probability,slope_deg,step_m,observations; other columns are not parsed).
/// Empty lines are skipped; CRLF line ends and spaces around fields are accepted. Throws
/// ssta::Error "FILE:LINE: ..." on a missing file or header column, a row with the wrong number
/// of fields, a non-numeric or non-finite x or y, or a class that is not an integer 0..4.
std::vector<QueryRow> ReadQueryCsv(const std::string& path);

/// Result of ScoreQueries / EvaluateQueryCsv.
struct QueryEvalSummary {
  std::string prediction;       ///< the CSV file
  std::string truth;            ///< the truth class image
  std::int64_t rows = 0;        ///< data rows read
  std::int64_t outside_truth = 0;  ///< rows whose (x, y) lies outside the truth grid: unscored
  ConfusionMatrix matrix;       ///< rows inside the truth grid: truth cell class vs row class

  std::string BriefReport() const;
  /// {"kind": "query", "unit": "points", "prediction", "truth", "rows", "outside_truth",
  ///  "metrics": {...}} with "metrics" as described at ConfusionMatrix.
  std::string ToJson() const;
};

/// Scores each row's class against the truth cell containing its (x, y). Rows outside the
/// truth grid are counted in `outside_truth` and not scored; rows on truth 0, 4 or 255 are
/// counted in the matrix but not scored (ConfusionMatrix rules). Throws ssta::Error naming
/// `truth.source` on a truth value other than 0..4 or 255.
QueryEvalSummary ScoreQueries(const std::vector<QueryRow>& rows, const ClassGrid& truth);

/// ReadQueryCsv(csv_path) scored against `truth` (ScoreQueries), with `prediction` set to csv_path.
QueryEvalSummary EvaluateQueryCsv(const std::string& csv_path, const ClassGrid& truth);

/// EvaluateQueryCsv against ReadGroundTruthGrid(sequence).
QueryEvalSummary EvaluateQueryCsv(const std::string& csv_path, const std::string& sequence);

}  // namespace ssta
