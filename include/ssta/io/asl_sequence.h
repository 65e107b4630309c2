#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "ssta/io/camera_calibration.h"

namespace ssta {

/// One stereo frame of a sequence: the paired left/right image files.
struct StereoFrame {
  std::int64_t timestamp_ns = 0;  ///< left image time
  std::string left_path;
  std::string right_path;
};

/// A frame that cannot be used, with the reason (reported, never guessed).
struct SkippedFrame {
  std::int64_t timestamp_ns = 0;
  std::string reason;
};

/// One IMU sample in the IMU sensor frame (ASL imu0/data.csv).
struct ImuSample {
  std::int64_t timestamp_ns = 0;
  Eigen::Vector3d angular_rate = Eigen::Vector3d::Zero();    ///< [rad/s]
  Eigen::Vector3d specific_force = Eigen::Vector3d::Zero();  ///< [m/s^2], +9.81 up at rest
};

/// One body pose T_WB (ASL pose0/data.csv or EuRoC's ground-truth estimate).
struct PoseSample {
  std::int64_t timestamp_ns = 0;
  Eigen::Vector3d world_p_body = Eigen::Vector3d::Zero();
  Eigen::Quaterniond world_q_body = Eigen::Quaterniond::Identity();
};

/// A recorded stereo sequence in the ASL / EuRoC layout (INTERFACES section 2), read at open:
/// calibration, frame list (left/right paired by timestamp, exact or nearest within 1 ms),
/// IMU and poses when present. Images are read on demand by the caller.
/// Immutable after Open(); safe for concurrent readers.
class AslSequence {
 public:
  /// Opens `path` (the sequence folder, or the folder holding `mav0/`). Throws ssta::Error naming
  /// the file and line for a missing folder, a malformed CSV row, timestamps out of order or
  /// duplicated, or an invalid calibration. Frames whose image files are missing are skipped
  /// with a reason (see skipped()), not errors.
  static AslSequence Open(const std::string& path);

  /// The folder the files were read from (with `/mav0` when the sequence has one).
  const std::string& root() const { return root_; }
  const StereoCalibration& calibration() const { return calibration_; }
  const std::vector<StereoFrame>& frames() const { return frames_; }
  const std::vector<SkippedFrame>& skipped() const { return skipped_; }
  const std::vector<ImuSample>& imu() const { return imu_; }
  const std::vector<PoseSample>& poses() const { return poses_; }
  /// Pose of the IMU in the body frame (imu0/sensor.yaml T_BS; identity when absent).
  const Eigen::Isometry3d& body_T_imu() const { return body_T_imu_; }
  /// `vehicle.yaml` shipped with the sequence, if any (a config file with a vehicle section).
  const std::optional<std::string>& vehicle_config() const { return vehicle_config_; }

  /// T_WB at `t`, interpolated (linear position, slerp rotation); nullopt outside the pose
  /// time range or when the sequence has no poses.
  std::optional<Eigen::Isometry3d> WorldTBodyAt(std::int64_t t) const;

  /// Up direction in the body frame from the accelerometer: the mean specific force over
  /// [t - window/2, t + window/2], normalised. Valid for a platform at rest or at constant
  /// velocity. nullopt without IMU samples in the window.
  std::optional<Eigen::Vector3d> UpInBodyFromImu(std::int64_t t, double window_s) const;

 private:
  std::string root_;
  StereoCalibration calibration_;
  std::vector<StereoFrame> frames_;
  std::vector<SkippedFrame> skipped_;
  std::vector<ImuSample> imu_;
  std::vector<PoseSample> poses_;
  Eigen::Isometry3d body_T_imu_ = Eigen::Isometry3d::Identity();
  std::optional<std::string> vehicle_config_;
};

/// Reads a numeric ASL CSV (`#` header line, comma separated, first column int64 ns).
/// Each row must have `columns` values. Throws ssta::Error naming file and line.
struct CsvRow {
  std::int64_t timestamp_ns = 0;
  std::vector<double> values;  ///< the columns after the timestamp
  int line = 0;
};
std::vector<CsvRow> ReadAslNumericCsv(const std::string& path, int columns);

}  // namespace ssta
