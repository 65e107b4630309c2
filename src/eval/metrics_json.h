#pragma once

// Private helper: the JSON form of a confusion matrix and its scores, shared by all scorers.

#include "ssta/core/json_writer.h"
#include "ssta/eval/confusion_matrix.h"

namespace ssta::internal {

/// Writes one metrics object (schema in include/ssta/eval/eval_summary.h).
void WriteMetricsJson(const ConfusionMatrix& matrix, JsonWriter* json);

}  // namespace ssta::internal
