// KITTI raw drive reader: rectified grey stereo (image_00, image_01), OXTS poses, calibration.

#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "ssta/core/error.h"
#include "ssta/io/sequence.h"

namespace fs = std::filesystem;

namespace ssta {
namespace {

constexpr double kEarthRadiusM = 6378137.0;  // as KITTI's development kit

/// "key: v1 v2 ..." lines of a KITTI calibration file.
std::map<std::string, std::vector<double>> ReadCalibFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(path + ": file not found");
  std::map<std::string, std::vector<double>> out;
  std::string line;
  while (std::getline(in, line)) {
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    const std::string key = line.substr(0, colon);
    std::istringstream values(line.substr(colon + 1));
    std::vector<double> v;
    double x;
    while (values >> x) v.push_back(x);
    if (values.fail() && !values.eof()) continue;  // text values (calib_time)
    out[key] = v;
  }
  return out;
}

const std::vector<double>& Need(const std::map<std::string, std::vector<double>>& calib, const std::string& key,
                                std::size_t n, const std::string& file) {
  const auto it = calib.find(key);
  if (it == calib.end()) throw Error(file + ": missing key " + key);
  if (it->second.size() != n) {
    throw Error(file + ": " + key + ": expected " + std::to_string(n) + " numbers, found " + std::to_string(it->second.size()));
  }
  return it->second;
}

Eigen::Isometry3d RigidFrom(const std::vector<double>& r, const std::vector<double>& t) {
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() << r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8];
  out.translation() << t[0], t[1], t[2];
  return out;
}

std::string FindCalib(const fs::path& drive, const std::string& name) {
  for (const fs::path& dir : {drive, drive.parent_path()}) {
    if (fs::exists(dir / name)) return (dir / name).string();
  }
  throw Error(drive.string() + ": " + name + " not found in the drive folder or its parent");
}

/// "2011-09-26 13:02:25.964389445" (UTC) -> ns since the epoch.
std::int64_t ParseKittiTime(const std::string& text, const std::string& where) {
  std::tm tm{};
  int year, month, day, hour, minute;
  double seconds;
  if (std::sscanf(text.c_str(), "%d-%d-%d %d:%d:%lf", &year, &month, &day, &hour, &minute, &seconds) != 6) {
    throw Error(where + ": bad timestamp '" + text + "'");
  }
  tm.tm_year = year - 1900;
  tm.tm_mon = month - 1;
  tm.tm_mday = day;
  tm.tm_hour = hour;
  tm.tm_min = minute;
  const auto whole = static_cast<std::int64_t>(std::floor(seconds));
  tm.tm_sec = static_cast<int>(whole);
  const std::int64_t epoch_s = timegm(&tm);
  // Read the fraction from the text to keep all nine digits.
  std::int64_t frac_ns = 0;
  const auto dot = text.rfind('.');
  if (dot != std::string::npos) {
    std::string digits = text.substr(dot + 1, 9);
    digits.resize(9, '0');
    frac_ns = std::stoll(digits);
  }
  return epoch_s * 1'000'000'000LL + frac_ns;
}

std::vector<std::int64_t> ReadTimestamps(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(path + ": file not found");
  std::vector<std::int64_t> out;
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    const std::string where = path + ":" + std::to_string(n);
    out.push_back(ParseKittiTime(line, where));
    if (out.size() > 1 && out.back() <= out[out.size() - 2]) throw Error(where + ": timestamp out of order or duplicated");
  }
  return out;
}

std::string Indexed(const fs::path& dir, std::size_t i, const char* ext) {
  char name[32];
  std::snprintf(name, sizeof(name), "%010zu%s", i, ext);
  return (dir / name).string();
}

}  // namespace

