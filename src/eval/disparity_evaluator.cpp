#include "ssta/eval/disparity_evaluator.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <vector>

#include "ssta/core/json_writer.h"
#include "ssta/core/error.h"
#include "eval/png_folder.h"
#include "ssta/io/image_io.h"

namespace ssta {
namespace fs = std::filesystem;
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string SizeText(const ImageF& image) {
  return std::to_string(image.width()) + "x" + std::to_string(image.height());
}

double Share(std::int64_t part, std::int64_t whole) {
  return whole > 0 ? static_cast<double>(part) / static_cast<double>(whole) : kNaN;
}

std::string Percent(double share) {
  if (std::isnan(share)) return "n/a";
  char text[32];
  std::snprintf(text, sizeof text, "%.2f %%", 100.0 * share);
  return text;
}

void Count(double error_px, std::vector<std::int64_t>* histogram) {
  using S = DisparityEvalSummary;
  const double bin = std::floor((error_px + S::kNoiseHalfRangePx) / S::kNoiseBinPx);
  ++(*histogram)[static_cast<std::size_t>(std::clamp(bin, 0.0, S::kNoiseBins - 1.0))];
}

/// The value below which `share` of the histogram's counts lie, at the centre of its bin [px].
double BinCentreAtShare(const std::vector<std::int64_t>& histogram, std::int64_t total, double share,
                        double bin_px, double origin_px) {
  const double wanted = share * static_cast<double>(total);
  std::int64_t below = 0;
  for (std::size_t i = 0; i < histogram.size(); ++i) {
    below += histogram[i];
    if (static_cast<double>(below) >= wanted) return origin_px + (static_cast<double>(i) + 0.5) * bin_px;
  }
  return origin_px + (static_cast<double>(histogram.size()) - 0.5) * bin_px;
}

/// The number of values a histogram holds.
std::int64_t Total(const std::vector<std::int64_t>& histogram) {
  std::int64_t total = 0;
  for (const std::int64_t n : histogram) total += n;
  return total;
}

/// The median of the values a histogram of Count holds, at the centre of its bin [px]; NaN when
/// `total`, the number of values it holds, is 0.
double Median(const std::vector<std::int64_t>& histogram, std::int64_t total) {
  if (total == 0) return kNaN;
  return BinCentreAtShare(histogram, total, 0.5, DisparityEvalSummary::kNoiseBinPx,
                          -DisparityEvalSummary::kNoiseHalfRangePx);
}

/// 1.4826 x the median absolute deviation of the values a histogram of Count holds.
double RobustSigma(const std::vector<std::int64_t>& histogram) {
  const std::int64_t total = Total(histogram);
  if (total == 0) return kNaN;
  constexpr double bin = DisparityEvalSummary::kNoiseBinPx, half = DisparityEvalSummary::kNoiseHalfRangePx;
  const double median = Median(histogram, total);
  // The absolute deviations of the bin centres from the median, binned alike from 0.
  std::vector<std::int64_t> deviations(histogram.size(), 0);
  for (std::size_t i = 0; i < histogram.size(); ++i) {
    const double deviation = std::abs(-half + (static_cast<double>(i) + 0.5) * bin - median);
    deviations[std::min(histogram.size() - 1, static_cast<std::size_t>(std::lround(deviation / bin)))] += histogram[i];
  }
  // Deviations are whole bins apart from the median's centre: bin k holds k bin widths.
  const double mad = BinCentreAtShare(deviations, total, 0.5, bin, 0.0) - 0.5 * bin;
  return 1.4826 * mad;
}

/// The largest and the smallest truth disparity within `radius` of each pixel (a square
/// window), over pixels with a truth (> 0); 0 where the window holds none.
struct WindowExtremes {
  ImageF nearest, farthest;
};

/// WindowExtremes of `truth`, separably: along the rows, then along the columns.
WindowExtremes TruthWindowExtremes(const ImageF& truth, int radius) {
  constexpr float kNone = std::numeric_limits<float>::infinity();  // the smallest of none
  const int w = truth.width(), h = truth.height();
  ImageF row_max(w, h, 0.0f), row_min(w, h, kNone);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      float largest = 0.0f, smallest = kNone;
      for (int x = std::max(0, u - radius); x <= std::min(w - 1, u + radius); ++x) {
        const float t = truth(v, x);
        if (!(t > 0.0f) || !std::isfinite(t)) continue;
        largest = std::max(largest, t);
        smallest = std::min(smallest, t);
      }
      row_max(v, u) = largest;
      row_min(v, u) = smallest;
    }
  }
  WindowExtremes out{ImageF(w, h, 0.0f), ImageF(w, h, 0.0f)};
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      float largest = 0.0f, smallest = kNone;
      for (int y = std::max(0, v - radius); y <= std::min(h - 1, v + radius); ++y) {
        largest = std::max(largest, row_max(y, u));
        smallest = std::min(smallest, row_min(y, u));
      }
      out.nearest(v, u) = largest;
      out.farthest(v, u) = std::isfinite(smallest) ? smallest : 0.0f;
    }
  }
  return out;
}

