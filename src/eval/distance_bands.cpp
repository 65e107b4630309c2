#include "eval/distance_bands.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <utility>

#include "eval/metrics_json.h"
#include "io/text_parsers.h"
#include "ssta/core/error.h"
#include "ssta/eval/class_grid.h"
#include "ssta/files/file_util.h"

namespace ssta::internal {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string Ratio(double value) {
  if (!std::isfinite(value)) return "     -";
  char text[32];
  std::snprintf(text, sizeof text, "%6.3f", value);
  return text;
}

}  // namespace

std::vector<Eigen::Vector2d> ReadPath(const std::string& pose_csv) {
  constexpr double kPathSpacingM = 0.25;
  std::vector<Eigen::Vector2d> path;
  const std::vector<PoseSample> poses = ParseAslPoseCsv(ReadTextFile(pose_csv), pose_csv);
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const Eigen::Vector2d p = poses[i].world_p_body.head<2>();
    if (path.empty() || (p - path.back()).norm() >= kPathSpacingM || i + 1 == poses.size()) path.push_back(p);
  }
  return path;
}

std::string FindPoseFile(const std::string& gt_dir) {
  const std::filesystem::path pose_csv =
      std::filesystem::path(gt_dir).lexically_normal().parent_path() / "pose0" / "data.csv";
  return std::filesystem::exists(pose_csv) ? pose_csv.string() : std::string();
}

double DistanceToPath(const Eigen::Vector2d& p, const std::vector<Eigen::Vector2d>& path) {
  if (path.size() == 1) return (p - path.front()).norm();
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 1; i < path.size(); ++i) {
    const Eigen::Vector2d a = path[i - 1], ab = path[i] - a;
    const double length_sq = ab.squaredNorm();
    const double t = length_sq > 0.0 ? std::clamp((p - a).dot(ab) / length_sq, 0.0, 1.0) : 0.0;
    best = std::min(best, (p - (a + t * ab)).norm());
  }
  return best;
}

BandAccumulator::BandAccumulator(std::vector<Eigen::Vector2d> path, double band_m)
    : path_(std::move(path)), band_m_(band_m) {
  if (!(band_m_ > 0.0) || !std::isfinite(band_m_)) throw Error("distance bands: band_m must be positive");
  if (path_.empty()) throw Error("distance bands: the path has no points");
  for (const Eigen::Vector2d& p : path_) {
    if (!p.allFinite()) throw Error("distance bands: the path has a point that is not finite");
  }
}

BandAccumulator::BandAccumulator(double band_m) : band_m_(band_m) {
  if (!(band_m_ > 0.0) || !std::isfinite(band_m_)) throw Error("distance bands: band_m must be positive");
}

void BandAccumulator::Add(const Eigen::Vector2d& at, std::uint8_t truth, std::uint8_t predicted) {
  if (path_.empty()) throw Error("distance bands: no path to measure the distance from");
  const double distance = DistanceToPath(at, path_);
  if (distance / band_m_ >= kMaxBands) {
    char message[200];
    std::snprintf(message, sizeof message,
                  "a scored sample lies %.0f m from the path (over %d bands of %g m): is the path this grid's?",
                  distance, kMaxBands, band_m_);
    throw Error(std::string("distance bands: ") + message);
  }
  AddAtDistance(distance, truth, predicted);
}

void BandAccumulator::AddAtDistance(double distance, std::uint8_t truth, std::uint8_t predicted,
                                    std::int64_t count) {
  if (!(distance >= 0.0) || distance / band_m_ >= kMaxBands) {
    char message[160];
    std::snprintf(message, sizeof message, "a sample at %g m is outside [0, %d bands of %g m)", distance, kMaxBands,
                  band_m_);
    throw Error(std::string("distance bands: ") + message);
  }
  const auto band = static_cast<std::size_t>(std::floor(distance / band_m_));
  while (bands_.size() <= band) {
    DistanceBand b;
    b.from_m = static_cast<double>(bands_.size()) * band_m_;
    b.to_m = b.from_m + band_m_;
    bands_.push_back(b);
  }
  bands_[band].matrix.Add(truth, predicted, count);
}

std::vector<DistanceBand> BandAccumulator::Finish() const {
  std::vector<DistanceBand> bands = bands_;
  ConfusionMatrix within;
  for (DistanceBand& b : bands) {
    within += b.matrix;
    b.matrix_within = within;
    b.accuracy_within = within.Scored() > 0 ? within.Accuracy() : kNaN;
  }
  return bands;
}

std::string BandsReport(const std::vector<DistanceBand>& bands, const std::string& path_source) {
  return BandsTable(bands, "by distance from the path (" + path_source + ")");
}

std::string BandsTable(const std::vector<DistanceBand>& bands, const std::string& heading) {
  if (bands.empty()) return "";
  std::string out =
      heading + ":\n"
      "distance [m]   scored accuracy coverage  recall: trav   semi    non   unsafe  f.blocked  accuracy within\n";
  for (const DistanceBand& b : bands) {
    const ConfusionMatrix& m = b.matrix;
    const bool any = m.Scored() > 0;
    char line[300];
    std::snprintf(line, sizeof line, "%5.0f - %-5.0f %8lld   %s   %s        %s %s %s   %s     %s           %s\n",
                  b.from_m, b.to_m, static_cast<long long>(m.Scored()), Ratio(any ? m.Accuracy() : kNaN).c_str(),
                  Ratio(any ? m.Coverage() : kNaN).c_str(), Ratio(m.Recall(TravClass::kTraversable)).c_str(),
                  Ratio(m.Recall(TravClass::kSemiTraversable)).c_str(),
                  Ratio(m.Recall(TravClass::kNonTraversable)).c_str(), Ratio(m.UnsafeRate()).c_str(),
                  Ratio(m.FalselyBlockedRate()).c_str(), Ratio(b.accuracy_within).c_str());
    out += line;
  }
  return out;
}

void WriteBandsJson(const std::vector<DistanceBand>& bands, const std::string& path_source, double band_m,
                    JsonWriter* json) {
  json->BeginObject();
  json->Key("path");
  json->String(path_source);
  json->Key("band_m");
  json->Number(band_m);
  json->Key("bands");
  json->BeginArray();
  for (const DistanceBand& b : bands) {
    const bool any = b.matrix.Scored() > 0;
    json->BeginObject();
    json->Key("from_m");
    json->Number(b.from_m);
    json->Key("to_m");
    json->Number(b.to_m);
    json->Key("scored");
    json->Integer(b.matrix.Scored());
    json->Key("accuracy");
    json->Number(any ? b.matrix.Accuracy() : kNaN);
    json->Key("coverage");
    json->Number(any ? b.matrix.Coverage() : kNaN);
    json->Key("mean_iou");
    json->Number(any ? b.matrix.MeanIou() : kNaN);
    json->Key("accuracy_within");
    json->Number(b.accuracy_within);  // NaN: null
    json->Key("metrics");
    WriteMetricsJson(b.matrix, json);
    json->Key("metrics_within");
    WriteMetricsJson(b.matrix_within, json);
    json->EndObject();
  }
  json->EndArray();
  json->EndObject();
}

}  // namespace ssta::internal

namespace ssta {

DrivenPath ReadDrivenPath(const std::string& sequence) {
  DrivenPath path;
  path.source = internal::FindPoseFile(FindGroundTruthDir(sequence));
  if (!path.source.empty()) path.points = internal::ReadPath(path.source);
  return path;
}

}  // namespace ssta
