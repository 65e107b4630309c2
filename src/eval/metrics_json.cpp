#include "eval/metrics_json.h"

namespace ssta::internal {

void BeginSummaryJson(const char* kind, const char* unit, const std::string& prediction, const std::string& truth,
                      JsonWriter* json) {
  json->BeginObject();
  json->Key("kind");
  json->String(kind);
  json->Key("unit");
  json->String(unit);
  json->Key("prediction");
  json->String(prediction);
  json->Key("truth");
  json->String(truth);
}

void WriteMetricsJson(const ConfusionMatrix& matrix, JsonWriter* json) {
  json->BeginObject();
  json->Key("scored");
  json->Integer(matrix.Scored());
  json->Key("correct");
  json->Integer(matrix.Correct());
  json->Key("decided");
  json->Integer(matrix.Decided());
  json->Key("not_scored");
  json->BeginObject();
  json->Key("dont_care");
  json->Integer(matrix.dont_care());
  json->Key("truth_unknown");
  json->Integer(matrix.TruthTotal(0));
  json->Key("truth_undecided");
  json->Integer(matrix.TruthTotal(4));
  json->EndObject();
  json->Key("accuracy");
  json->Number(matrix.Accuracy());
  json->Key("coverage");
  json->Number(matrix.Coverage());
  json->Key("decided_accuracy");
  json->Number(matrix.DecidedAccuracy());
  json->Key("mean_iou");
  json->Number(matrix.MeanIou());
  json->Key("present_classes");
  json->Integer(matrix.PresentClasses());
  json->Key("iou");
  json->BeginObject();
  for (int c = 1; c <= 3; ++c) {
    const auto cls = static_cast<TravClass>(c);
    json->Key(ClassName(cls));
    json->Number(matrix.Iou(cls));
  }
  json->EndObject();
  json->Key("recall");
  json->BeginObject();
  for (int c = 1; c <= 3; ++c) {
    const auto cls = static_cast<TravClass>(c);
    json->Key(ClassName(cls));
    json->Number(matrix.Recall(cls));
  }
  json->EndObject();
  const int non = static_cast<int>(TravClass::kNonTraversable);
  json->Key("unsafe");
  json->BeginObject();
  json->Key("count");
  json->Integer(matrix.Unsafe());
  json->Key("truly_blocked");
  json->Integer(matrix.TruthTotal(non));
  json->Key("rate");
  json->Number(matrix.UnsafeRate());
  json->EndObject();
  json->Key("falsely_blocked");
  json->BeginObject();
  json->Key("count");
  json->Integer(matrix.FalselyBlocked());
  json->Key("truly_free");
  json->Integer(matrix.TruthTotal(non - 1) + matrix.TruthTotal(non - 2));
  json->Key("rate");
  json->Number(matrix.FalselyBlockedRate());
  json->EndObject();
  json->Key("confusion");
  json->BeginArray();
  for (int t = 0; t < ConfusionMatrix::kSize; ++t) {
    json->BeginInlineArray();
    for (int p = 0; p < ConfusionMatrix::kSize; ++p) json->Integer(matrix.Count(t, p));
    json->EndArray();
  }
  json->EndArray();
  json->EndObject();
}

}  // namespace ssta::internal