// The PNGs of a folder by file name (its disparity/ subfolder when it has one).
std::map<std::string, fs::path> DisparityPngs(const std::string& folder) {
  fs::path dir(folder);
  if (fs::is_directory(dir / "disparity")) dir /= "disparity";
  return internal::ListPngs(dir);
}

DisparityEvalSummary ScoreFiles(const std::string& predicted_path, const std::string& truth_path,
                                const DisparityEvalOptions& options) {
  const ImageF truth = ReadDisparityPng(truth_path);
  const ImageF estimate = ReadDisparityPng(predicted_path);
  if (truth.width() != estimate.width() || truth.height() != estimate.height()) {
    throw Error(predicted_path + ": size " + SizeText(estimate) + " differs from the truth " + truth_path + " (" +
                SizeText(truth) + ")");
  }
  return ScoreDisparity(truth, estimate, options);
}

}  // namespace

bool DisparityEvalOptions::IsValid(std::string* error) const {
  if (!(std::isfinite(max_error_px) && max_error_px >= 0)) {
    return Fail(error, "max_error_px: must be finite and >= 0");
  }
  if (!(std::isfinite(max_error_ratio) && max_error_ratio >= 0)) {
    return Fail(error, "max_error_ratio: must be finite and >= 0");
  }
  return true;
}

double DisparityEvalSummary::D1All() const {
  return Share(truth_pixels - matched_pixels + bad_matched_pixels, truth_pixels);
}

double DisparityEvalSummary::D1Matched() const { return Share(bad_matched_pixels, matched_pixels); }

double DisparityEvalSummary::EndPointErrorPx() const {
  return matched_pixels > 0 ? sum_abs_error_px / static_cast<double>(matched_pixels) : kNaN;
}

double DisparityEvalSummary::Density() const { return Share(matched_pixels, truth_pixels); }

double DisparityEvalSummary::FattenedShare() const { return Share(fattened_pixels, behind_edge_pixels); }

double DisparityEvalSummary::ErodedShare() const { return Share(eroded_pixels, front_edge_pixels); }

double DisparityEvalSummary::GoodErrorMedianPx() const {
  return Median(good_error_histogram, Total(good_error_histogram));
}

double DisparityEvalSummary::GoodErrorSigmaPx() const { return RobustSigma(good_error_histogram); }

double DisparityEvalSummary::NeighbourDifferenceSigmaPx() const {
  return RobustSigma(neighbour_difference_histogram);
}

double DisparityEvalSummary::NeighbourDifferenceRatio() const {
  const double sigma = GoodErrorSigmaPx();
  return sigma > 0.0 ? NeighbourDifferenceSigmaPx() / (std::sqrt(2.0) * sigma) : kNaN;
}

void DisparityEvalSummary::Add(const DisparityEvalSummary& other) {
  pairs += other.pairs;
  truth_pixels += other.truth_pixels;
  matched_pixels += other.matched_pixels;
  bad_matched_pixels += other.bad_matched_pixels;
  sum_abs_error_px += other.sum_abs_error_px;
  behind_edge_pixels += other.behind_edge_pixels;
  fattened_pixels += other.fattened_pixels;
  front_edge_pixels += other.front_edge_pixels;
  eroded_pixels += other.eroded_pixels;
  for (std::size_t i = 0; i < good_error_histogram.size(); ++i) {
    good_error_histogram[i] += other.good_error_histogram[i];
    neighbour_difference_histogram[i] += other.neighbour_difference_histogram[i];
  }
}

