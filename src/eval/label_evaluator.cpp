#include "ssta/eval/label_evaluator.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <vector>

#include "eval/class_ids.h"
#include "ssta/core/json_writer.h"
#include "eval/metrics_json.h"
#include "ssta/core/classes.h"
#include "ssta/core/error.h"
#include "eval/png_folder.h"
#include "eval/distance_bands.h"
#include "ssta/eval/class_grid.h"
#include "ssta/eval/disparity_evaluator.h"
#include "ssta/files/yaml_reader.h"
#include "ssta/files/file_util.h"
#include "ssta/io/image_io.h"

namespace ssta {
namespace fs = std::filesystem;
namespace {

std::string SizeText(const ImageU8& image) {
  return std::to_string(image.width()) + "x" + std::to_string(image.height());
}

void CheckSameSize(const ImageU8& truth, const ImageU8& predicted, const std::string& truth_name,
                   const std::string& predicted_name) {
  if (truth.width() != predicted.width() || truth.height() != predicted.height()) {
    throw Error(predicted_name + ": size " + SizeText(predicted) + " differs from the truth " +
                truth_name + " (" + SizeText(truth) + ")");
  }
}

fs::path PredictionFolder(const std::string& prediction) {
  if (!fs::is_directory(prediction)) throw Error(prediction + ": prediction folder not found");
  const fs::path labels = fs::path(prediction) / "labels";
  return fs::is_directory(labels) ? labels : fs::path(prediction);
}

/// f b [px m] of the rig a synthetic sequence was rendered with (gt/rig.yaml), 0 when the truth
/// has no rig file. Throws ssta::Error naming the file and key when it is there but unusable.
double RenderedFocalTimesBaseline(const fs::path& gt_dir) {
  const fs::path path = gt_dir / "rig.yaml";
  if (!fs::is_regular_file(path)) return 0.0;
  internal::YamlSection rig(internal::ParseYaml(ReadTextFile(path.string()), path.string()), path.string(), "");
  const auto focal = rig.Require<double>("focal_px");
  const auto baseline = rig.Require<double>("baseline_m");
  if (!(std::isfinite(focal) && focal > 0.0)) throw Error(rig.Name("focal_px") + ": must be positive");
  if (!(std::isfinite(baseline) && baseline > 0.0)) throw Error(rig.Name("baseline_m") + ": must be positive");
  return focal * baseline;
}

/// Adds each scored pixel to the band of its depth f b / d (d the true disparity, > 0). Counts
/// into a histogram per band first, as ScoreLabels does: one increment per pixel.
void AddByDepth(const ImageU8& truth, const ImageU8& predicted, const ImageF& disparity, double focal_times_baseline,
                internal::BandAccumulator* bands, const std::string& disparity_name) {
  if (disparity.width() != truth.width() || disparity.height() != truth.height()) {
    throw Error(disparity_name + ": size " + std::to_string(disparity.width()) + "x" +
                std::to_string(disparity.height()) + " differs from the truth labels (" + SizeText(truth) + ")");
  }
  // Per band, counts by truth 1..3 and prediction 0..4.
  constexpr int kCells = 3 * kNumClasses;
  std::vector<std::array<std::int64_t, kCells>> histogram;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const std::uint8_t t = truth[i];
    if (t < 1 || t > 3 || !(disparity[i] > 0.0f)) continue;
    const double depth = focal_times_baseline / disparity[i];
    const double band = std::floor(depth / bands->band_m());
    if (band >= internal::BandAccumulator::kMaxBands) {
      bands->AddAtDistance(depth, t, predicted[i]);  // beyond the bands: the accumulator says so
      continue;
    }
    const auto b = static_cast<std::size_t>(band);
    if (histogram.size() <= b) histogram.resize(b + 1, std::array<std::int64_t, kCells>{});
    ++histogram[b][(t - 1) * kNumClasses + predicted[i]];
  }
  for (std::size_t b = 0; b < histogram.size(); ++b) {
    const double centre = (static_cast<double>(b) + 0.5) * bands->band_m();
    for (int cell = 0; cell < kCells; ++cell) {
      if (histogram[b][cell] == 0) continue;
      bands->AddAtDistance(centre, static_cast<std::uint8_t>(cell / kNumClasses + 1),
                           static_cast<std::uint8_t>(cell % kNumClasses), histogram[b][cell]);
    }
  }
}

const char* PolicyName(MissingPrediction policy) {
  return policy == MissingPrediction::kSkip ? "skip" : "score_as_unknown";
}

}  // namespace

