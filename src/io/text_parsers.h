#pragma once

// Private: the sequence and calibration readers' parsers, from text already read from a file.
// The file readers in src/io call these; the fuzz targets (fuzz/) and the io tests call them
// directly. `path` only names the file in messages. Each throws ssta::Error naming the file
// (and line or key) on bad input; none touches the file system.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "ssta/io/camera_calibration.h"
#include "ssta/io/sequence.h"

namespace ssta::internal {

/// One row of a camera's `data.csv`: the time and the image file name as written (relative to
/// the camera's `data/` folder).
struct ImageListEntry {
  std::int64_t timestamp_ns = 0;
  std::string file;
};

/// Rows of an ASL numeric CSV (`#` comment lines, comma separated, strictly increasing int64 ns
/// timestamps in the first column, `columns` columns in all).
std::vector<CsvRow> ParseAslNumericCsv(const std::string& text, const std::string& path, int columns);

/// A camera's `data.csv` ("timestamp,filename").
std::vector<ImageListEntry> ParseAslImageList(const std::string& text, const std::string& path);

/// `imu0/data.csv`: t, angular rate xyz [rad/s], specific force xyz [m/s^2].
std::vector<ImuSample> ParseAslImuCsv(const std::string& text, const std::string& path);

/// `pose0/data.csv` or EuRoC's ground truth: t, position xyz, quaternion wxyz, optional extra
/// columns (the count is taken from the first data row). Quaternions are normalised; a zero
/// one is an error.
std::vector<PoseSample> ParseAslPoseCsv(const std::string& text, const std::string& path);

/// A camera's `sensor.yaml` (ASL / EuRoC layout), validated.
CameraCalibration ParseCameraCalibration(const std::string& text, const std::string& path);

/// "key: v1 v2 ..." lines of a KITTI calibration file; keys with text values are left out.
std::map<std::string, std::vector<double>> ParseKittiCalib(const std::string& text);

/// A KITTI `timestamps.txt` ("2011-09-26 13:02:25.964389445", UTC), strictly increasing.
std::vector<std::int64_t> ParseKittiTimestamps(const std::string& text, const std::string& path);

/// One KITTI OXTS row: at least lat lon alt roll pitch yaw, all finite; returns every number.
std::vector<double> ParseOxtsRow(const std::string& text, const std::string& path);

}  // namespace ssta::internal