std::string DisparityEvalSummary::BriefReport() const {
  char rule_text[96];
  std::snprintf(rule_text, sizeof rule_text, "off by more than %g px and %g %%, or no disparity", rule.max_error_px,
                100.0 * rule.max_error_ratio);
  char epe[32];
  std::snprintf(epe, sizeof epe, "%.3f px", EndPointErrorPx());
  std::string out = "eval disparity: " + prediction + " against " + truth + "\n";
  out += "pairs: " + std::to_string(pairs) + ", truth pixels: " + std::to_string(truth_pixels) +
         ", matched: " + std::to_string(matched_pixels) + "\n";
  out += "D1 (bad: " + std::string(rule_text) + "): " + Percent(D1All()) + " of truth pixels, " +
         Percent(D1Matched()) + " of matched pixels\n";
  out += "end-point error (matched): " + std::string(std::isnan(EndPointErrorPx()) ? "n/a" : epe) +
         ", density: " + Percent(Density()) + "\n";
  char noise[192];
  std::snprintf(noise, sizeof noise,
                "noise of the good matches: median error %+.3f px, sigma %.3f px; difference of vertical "
                "neighbours %.3f px (%.2f of independent errors')\n",
                GoodErrorMedianPx(), GoodErrorSigmaPx(), NeighbourDifferenceSigmaPx(), NeighbourDifferenceRatio());
  out += noise;
  out += "depth edges (truth pixels within " + std::to_string(kEdgeRadiusPx) +
         " px of one nearer or farther by a bad error): behind one " + std::to_string(behind_edge_pixels) + ", " +
         Percent(FattenedShare()) + " fattened (given a nearer disparity, bad); in front of one " +
         std::to_string(front_edge_pixels) + ", " + Percent(ErodedShare()) + " eroded (given a farther one, bad)\n";
  return out;
}

std::string DisparityEvalSummary::ToJson() const {
  internal::JsonWriter json;
  json.BeginObject();
  json.Key("kind");
  json.String("disparity");
  json.Key("prediction");
  json.String(prediction);
  json.Key("truth");
  json.String(truth);
  internal::WriteDisparityScoreFields(*this, &json);
  json.EndObject();
  return json.Take();
}

DisparityEvalSummary ScoreDisparity(const ImageF& truth, const ImageF& estimate, const DisparityEvalOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw Error(why);
  if (truth.width() != estimate.width() || truth.height() != estimate.height()) {
    throw Error("the estimate is " + SizeText(estimate) + " but the truth is " + SizeText(truth));
  }
  DisparityEvalSummary s;
  s.rule = options;
  s.pairs = 1;
  // The signed error of each good match, NaN elsewhere, for the neighbour differences.
  ImageF good_error(truth.width(), truth.height(), std::numeric_limits<float>::quiet_NaN());
  const WindowExtremes window = TruthWindowExtremes(truth, DisparityEvalSummary::kEdgeRadiusPx);
  // Whether a disparity difference of `d` (> 0) at truth `t` is a bad error under the rule.
  const auto bad = [&options](double d, double t) {
    return d > options.max_error_px && d > options.max_error_ratio * t;
  };
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const double t = truth[i];
    if (!(t > 0.0) || !std::isfinite(t)) continue;
    ++s.truth_pixels;
    const bool behind = bad(window.nearest[i] - t, t), in_front = bad(t - window.farthest[i], t);
    s.behind_edge_pixels += behind;
    s.front_edge_pixels += in_front;
    const double e = estimate[i];
    if (!(e > 0.0) || !std::isfinite(e)) continue;
    ++s.matched_pixels;
    s.fattened_pixels += behind && bad(e - t, t);
    s.eroded_pixels += in_front && bad(t - e, t);
    const double error = std::abs(e - t);
    s.sum_abs_error_px += error;
    if (bad(error, t)) {
      ++s.bad_matched_pixels;
      continue;
    }
    Count(e - t, &s.good_error_histogram);
    good_error[i] = static_cast<float>(e - t);
  }
  for (int v = 0; v + 1 < good_error.height(); ++v) {
    for (int u = 0; u < good_error.width(); ++u) {
      const double difference = static_cast<double>(good_error(v, u)) - good_error(v + 1, u);
      if (!std::isnan(difference)) Count(difference, &s.neighbour_difference_histogram);
    }
  }
  return s;
}