ConfusionMatrix ScoreLabels(const ImageU8& truth, const ImageU8& predicted,
                            const std::string& truth_name, const std::string& predicted_name) {
  CheckSameSize(truth, predicted, truth_name, predicted_name);
  internal::CheckTruthIds(truth, truth_name);
  internal::CheckPredictedIds(predicted, predicted_name);
  // Count into a flat histogram first: one increment per pixel instead of a checked Add.
  std::array<std::int64_t, 256 * kNumClasses> histogram{};
  for (std::size_t i = 0; i < truth.size(); ++i) ++histogram[truth[i] * kNumClasses + predicted[i]];
  ConfusionMatrix matrix;
  for (int t = 0; t < 256; ++t) {
    for (int p = 0; p < kNumClasses; ++p) {
      const std::int64_t n = histogram[t * kNumClasses + p];
      if (n > 0) matrix.Add(static_cast<std::uint8_t>(t), static_cast<std::uint8_t>(p), n);
    }
  }
  return matrix;
}

bool LabelEvalOptions::IsValid(std::string* error) const {
  if (!pictures_dir.empty() && fs::exists(pictures_dir) && !fs::is_directory(pictures_dir)) {
    return Fail(error, "pictures_dir: " + pictures_dir + " exists and is not a folder");
  }
  if (worst_frames_listed < 0) return Fail(error, "worst_frames_listed: must be >= 0");
  if (!(std::isfinite(depth_band_m) && depth_band_m >= 0.0)) return Fail(error, "depth_band_m: must be >= 0");
  return true;
}

LabelEvalSummary EvaluateLabelFolders(const std::string& prediction, const std::string& sequence,
                                      const LabelEvalOptions& options) {
  std::string error;
  if (!options.IsValid(&error)) throw Error("eval labels options: " + error);

  LabelEvalSummary summary;
  summary.missing_prediction_policy = options.missing_prediction;
  summary.worst_frames_listed = options.worst_frames_listed;
  const fs::path pred_dir = PredictionFolder(prediction);
  const fs::path gt_dir = FindGroundTruthDir(sequence);
  const fs::path truth_dir = gt_dir / "labels";
  if (!fs::is_directory(truth_dir)) throw Error(truth_dir.string() + ": truth label folder not found");
  summary.prediction_dir = pred_dir.string();
  summary.truth_dir = truth_dir.string();

  const auto predicted_files = internal::ListPngs(pred_dir);
  const auto truth_files = internal::ListPngs(truth_dir);
  if (truth_files.empty()) throw Error(truth_dir.string() + ": no truth label PNGs in the folder");
  if (predicted_files.empty()) {
    throw Error(prediction + ": no label PNGs (looked in " + pred_dir.string() +
                "; expected DIR/labels/<ts>.png or DIR/<ts>.png)");
  }
  for (const auto& [name, path] : predicted_files) {
    if (truth_files.count(name) == 0) summary.missing_truth.push_back(name);
  }
  if (!options.pictures_dir.empty()) MakeDirectories(options.pictures_dir);
  // Depth bands, when the truth has the disparity and the rig to turn it into depth.
  const fs::path disparity_dir = gt_dir / "disparity";
  const double focal_times_baseline =
      options.depth_band_m > 0.0 && fs::is_directory(disparity_dir) ? RenderedFocalTimesBaseline(gt_dir) : 0.0;
  std::unique_ptr<internal::BandAccumulator> depth_bands;
  if (focal_times_baseline > 0.0) {
    depth_bands = std::make_unique<internal::BandAccumulator>(options.depth_band_m);
    summary.depth_band_m = options.depth_band_m;
    char source[160];
    std::snprintf(source, sizeof source, "true disparity, f b = %.4g px m", focal_times_baseline);
    summary.depth_source = source;
  }

  // Adds a frame's scored pixels to the depth bands, when the truth has its disparity.
  const auto add_by_depth = [&](const std::string& name, const ImageU8& truth, const ImageU8& predicted) {
    const fs::path disparity_path = disparity_dir / name;
    if (!depth_bands || !fs::is_regular_file(disparity_path)) return;
    AddByDepth(truth, predicted, ReadDisparityPng(disparity_path.string()), focal_times_baseline, depth_bands.get(),
               disparity_path.string());
  };

  for (const auto& [name, truth_path] : truth_files) {
    FrameScore frame;
    frame.name = name;
    const ImageU8 truth = ReadLabelImage(truth_path.string());
    const auto found = predicted_files.find(name);
    if (found == predicted_files.end()) {
      frame.prediction_missing = true;
      summary.missing_prediction.push_back(name);
      if (options.missing_prediction == MissingPrediction::kScoreAsUnknown) {
        const ImageU8 unknown(truth.width(), truth.height(), 0);
        frame.matrix = ScoreLabels(truth, unknown, truth_path.string(), "(no prediction)");
        add_by_depth(name, truth, unknown);
      }
    } else {
      const ImageU8 predicted = ReadLabelImage(found->second.string());
      frame.matrix = ScoreLabels(truth, predicted, truth_path.string(), found->second.string());
      add_by_depth(name, truth, predicted);
      if (!options.pictures_dir.empty()) {
        WriteImage(MakeComparisonPicture(truth, predicted),
                   (fs::path(options.pictures_dir) / name).string());
      }
    }
    summary.total += frame.matrix;
    summary.frames.push_back(std::move(frame));
    if (options.progress) {
      options.progress(static_cast<int>(summary.frames.size()), static_cast<int>(truth_files.size()));
    }
  }
  if (depth_bands) summary.by_depth = depth_bands->Finish();
  return summary;
}

