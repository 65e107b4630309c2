#include "ssta/io/sequence.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "ssta/core/error.h"
#include "ssta/files/file_util.h"
#include "ssta/io/image_io.h"
#include "text_parsers.h"
#include "ssta/files/yaml_reader.h"

namespace fs = std::filesystem;

namespace ssta {
namespace {

constexpr std::int64_t kPairToleranceNs = 1'000'000;  // 1 ms (docs/interfaces.md, section 2)
// Pose files print unit quaternions to a few digits at least; a norm further off is damage.
constexpr double kMaxQuaternionNormError = 0.01;

std::string Trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

std::vector<std::string> SplitCommas(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(Trim(item));
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

std::int64_t ParseTimestamp(const std::string& text, const std::string& where) {
  std::size_t used = 0;
  long long value = 0;
  try {
    value = std::stoll(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size()) throw Error(where + ": bad timestamp '" + text + "'");
  return value;
}

double ParseNumber(const std::string& text, const std::string& where) {
  std::size_t used = 0;
  double value = 0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size()) throw Error(where + ": bad number '" + text + "'");
  if (!std::isfinite(value)) throw Error(where + ": NaN or infinite value");
  return value;
}

/// Calls `row(t, cols, where, line)` for every data row of an ASL CSV given as text (comment
/// and blank lines skipped), after checking the column count and that the first column, a
/// timestamp, strictly increases.
template <typename Row>
void ForEachCsvRow(const std::string& text, const std::string& path, std::size_t columns, const std::string& expected,
                   Row row) {
  std::istringstream in(text);
  std::string line;
  int n = 0;
  std::int64_t previous = 0;
  bool first = true;
  while (std::getline(in, line)) {
    ++n;
    line = Trim(line);
    if (line.empty() || line[0] == '#') continue;
    const std::string where = path + ":" + std::to_string(n);
    const auto cols = SplitCommas(line);
    if (cols.size() != columns) {
      throw Error(where + ": expected " + expected + ", found " + std::to_string(cols.size()) + " columns");
    }
    const std::int64_t t = ParseTimestamp(cols[0], where);
    if (!first && t <= previous) {
      throw Error(where + ": timestamp " + cols[0] + (t == previous ? " is duplicated" : " is out of order"));
    }
    first = false;
    previous = t;
    row(t, cols, where, n);
  }
}

std::vector<internal::ImageListEntry> ReadImageList(const std::string& cam_dir) {
  const std::string csv = cam_dir + "/data.csv";
  auto out = internal::ParseAslImageList(ReadTextFile(csv), csv);
  for (auto& entry : out) entry.file = cam_dir + "/data/" + entry.file;
  return out;
}

}  // namespace

std::vector<std::ptrdiff_t> PairNearestWithin1Ms(const std::vector<std::int64_t>& left,
                                                 const std::vector<std::int64_t>& right) {
  std::vector<std::ptrdiff_t> out;
  out.reserve(left.size());
  std::size_t j = 0;
  for (const std::int64_t t : left) {
    while (j + 1 < right.size() && std::llabs(right[j + 1] - t) <= std::llabs(right[j] - t)) ++j;
    const bool paired = !right.empty() && std::llabs(right[j] - t) <= kPairToleranceNs;
    out.push_back(paired ? static_cast<std::ptrdiff_t>(j) : -1);
  }
  return out;
}

namespace internal {

std::vector<CsvRow> ParseAslNumericCsv(const std::string& text, const std::string& path, int columns) {
  std::vector<CsvRow> rows;
  const std::string expected = std::to_string(columns) + " columns";
  ForEachCsvRow(text, path, static_cast<std::size_t>(columns), expected,
                [&](std::int64_t t, const std::vector<std::string>& cols, const std::string& where, int line) {
                  CsvRow row;
                  row.line = line;
                  row.timestamp_ns = t;
                  for (std::size_t c = 1; c < cols.size(); ++c) row.values.push_back(ParseNumber(cols[c], where));
                  rows.push_back(std::move(row));
                });
  return rows;
}

std::vector<ImageListEntry> ParseAslImageList(const std::string& text, const std::string& path) {
  std::vector<ImageListEntry> out;
  ForEachCsvRow(text, path, 2, "'timestamp,filename'",
                [&](std::int64_t t, const std::vector<std::string>& cols, const std::string& where, int) {
                  if (cols[1].empty()) throw Error(where + ": empty file name");
                  out.push_back({t, cols[1]});
                });
  return out;
}

std::vector<ImuSample> ParseAslImuCsv(const std::string& text, const std::string& path) {
  std::vector<ImuSample> out;
  for (const auto& row : ParseAslNumericCsv(text, path, 7)) {
    ImuSample s;
    s.timestamp_ns = row.timestamp_ns;
    s.angular_rate = Eigen::Vector3d(row.values[0], row.values[1], row.values[2]);
    s.specific_force = Eigen::Vector3d(row.values[3], row.values[4], row.values[5]);
    out.push_back(s);
  }
  return out;
}

std::vector<PoseSample> ParseAslPoseCsv(const std::string& text, const std::string& path) {
  // The column count comes from the first data row (EuRoC's ground truth has 17, pose0 has 8).
  std::istringstream probe(text);
  std::string first;
  int first_line = 0;
  for (std::string line; std::getline(probe, line);) {
    ++first_line;
    line = Trim(line);
    if (line.empty() || line[0] == '#') continue;
    first = line;
    break;
  }
  const int columns = first.empty() ? 8 : static_cast<int>(SplitCommas(first).size());
  if (columns < 8) {
    throw Error(path + ":" + std::to_string(first_line) + ": expected at least 8 columns (t, p, q), found " +
                std::to_string(columns));
  }
  std::vector<PoseSample> out;
  for (const auto& row : ParseAslNumericCsv(text, path, columns)) {
    PoseSample p;
    p.timestamp_ns = row.timestamp_ns;
    p.world_p_body = Eigen::Vector3d(row.values[0], row.values[1], row.values[2]);
    Eigen::Quaterniond q(row.values[3], row.values[4], row.values[5], row.values[6]);
    const double norm = q.norm();
    if (!std::isfinite(norm)) throw Error(path + ":" + std::to_string(row.line) + ": quaternion too large to normalise");
    if (norm < 1e-6) throw Error(path + ":" + std::to_string(row.line) + ": zero quaternion");
    if (std::abs(norm - 1.0) > kMaxQuaternionNormError) {
      std::ostringstream m;
      m << path << ":" << row.line << ": quaternion norm " << norm << " is not 1 (a corrupt row?)";
      throw Error(m.str());
    }
    q.normalize();
    p.world_q_body = q;
    out.push_back(p);
  }
  return out;
}

}  // namespace internal

std::vector<CsvRow> ReadAslNumericCsv(const std::string& path, int columns) {
  return internal::ParseAslNumericCsv(ReadTextFile(path), path, columns);
}

Sequence::Sequence(SequenceData data) : data_(std::move(data)) {}

std::string DescribeSkipped(const std::vector<SkippedFrame>& skipped) {
  // By reason, in order of first appearance: a recording skips many frames for few reasons.
  std::vector<std::pair<std::string, std::vector<std::int64_t>>> by_reason;
  for (const SkippedFrame& f : skipped) {
    auto it = std::find_if(by_reason.begin(), by_reason.end(), [&](const auto& r) { return r.first == f.reason; });
    if (it == by_reason.end()) it = by_reason.insert(by_reason.end(), {f.reason, {}});
    it->second.push_back(f.timestamp_ns);
  }
  constexpr std::size_t kMaxLines = 10;
  std::ostringstream out;
  for (std::size_t i = 0; i < by_reason.size() && i < kMaxLines; ++i) {
    const auto& [reason, stamps] = by_reason[i];
    out << "  skipped " << stamps.size() << " (first at " << stamps.front() << " ns): " << reason << "\n";
  }
  if (by_reason.size() > kMaxLines) out << "  ... and " << by_reason.size() - kMaxLines << " more reasons\n";
  return out.str();
}

namespace {

/// The frames of a sequence and the ones skipped, with the reason, in time order.
struct AslFrames {
  std::vector<StereoFrame> frames;
  std::vector<SkippedFrame> skipped;
};

/// Pairs the cam0 and cam1 image lists exactly or to the nearest within 1 ms; a cam0 frame
/// without a partner or with a missing image, and a cam1 row no cam0 frame pairs with, are
/// skipped with the reason.
AslFrames PairAslFrames(const std::string& cam0, const std::string& cam1) {
  const auto left = ReadImageList(cam0);
  const auto right = ReadImageList(cam1);
  if (left.empty()) throw Error(cam0 + "/data.csv: lists no frames (an empty sequence)");
  const auto times = [](const std::vector<internal::ImageListEntry>& list) {
    std::vector<std::int64_t> out;
    for (const auto& entry : list) out.push_back(entry.timestamp_ns);
    return out;
  };
  const std::vector<std::ptrdiff_t> paired = PairNearestWithin1Ms(times(left), times(right));
  AslFrames out;
  std::vector<bool> right_used(right.size(), false);
  for (std::size_t i = 0; i < left.size(); ++i) {
    const auto& l = left[i];
    if (paired[i] < 0) {
      out.skipped.push_back({l.timestamp_ns, "no cam1 frame within 1 ms"});
      continue;
    }
    const auto j = static_cast<std::size_t>(paired[i]);
    right_used[j] = true;  // paired: a missing image skips the pair once, as one frame
    if (!fs::exists(l.file)) {
      out.skipped.push_back({l.timestamp_ns, "cam0 image missing: " + l.file});
      continue;
    }
    if (!fs::exists(right[j].file)) {
      out.skipped.push_back({l.timestamp_ns, "cam1 image missing: " + right[j].file});
      continue;
    }
    out.frames.push_back({l.timestamp_ns, l.file, right[j].file});
  }
  // cam1 rows that no cam0 frame pairs with are reported too (a cut recording, a dropped frame).
  for (std::size_t k = 0; k < right.size(); ++k) {
    if (right_used[k]) continue;
    out.skipped.push_back({right[k].timestamp_ns, fs::exists(right[k].file)
                                                      ? "cam1 frame without a cam0 frame within 1 ms"
                                                      : "cam1 frame without a cam0 frame, and its image is missing: " +
                                                            right[k].file});
  }
  std::sort(out.skipped.begin(), out.skipped.end(),
            [](const SkippedFrame& a, const SkippedFrame& b) { return a.timestamp_ns < b.timestamp_ns; });
  return out;
}

/// The IMU of an ASL sequence: its samples, the file they were read from, and its mount T_BS.
struct AslImu {
  std::vector<ImuSample> samples;
  std::string path;  ///< "" without imu0/data.csv
  Eigen::Isometry3d body_T_imu = Eigen::Isometry3d::Identity();
};

/// The IMU mount T_BS of imu0/sensor.yaml (`imu_yaml`); identity when the file or its T_BS
/// data is absent.
Eigen::Isometry3d ReadBodyTImu(const std::string& imu_yaml) {
  Eigen::Isometry3d body_T_imu = Eigen::Isometry3d::Identity();
  if (!fs::exists(imu_yaml)) return body_T_imu;
  const YAML::Node root = internal::ParseYaml(ReadTextFile(imu_yaml), imu_yaml);
  if (!root["T_BS"] || !root["T_BS"]["data"]) return body_T_imu;
  internal::YamlSection t_bs(root["T_BS"], imu_yaml, "T_BS");
  std::vector<double> m;
  t_bs.ReadList("data", &m, 16);
  Eigen::Matrix4d mat;
  for (int i = 0; i < 16; ++i) mat(i / 4, i % 4) = m[i];
  const Eigen::Matrix3d r = mat.topLeftCorner<3, 3>();
  if (!(r * r.transpose()).isApprox(Eigen::Matrix3d::Identity(), 1e-4)) {
    throw Error(imu_yaml + ": T_BS: not a rigid transform");
  }
  body_T_imu.matrix() = mat;
  return body_T_imu;
}

/// The samples of imu0/data.csv under `root` and the mount of imu0/sensor.yaml; no samples and
/// an identity mount when the sequence has no imu0/data.csv.
AslImu ReadAslImu(const std::string& root) {
  AslImu imu;
  const std::string imu_csv = root + "/imu0/data.csv";
  if (!fs::exists(imu_csv)) return imu;
  imu.samples = internal::ParseAslImuCsv(ReadTextFile(imu_csv), imu_csv);
  // A present IMU file without samples is a broken recording, not a sequence without an IMU.
  if (imu.samples.empty()) throw Error(imu_csv + ": no IMU samples (remove imu0/ if the platform has no IMU)");
  imu.path = imu_csv;
  imu.body_T_imu = ReadBodyTImu(root + "/imu0/sensor.yaml");
  return imu;
}

/// The poses of an ASL sequence and the file they were read from.
struct AslPoses {
  std::vector<PoseSample> samples;
  std::string path;  ///< "" without a pose file
};

/// The poses of pose0/data.csv under `root`, else of EuRoC's state_groundtruth_estimate0/data.csv;
/// none when neither exists.
AslPoses ReadAslPoses(const std::string& root) {
  AslPoses poses;
  std::string pose_csv = root + "/pose0/data.csv";
  if (!fs::exists(pose_csv)) pose_csv = root + "/state_groundtruth_estimate0/data.csv";
  if (!fs::exists(pose_csv)) return poses;
  poses.samples = internal::ParseAslPoseCsv(ReadTextFile(pose_csv), pose_csv);
  poses.path = pose_csv;
  return poses;
}

/// The vehicle.yaml shipped with the sequence: in the folder given (`path`), else in its root.
std::optional<std::string> FindVehicleConfig(const std::string& path, const std::string& root) {
  for (const auto& candidate : {fs::path(path) / "vehicle.yaml", fs::path(root) / "vehicle.yaml"}) {
    if (fs::exists(candidate)) return candidate.string();
  }
  return std::nullopt;
}

}  // namespace

Sequence Sequence::OpenAsl(const std::string& path) {
  if (!fs::is_directory(path)) throw Error(path + ": sequence folder not found");
  SequenceData seq;
  seq.format = "asl";
  seq.root = fs::is_directory(fs::path(path) / "mav0") ? (fs::path(path) / "mav0").string() : path;
  const std::string cam0 = seq.root + "/cam0";
  const std::string cam1 = seq.root + "/cam1";
  for (const auto& dir : {cam0, cam1}) {
    if (!fs::is_directory(dir)) throw Error(dir + ": camera folder not found (expected the ASL layout, docs/interfaces.md, section 2)");
  }
  seq.calibration = LoadStereoCalibration(cam0 + "/sensor.yaml", cam1 + "/sensor.yaml");
  AslFrames frames = PairAslFrames(cam0, cam1);
  seq.frames = std::move(frames.frames);
  seq.skipped = std::move(frames.skipped);
  AslImu imu = ReadAslImu(seq.root);
  seq.imu = std::move(imu.samples);
  seq.imu_path = std::move(imu.path);
  seq.body_T_imu = imu.body_T_imu;
  AslPoses poses = ReadAslPoses(seq.root);
  seq.poses = std::move(poses.samples);
  seq.pose_path = std::move(poses.path);
  seq.vehicle_config = FindVehicleConfig(path, seq.root);
  return Sequence(std::move(seq));
}

StereoImages Sequence::ReadImages(const StereoFrame& frame) const {
  if (data_.image_source) return data_.image_source->Read(frame);
  return ReadStereoImages(frame, data_.calibration);
}

StereoImages ReadStereoImages(const StereoFrame& frame, const StereoCalibration& calibration) {
  const auto read = [](const std::string& path, const CameraCalibration& c, const char* camera) {
    ImageU8 image = ReadGreyImage(path);
    if (image.width() != c.width || image.height() != c.height) {
      throw Error(path + ": image is " + std::to_string(image.width()) + "x" + std::to_string(image.height()) +
                  " px, the " + camera + " calibration (sensor.yaml resolution) says " + std::to_string(c.width) +
                  "x" + std::to_string(c.height));
    }
    return image;
  };
  StereoImages out;
  out.left = read(frame.left_path, calibration.left, "cam0");
  out.right = read(frame.right_path, calibration.right, "cam1");
  return out;
}

std::vector<StereoFrame> SelectFrames(const std::vector<StereoFrame>& frames, int every, int max_frames) {
  SSTA_CHECK(every >= 1 && max_frames >= 0, "every must be >= 1 and max_frames >= 0");
  std::vector<StereoFrame> out;
  for (std::size_t i = 0; i < frames.size(); i += static_cast<std::size_t>(every)) {
    if (max_frames > 0 && static_cast<int>(out.size()) >= max_frames) break;
    out.push_back(frames[i]);
  }
  return out;
}

void Sequence::RequireFramesWithin(std::int64_t first, std::int64_t last, const std::string& file,
                                   const std::string& what) const {
  const auto& frames = data_.frames;
  if (frames.empty() || std::any_of(frames.begin(), frames.end(), [&](const StereoFrame& f) {
        return f.timestamp_ns >= first && f.timestamp_ns <= last;
      })) {
    return;
  }
  throw Error(file + ": the " + what + " (" + std::to_string(first) + " to " + std::to_string(last) +
              " ns) overlap none of the " + std::to_string(frames.size()) + " frames (" +
              std::to_string(frames.front().timestamp_ns) + " to " + std::to_string(frames.back().timestamp_ns) +
              " ns)");
}

std::string Sequence::NoPoseReason(std::int64_t t) const {
  if (data_.poses.empty()) return "the sequence has no poses";
  if (t < data_.poses.front().timestamp_ns || t > data_.poses.back().timestamp_ns) {
    return "outside the pose time range";
  }
  if (WorldTBodyAt(t)) return "";
  const auto it = std::lower_bound(data_.poses.begin(), data_.poses.end(), t,
                                   [](const PoseSample& p, std::int64_t time) { return p.timestamp_ns < time; });
  std::ostringstream why;
  why << "inside a pose gap of " << 1e-9 * static_cast<double>(it->timestamp_ns - (it - 1)->timestamp_ns)
      << " s (longer than " << 1e-9 * kMaxPoseGapNs << " s is not interpolated)";
  return why.str();
}

std::optional<Eigen::Isometry3d> Sequence::WorldTBodyAt(std::int64_t t) const {
  if (data_.poses.empty() || t < data_.poses.front().timestamp_ns || t > data_.poses.back().timestamp_ns) {
    return std::nullopt;
  }
  const auto it = std::lower_bound(data_.poses.begin(), data_.poses.end(), t,
                                   [](const PoseSample& p, std::int64_t time) { return p.timestamp_ns < time; });
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  if (it->timestamp_ns == t || it == data_.poses.begin()) {
    out.linear() = it->world_q_body.toRotationMatrix();
    out.translation() = it->world_p_body;
    return out;
  }
  const PoseSample& b = *it;
  const PoseSample& a = *(it - 1);
  if (b.timestamp_ns - a.timestamp_ns > kMaxPoseGapNs) return std::nullopt;
  const double s = static_cast<double>(t - a.timestamp_ns) / static_cast<double>(b.timestamp_ns - a.timestamp_ns);
  out.linear() = a.world_q_body.slerp(s, b.world_q_body).toRotationMatrix();
  out.translation() = (1.0 - s) * a.world_p_body + s * b.world_p_body;
  return out;
}

}  // namespace ssta
