#include "ssta/eval/query_evaluator.h"

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <sstream>

#include "eval/class_ids.h"
#include "ssta/core/json_writer.h"
#include "eval/metrics_json.h"
#include "ssta/core/classes.h"
#include "ssta/core/error.h"
#include "ssta/files/file_util.h"

namespace ssta {
namespace {

std::string Trim(std::string_view text) {
  const auto first = text.find_first_not_of(" \t\r");
  if (first == std::string_view::npos) return {};
  const auto last = text.find_last_not_of(" \t\r");
  return std::string(text.substr(first, last - first + 1));
}

std::vector<std::string> SplitFields(const std::string& line) {
  std::vector<std::string> fields;
  std::size_t start = 0;
  while (true) {
    const auto comma = line.find(',', start);
    fields.push_back(Trim(std::string_view(line).substr(start, comma == std::string::npos ? std::string::npos : comma - start)));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return fields;
}

double ParseCoordinate(const std::string& field, const std::string& where, const char* column) {
  char* end = nullptr;
  const double value = std::strtod(field.c_str(), &end);
  if (field.empty() || end != field.c_str() + field.size() || !std::isfinite(value)) {
    throw Error(where + ": column '" + column + "': '" + field + "' is not a finite number");
  }
  return value;
}

std::uint8_t ParseClass(const std::string& field, const std::string& where) {
  int value = -1;
  const auto result = std::from_chars(field.data(), field.data() + field.size(), value);
  if (field.empty() || result.ec != std::errc() || result.ptr != field.data() + field.size() ||
      value < 0 || value >= kNumClasses) {
    throw Error(where + ": column 'class': '" + field + "' is not a class id 0..4");
  }
  return static_cast<std::uint8_t>(value);
}

}  // namespace

std::vector<QueryRow> ReadQueryCsv(const std::string& path) {
  if (!std::filesystem::exists(path)) throw Error(path + ": query CSV file not found");
  std::istringstream stream(ReadTextFile(path));
  std::vector<QueryRow> rows;
  std::string line;
  int line_number = 0;
  std::size_t num_columns = 0;
  int x_column = -1, y_column = -1, class_column = -1;
  while (std::getline(stream, line)) {
    ++line_number;
    if (Trim(line).empty()) continue;
    const std::string where = path + ":" + std::to_string(line_number);
    const std::vector<std::string> fields = SplitFields(line);
    if (num_columns == 0) {
      for (std::size_t i = 0; i < fields.size(); ++i) {
        std::string name = fields[i];
        if (i == 0 && !name.empty() && name[0] == '#') name = Trim(name.substr(1));
        if (name == "x") x_column = static_cast<int>(i);
        if (name == "y") y_column = static_cast<int>(i);
        if (name == "class") class_column = static_cast<int>(i);
      }
      if (x_column < 0 || y_column < 0 || class_column < 0) {
        throw Error(where + ": header must name the columns x, y and class (got '" + Trim(line) +
                    "')");
      }
      num_columns = fields.size();
      continue;
    }
    if (fields.size() != num_columns) {
      throw Error(where + ": expected " + std::to_string(num_columns) + " fields like the header, got " +
                  std::to_string(fields.size()));
    }
    QueryRow row;
    row.x_m = ParseCoordinate(fields[x_column], where, "x");
    row.y_m = ParseCoordinate(fields[y_column], where, "y");
    row.predicted = ParseClass(fields[class_column], where);
    row.line = line_number;
    rows.push_back(row);
  }
  if (num_columns == 0) throw Error(path + ":1: empty file, expected a header line");
  return rows;
}

QueryEvalSummary ScoreQueries(const std::vector<QueryRow>& rows, const ClassGrid& truth) {
  internal::CheckTruthIds(truth.classes, truth.source);
  QueryEvalSummary summary;
  summary.truth = truth.source;
  summary.rows = static_cast<std::int64_t>(rows.size());
  for (const QueryRow& row : rows) {
    const auto cell = truth.CellAt({row.x_m, row.y_m});
    if (!cell) {
      ++summary.outside_truth;
      continue;
    }
    summary.matrix.Add(truth.classes(cell->row, cell->col), row.predicted);
  }
  return summary;
}

QueryEvalSummary EvaluateQueryCsv(const std::string& csv_path, const ClassGrid& truth) {
  QueryEvalSummary summary = ScoreQueries(ReadQueryCsv(csv_path), truth);
  summary.prediction = csv_path;
  return summary;
}

QueryEvalSummary EvaluateQueryCsv(const std::string& csv_path, const std::string& sequence) {
  return EvaluateQueryCsv(csv_path, ReadGroundTruthGrid(sequence));
}

std::string QueryEvalSummary::BriefReport() const {
  std::string out = "eval query: " + prediction + " against " + truth + "\n";
  out += "rows: " + std::to_string(rows) + ", outside the truth grid (unscored): " +
         std::to_string(outside_truth) + "\n";
  out += matrix.BriefReport("points");
  return out;
}

std::string QueryEvalSummary::ToJson() const {
  internal::JsonWriter json;
  internal::BeginSummaryJson("query", "points", prediction, truth, &json);
  json.Key("rows");
  json.Integer(rows);
  json.Key("outside_truth");
  json.Integer(outside_truth);
  json.Key("metrics");
  internal::WriteMetricsJson(matrix, &json);
  json.EndObject();
  return json.Take();
}

}  // namespace ssta