ImageF ReadDisparityPng(const std::string& path) {
  if (!fs::is_regular_file(path)) throw Error(path + ": disparity file not found");
  const ImageU16 fixed = ReadImageU16(path);
  ImageF disparity(fixed.width(), fixed.height(), 0.0f);
  for (std::size_t i = 0; i < fixed.size(); ++i) disparity[i] = static_cast<float>(fixed[i]) / 256.0f;
  return disparity;
}

DisparityEvalSummary EvaluateDisparityFiles(const std::string& prediction, const std::string& truth,
                                            const DisparityEvalOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw Error(why);
  const bool truth_is_folder = fs::is_directory(truth), prediction_is_folder = fs::is_directory(prediction);
  if (!truth_is_folder && !fs::is_regular_file(truth)) throw Error(truth + ": truth not found");
  if (!prediction_is_folder && !fs::is_regular_file(prediction)) throw Error(prediction + ": prediction not found");
  if (truth_is_folder != prediction_is_folder) {
    throw Error(prediction + ": give two files or two folders (the truth " + truth + " is a " +
                (truth_is_folder ? "folder" : "file") + ")");
  }
  DisparityEvalSummary total;
  total.rule = options;
  total.prediction = prediction;
  total.truth = truth;
  if (!truth_is_folder) {
    total.Add(ScoreFiles(prediction, truth, options));
    return total;
  }
  const auto truth_files = DisparityPngs(truth);
  if (truth_files.empty()) throw Error(truth + ": no PNG files in the truth folder");
  const auto predicted_files = DisparityPngs(prediction);
  for (const auto& [name, truth_file] : truth_files) {
    const auto found = predicted_files.find(name);
    if (found == predicted_files.end()) {
      fs::path dir(prediction);
      if (fs::is_directory(dir / "disparity")) dir /= "disparity";
      throw Error((dir / name).string() + ": no estimate for the truth " + truth_file.string());
    }
    total.Add(ScoreFiles(found->second.string(), truth_file.string(), options));
  }
  return total;
}

namespace internal {

void WriteDisparityScoreFields(const DisparityEvalSummary& summary, JsonWriter* json) {
  json->Key("pairs");
  json->Integer(summary.pairs);
  json->Key("truth_pixels");
  json->Integer(summary.truth_pixels);
  json->Key("matched_pixels");
  json->Integer(summary.matched_pixels);
  json->Key("bad_matched_pixels");
  json->Integer(summary.bad_matched_pixels);
  json->Key("max_error_px");
  json->Number(summary.rule.max_error_px);
  json->Key("max_error_ratio");
  json->Number(summary.rule.max_error_ratio);
  json->Key("d1_all");
  json->Number(summary.D1All());
  json->Key("d1_matched");
  json->Number(summary.D1Matched());
  json->Key("epe_px");
  json->Number(summary.EndPointErrorPx());
  json->Key("density");
  json->Number(summary.Density());
  json->Key("good_error_median_px");
  json->Number(summary.GoodErrorMedianPx());
  json->Key("good_error_sigma_px");
  json->Number(summary.GoodErrorSigmaPx());
  json->Key("neighbour_difference_sigma_px");
  json->Number(summary.NeighbourDifferenceSigmaPx());
  json->Key("neighbour_difference_ratio");
  json->Number(summary.NeighbourDifferenceRatio());
  json->Key("edge_radius_px");
  json->Integer(DisparityEvalSummary::kEdgeRadiusPx);
  json->Key("behind_edge_pixels");
  json->Integer(summary.behind_edge_pixels);
  json->Key("fattened_pixels");
  json->Integer(summary.fattened_pixels);
  json->Key("fattened_share");
  json->Number(summary.FattenedShare());
  json->Key("front_edge_pixels");
  json->Integer(summary.front_edge_pixels);
  json->Key("eroded_pixels");
  json->Integer(summary.eroded_pixels);
  json->Key("eroded_share");
  json->Number(summary.ErodedShare());
}

}  // namespace internal

}  // namespace ssta
