#include "ssta/bench/stereo_bench.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>

#include "ssta/core/json_writer.h"
#include "ssta/bench/pipeline_bench.h"
#include "ssta/core/error.h"
#include "ssta/io/image_io.h"

namespace ssta {
namespace fs = std::filesystem;
namespace {

fs::path RequireFolder(const fs::path& dir) {
  if (!fs::is_directory(dir)) throw Error(dir.string() + ": folder not found (expected left/, right/ and gt/)");
  return dir;
}

fs::path RequireFile(const fs::path& file) {
  if (!fs::is_regular_file(file)) throw Error(file.string() + ": file not found");
  return file;
}

// The truth PNGs of `gt`, sorted by name.
std::vector<fs::path> TruthFiles(const fs::path& gt) {
  std::vector<fs::path> files;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(gt, ec)) {
    if (!entry.is_regular_file()) continue;
    std::string ext = entry.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (ext == ".png") files.push_back(entry.path());
  }
  if (ec) throw Error(gt.string() + ": cannot list folder: " + ec.message());
  if (files.empty()) throw Error(gt.string() + ": no PNG files in the truth folder");
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace

bool StereoBenchOptions::IsValid(std::string* error) const {
  if (max_pairs < 0) return Fail(error, "max_pairs: must be >= 0");
  if (warmup_pairs < 0) return Fail(error, "warmup_pairs: must be >= 0");
  return rule.IsValid(error);
}

double StereoBenchReport::MedianMatchMs() const { return Quantile(match_ms, 0.5); }

double StereoBenchReport::MedianMatchCpuMs() const { return Quantile(match_cpu_ms, 0.5); }

std::string StereoBenchReport::BriefReport() const {
  char line[200];
  std::snprintf(line, sizeof line, "matching (%s, %dx%d): median %.1f ms per pair (CPU %.1f ms) over %zu pairs\n",
                matcher.c_str(), width, height, MedianMatchMs(), MedianMatchCpuMs(), match_ms.size());
  return score.BriefReport() + line;
}

std::string StereoBenchReport::ToJson() const {
  internal::JsonWriter json;
  json.BeginObject();
  json.Key("kind");
  json.String("stereo_bench");
  json.Key("data");
  json.String(data);
  json.Key("matcher");
  json.String(matcher);
  json.Key("width");
  json.Integer(width);
  json.Key("height");
  json.Integer(height);
  internal::WriteDisparityScoreFields(score, &json);
  json.Key("median_match_ms");
  json.Number(MedianMatchMs());
  json.Key("median_match_cpu_ms");
  json.Number(MedianMatchCpuMs());
  json.Key("match_ms");
  json.BeginInlineArray();
  for (const double ms : match_ms) json.Number(ms);
  json.EndArray();
  json.Key("match_cpu_ms");
  json.BeginInlineArray();
  for (const double ms : match_cpu_ms) json.Number(ms);
  json.EndArray();
  json.EndObject();
  return json.Take();
}

StereoBenchReport RunStereoBench(const std::string& data_dir, const StereoMatcherOptions& matcher_options,
                                 const StereoBenchOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw Error(why);
  const StereoMatcher matcher(matcher_options);
  const fs::path root = RequireFolder(data_dir);
  const fs::path left_dir = RequireFolder(root / "left"), right_dir = RequireFolder(root / "right");
  std::vector<fs::path> truths = TruthFiles(RequireFolder(root / "gt"));
  if (options.max_pairs > 0 && static_cast<int>(truths.size()) > options.max_pairs) truths.resize(options.max_pairs);

  StereoBenchReport report;
  report.data = data_dir;
  report.matcher = MatcherTypeName(matcher_options.algorithm) + (matcher_options.downscale == 2 ? " at half size" : "");
  report.score.rule = options.rule;
  report.score.prediction = report.matcher;
  report.score.truth = (root / "gt").string();
  for (std::size_t k = 0; k < truths.size(); ++k) {
    const std::string name = truths[k].filename().string();
    const ImageU8 left = ReadGreyImage(RequireFile(left_dir / name).string());
    const ImageU8 right = ReadGreyImage(RequireFile(right_dir / name).string());
    const ImageF truth = ReadDisparityPng(truths[k].string());
    if (truth.width() != left.width() || truth.height() != left.height()) {
      throw Error(truths[k].string() + ": size " + std::to_string(truth.width()) + "x" + std::to_string(truth.height()) +
                  " differs from the left image's (" + std::to_string(left.width()) + "x" +
                  std::to_string(left.height()) + ")");
    }
    if (k == 0) {
      report.width = left.width();
      report.height = left.height();
      for (int i = 0; i < options.warmup_pairs; ++i) matcher.Compute(left, right);
    }
    const auto start = std::chrono::steady_clock::now();
    const std::clock_t cpu_start = std::clock();
    const ImageF disparity = matcher.Compute(left, right);
    report.match_cpu_ms.push_back(1000.0 * static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC);
    report.match_ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    report.score.Add(ScoreDisparity(truth, disparity, options.rule));
  }
  return report;
}

}  // namespace ssta