Sequence Sequence::OpenKittiRaw(const std::string& path) {
  const fs::path drive(path);
  if (!fs::is_directory(drive)) throw Error(path + ": KITTI drive folder not found");
  SequenceData seq;
  seq.root = path;
  seq.format = "kitti_raw";

  // Calibration: rectified cam0/cam1 intrinsics from P_rect, body (= OXTS IMU) to camera from
  // the IMU->velodyne->camera chain and R_rect_00.
  const std::string cam_file = FindCalib(drive, "calib_cam_to_cam.txt");
  const std::string velo_file = FindCalib(drive, "calib_velo_to_cam.txt");
  const std::string imu_file = FindCalib(drive, "calib_imu_to_velo.txt");
  const auto cam = ReadCalibFile(cam_file);
  const auto velo = ReadCalibFile(velo_file);
  const auto imu = ReadCalibFile(imu_file);
  const auto& size = Need(cam, "S_rect_00", 2, cam_file);
  const auto& p0 = Need(cam, "P_rect_00", 12, cam_file);
  const auto& p1 = Need(cam, "P_rect_01", 12, cam_file);
  const auto& r_rect = Need(cam, "R_rect_00", 9, cam_file);
  const Eigen::Isometry3d cam0_T_velo = RigidFrom(Need(velo, "R", 9, velo_file), Need(velo, "T", 3, velo_file));
  const Eigen::Isometry3d velo_T_imu = RigidFrom(Need(imu, "R", 9, imu_file), Need(imu, "T", 3, imu_file));
  const Eigen::Isometry3d rect_T_cam0 = RigidFrom(r_rect, {0, 0, 0});

  CameraCalibration left;
  left.width = static_cast<int>(size[0]);
  left.height = static_cast<int>(size[1]);
  left.fu = p0[0];
  left.fv = p0[5];
  left.cu = p0[2];
  left.cv = p0[6];
  left.body_T_camera = (rect_T_cam0 * cam0_T_velo * velo_T_imu).inverse();
  left.rate_hz = 10.0;
  // Orthonormalise: KITTI's rotations are printed with ~1e-6 precision.
  left.body_T_camera.linear() = Eigen::Quaterniond(left.body_T_camera.rotation()).normalized().toRotationMatrix();
  if (!(p1[0] > 0)) throw Error(cam_file + ": P_rect_01: focal length must be positive");
  const double baseline = -p1[3] / p1[0];
  CameraCalibration right = left;
  right.body_T_camera = left.body_T_camera * Eigen::Translation3d(baseline, 0, 0);
  seq.calibration = StereoCalibration{left, right};
  std::string error;
  if (!seq.calibration.IsValid(&error)) throw Error(cam_file + ": " + error);

  // Frames: image_00 / image_01 by index (the synced drive has one row per index).
  const auto left_times = ReadTimestamps((drive / "image_00/timestamps.txt").string());
  const auto right_times = ReadTimestamps((drive / "image_01/timestamps.txt").string());
  if (left_times.size() != right_times.size()) {
    throw Error(path + ": image_00 and image_01 list " + std::to_string(left_times.size()) + " and " +
                std::to_string(right_times.size()) + " timestamps");
  }
  for (std::size_t i = 0; i < left_times.size(); ++i) {
    const std::string l = Indexed(drive / "image_00/data", i, ".png");
    const std::string r = Indexed(drive / "image_01/data", i, ".png");
    if (!fs::exists(l)) {
      seq.skipped.push_back({left_times[i], "cam0 image missing: " + l});
    } else if (!fs::exists(r)) {
      seq.skipped.push_back({left_times[i], "cam1 image missing: " + r});
    } else {
      seq.frames.push_back({left_times[i], l, r});
    }
  }

  // OXTS -> poses (KITTI devkit: Mercator at the first latitude, R = Rz(yaw) Ry(pitch) Rx(roll),
  // relative to the first pose).
  const auto oxts_times = ReadTimestamps((drive / "oxts/timestamps.txt").string());
  double scale = 0.0;
  Eigen::Isometry3d first_inv = Eigen::Isometry3d::Identity();
  for (std::size_t i = 0; i < oxts_times.size(); ++i) {
    const std::string file = Indexed(drive / "oxts/data", i, ".txt");
    std::ifstream in(file);
    if (!in) throw Error(file + ": file not found");
    std::vector<double> v;
    double x;
    while (in >> x) v.push_back(x);
    if (v.size() < 6) throw Error(file + ": expected at least 6 numbers (lat lon alt roll pitch yaw)");
    for (int k = 0; k < 6; ++k) {
      if (!std::isfinite(v[k])) throw Error(file + ": NaN or infinite value");
    }
    const double lat = v[0], lon = v[1], alt = v[2];
    if (i == 0) scale = std::cos(lat * M_PI / 180.0);
    const double mx = scale * lon * M_PI * kEarthRadiusM / 180.0;
    const double my = scale * kEarthRadiusM * std::log(std::tan((90.0 + lat) * M_PI / 360.0));
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.linear() = (Eigen::AngleAxisd(v[5], Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(v[4], Eigen::Vector3d::UnitY()) *
                  Eigen::AngleAxisd(v[3], Eigen::Vector3d::UnitX()))
                     .toRotationMatrix();
    t.translation() << mx, my, alt;
    if (i == 0) first_inv = t.inverse();
    const Eigen::Isometry3d pose = first_inv * t;
    seq.poses.push_back({oxts_times[i], pose.translation(), Eigen::Quaterniond(pose.rotation()).normalized()});
  }
  return Sequence(std::move(seq));
}

}  // namespace ssta