std::string LabelEvalSummary::BriefReport() const {
  const std::size_t with_prediction = frames.size() - missing_prediction.size();
  std::string out = "eval labels: " + prediction_dir + " against " + truth_dir + "\n";
  out += "frames: " + std::to_string(frames.size()) + " in truth, " +
         std::to_string(with_prediction) + " with a prediction, " +
         std::to_string(missing_prediction.size()) + " without (" +
         (missing_prediction_policy == MissingPrediction::kSkip ? "skipped" : "scored as unknown") +
         "), " + std::to_string(missing_truth.size()) + " predictions without truth (unscored)\n";
  auto list = [&out](const char* title, const std::vector<std::string>& names) {
    if (names.empty()) return;
    out += title;
    const std::size_t shown = std::min<std::size_t>(names.size(), 10);
    for (std::size_t i = 0; i < shown; ++i) out += " " + names[i];
    if (shown < names.size()) out += " ... (" + std::to_string(names.size() - shown) + " more)";
    out += "\n";
  };
  list("missing prediction:", missing_prediction);
  list("missing truth:", missing_truth);
  // Worst frames first: the ones a person should look at.
  std::vector<const FrameScore*> ranked;
  for (const auto& frame : frames) {
    if (!frame.prediction_missing && frame.matrix.Scored() > 0) ranked.push_back(&frame);
  }
  std::stable_sort(ranked.begin(), ranked.end(), [](const FrameScore* a, const FrameScore* b) {
    return a->matrix.Accuracy() < b->matrix.Accuracy();
  });
  const std::size_t listed = std::min<std::size_t>(ranked.size(), static_cast<std::size_t>(std::max(0, worst_frames_listed)));
  if (listed > 0 && ranked.size() > 1) {
    out += "worst frames by accuracy:";
    char item[128];
    for (std::size_t i = 0; i < listed; ++i) {
      std::snprintf(item, sizeof item, " %s (%.3f)", ranked[i]->name.c_str(),
                    ranked[i]->matrix.Accuracy());
      out += item;
    }
    out += "\n";
  }
  out += total.BriefReport("pixels");
  out += internal::BandsTable(by_depth, "by depth from the camera (" + depth_source + ")");
  return out;
}

std::string LabelEvalSummary::ToJson() const {
  internal::JsonWriter json;
  internal::BeginSummaryJson("labels", "pixels", prediction_dir, truth_dir, &json);
  json.Key("frames_truth");
  json.Integer(static_cast<std::int64_t>(frames.size()));
  json.Key("frames_predicted");
  json.Integer(static_cast<std::int64_t>(frames.size() - missing_prediction.size() +
                                         missing_truth.size()));
  std::int64_t scored_frames = 0;
  for (const auto& frame : frames) {
    scored_frames += !frame.prediction_missing || missing_prediction_policy == MissingPrediction::kScoreAsUnknown;
  }
  json.Key("frames_scored");
  json.Integer(scored_frames);
  json.Key("missing_prediction_policy");
  json.String(PolicyName(missing_prediction_policy));
  json.Key("missing_prediction");
  json.BeginArray();
  for (const auto& name : missing_prediction) json.String(name);
  json.EndArray();
  json.Key("missing_truth");
  json.BeginArray();
  for (const auto& name : missing_truth) json.String(name);
  json.EndArray();
  json.Key("metrics");
  internal::WriteMetricsJson(total, &json);
  if (!by_depth.empty()) {
    json.Key("by_depth");
    internal::WriteBandsJson(by_depth, depth_source, depth_band_m, &json);
  }
  json.Key("frames");
  json.BeginArray();
  for (const auto& frame : frames) {
    json.BeginObject();
    json.Key("name");
    json.String(frame.name);
    json.Key("prediction_missing");
    json.Bool(frame.prediction_missing);
    json.Key("scored_in_total");
    json.Bool(!frame.prediction_missing ||
              missing_prediction_policy == MissingPrediction::kScoreAsUnknown);
    json.Key("metrics");
    internal::WriteMetricsJson(frame.matrix, &json);
    json.EndObject();
  }
  json.EndArray();
  json.EndObject();
  return json.Take();
}

}  // namespace ssta
