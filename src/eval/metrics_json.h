#pragma once

// Private helpers of the scorers' JSON: the fields every summary opens with, and a confusion
// matrix with its scores.

#include <string>

#include "ssta/core/json_writer.h"
#include "ssta/eval/confusion_matrix.h"

namespace ssta::internal {

/// Opens a summary's object with what every scorer's JSON starts with: "kind" (the scorer),
/// "unit" (what it counts), "prediction" and "truth" (what it read).
void BeginSummaryJson(const char* kind, const char* unit, const std::string& prediction, const std::string& truth,
                      JsonWriter* json);

/// Writes one metrics object (schema in include/ssta/eval/eval_summary.h).
void WriteMetricsJson(const ConfusionMatrix& matrix, JsonWriter* json);

}  // namespace ssta::internal
