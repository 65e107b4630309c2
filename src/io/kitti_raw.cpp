// KITTI raw drive reader: rectified grey stereo (image_00, image_01), OXTS poses, calibration.

#include <cctype>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "ssta/core/error.h"
#include "ssta/files/file_util.h"
#include "ssta/io/sequence.h"
#include "ssta/core/units.h"
#include "text_parsers.h"

namespace fs = std::filesystem;

namespace ssta {
namespace {

constexpr double kEarthRadiusM = 6378137.0;  // as KITTI's development kit

std::map<std::string, std::vector<double>> ReadCalibFile(const std::string& path) {
  return internal::ParseKittiCalib(ReadTextFile(path));
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

/// "2011-09-26 13:02:25.964389445" (UTC) -> ns since the epoch. Fields are range-checked so
/// that no arithmetic below can overflow.
std::int64_t ParseKittiTime(const std::string& text, const std::string& where) {
  int year = 0, month = 0, day = 0, hour = 0, minute = 0, second = 0, used = 0;
  const auto bad = [&]() { return Error(where + ": bad timestamp '" + text + "'"); };
  if (std::sscanf(text.c_str(), "%4d-%2d-%2d %2d:%2d:%2d%n", &year, &month, &day, &hour, &minute, &second, &used) != 6) {
    throw bad();
  }
  if (year < 1970 || year > 2200 || month < 1 || month > 12 || day < 1 || day > 31 || hour < 0 || hour > 23 ||
      minute < 0 || minute > 59 || second < 0 || second > 60) {
    throw bad();
  }
  // Optional fraction: '.' and up to nine digits are kept (more are ignored), then only blanks.
  std::int64_t frac_ns = 0;
  std::size_t pos = static_cast<std::size_t>(used);
  if (pos < text.size() && text[pos] == '.') {
    ++pos;
    int digits = 0;
    while (pos < text.size() && std::isdigit(static_cast<unsigned char>(text[pos]))) {
      if (digits < 9) frac_ns = frac_ns * 10 + (text[pos] - '0');
      ++digits;
      ++pos;
    }
    if (digits == 0) throw bad();
    for (; digits < 9; ++digits) frac_ns *= 10;
  }
  if (text.find_first_not_of(" \t\r", pos) != std::string::npos) throw bad();
  std::tm tm{};
  tm.tm_year = year - 1900;
  tm.tm_mon = month - 1;
  tm.tm_mday = day;
  tm.tm_hour = hour;
  tm.tm_min = minute;
  tm.tm_sec = second;
  const std::int64_t epoch_s = timegm(&tm);
  return epoch_s * 1'000'000'000LL + frac_ns;
}

std::vector<std::int64_t> ReadTimestamps(const std::string& path) {
  return internal::ParseKittiTimestamps(ReadTextFile(path), path);
}

std::string Indexed(const fs::path& dir, std::size_t i, const char* ext) {
  char name[32];
  std::snprintf(name, sizeof(name), "%010zu%s", i, ext);
  return (dir / name).string();
}

}  // namespace

namespace internal {

std::map<std::string, std::vector<double>> ParseKittiCalib(const std::string& text) {
  std::istringstream in(text);
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

std::vector<std::int64_t> ParseKittiTimestamps(const std::string& text, const std::string& path) {
  std::istringstream in(text);
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

std::vector<double> ParseOxtsRow(const std::string& text, const std::string& path) {
  std::istringstream in(text);
  std::vector<double> v;
  double x;
  while (in >> x) v.push_back(x);
  if (v.size() < 6) throw Error(path + ": expected at least 6 numbers (lat lon alt roll pitch yaw)");
  for (int k = 0; k < 6; ++k) {
    if (!std::isfinite(v[k])) throw Error(path + ": NaN or infinite value");
  }
  if (std::abs(v[0]) >= 90.0) throw Error(path + ": latitude must lie strictly between -90 and 90 degrees");
  return v;
}

}  // namespace internal

namespace {

/// The rectified stereo calibration of the drive: cam0/cam1 intrinsics from P_rect, body
/// (= OXTS IMU) to camera from the IMU->velodyne->camera chain and R_rect_00.
StereoCalibration ReadKittiCalibration(const fs::path& drive) {
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

  for (const double pixels : size) {
    if (!(pixels >= 1 && pixels <= 100000) || pixels != std::floor(pixels)) {
      throw Error(cam_file + ": S_rect_00: must be two positive whole numbers");
    }
  }
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
  StereoCalibration calibration{left, right};
  std::string error;
  if (!calibration.IsValid(&error)) throw Error(cam_file + ": " + error);
  return calibration;
}

/// The frames of a drive and the ones skipped for a missing image.
struct KittiFrames {
  std::vector<StereoFrame> frames;
  std::vector<SkippedFrame> skipped;
};

/// The stereo frames of the drive: image_00 / image_01 by index (the synced drive has one
/// timestamp row per index), a frame whose image file is missing skipped with the reason.
KittiFrames ListKittiFrames(const fs::path& drive) {
  const auto left_times = ReadTimestamps((drive / "image_00/timestamps.txt").string());
  const auto right_times = ReadTimestamps((drive / "image_01/timestamps.txt").string());
  if (left_times.empty()) throw Error((drive / "image_00/timestamps.txt").string() + ": lists no frames (an empty sequence)");
  if (left_times.size() != right_times.size()) {
    throw Error(drive.string() + ": image_00 and image_01 list " + std::to_string(left_times.size()) + " and " +
                std::to_string(right_times.size()) + " timestamps");
  }
  KittiFrames out;
  for (std::size_t i = 0; i < left_times.size(); ++i) {
    const std::string l = Indexed(drive / "image_00/data", i, ".png");
    const std::string r = Indexed(drive / "image_01/data", i, ".png");
    if (!fs::exists(l)) {
      out.skipped.push_back({left_times[i], "cam0 image missing: " + l});
    } else if (!fs::exists(r)) {
      out.skipped.push_back({left_times[i], "cam1 image missing: " + r});
    } else {
      out.frames.push_back({left_times[i], l, r});
    }
  }
  return out;
}

/// The drive's OXTS readings as poses T_WB, as KITTI's development kit converts them: Mercator
/// at the first latitude, R = Rz(yaw) Ry(pitch) Rx(roll), relative to the first pose.
std::vector<PoseSample> ReadOxtsPoses(const fs::path& drive) {
  const auto oxts_times = ReadTimestamps((drive / "oxts/timestamps.txt").string());
  std::vector<PoseSample> poses;
  double scale = 0.0;
  Eigen::Isometry3d first_inv = Eigen::Isometry3d::Identity();
  for (std::size_t i = 0; i < oxts_times.size(); ++i) {
    const std::string file = Indexed(drive / "oxts/data", i, ".txt");
    const std::vector<double> v = internal::ParseOxtsRow(ReadTextFile(file), file);
    const double lat = v[0], lon = v[1], alt = v[2];
    if (i == 0) scale = std::cos(DegToRad(lat));
    const double mx = scale * DegToRad(lon) * kEarthRadiusM;
    const double my = scale * kEarthRadiusM * std::log(std::tan(DegToRad(90.0 + lat) / 2.0));
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.linear() = (Eigen::AngleAxisd(v[5], Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(v[4], Eigen::Vector3d::UnitY()) *
                  Eigen::AngleAxisd(v[3], Eigen::Vector3d::UnitX()))
                     .toRotationMatrix();
    t.translation() << mx, my, alt;
    if (i == 0) first_inv = t.inverse();
    const Eigen::Isometry3d pose = first_inv * t;
    poses.push_back({oxts_times[i], pose.translation(), Eigen::Quaterniond(pose.rotation()).normalized()});
  }
  return poses;
}

}  // namespace

Sequence Sequence::OpenKittiRaw(const std::string& path) {
  const fs::path drive(path);
  if (!fs::is_directory(drive)) throw Error(path + ": KITTI drive folder not found");
  SequenceData seq;
  seq.root = path;
  seq.format = "kitti_raw";
  seq.calibration = ReadKittiCalibration(drive);
  KittiFrames frames = ListKittiFrames(drive);
  seq.frames = std::move(frames.frames);
  seq.skipped = std::move(frames.skipped);
  seq.pose_path = (drive / "oxts").string();
  seq.poses = ReadOxtsPoses(drive);
  return Sequence(std::move(seq));
}

}  // namespace ssta
