#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "ssta/core/image.h"
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

/// Everything a sequence reader produces; a Sequence wraps it.
struct SequenceData {
  std::string root;     ///< folder the files were read from
  std::string format;   ///< "asl" or "kitti_raw"
  StereoCalibration calibration;
  std::vector<StereoFrame> frames;
  std::vector<SkippedFrame> skipped;
  std::vector<ImuSample> imu;
  std::string imu_path;  ///< the file `imu` was read from ("" without IMU), for messages
  std::vector<PoseSample> poses;
  std::string pose_path;  ///< the file (or folder) `poses` were read from ("" without them)
  Eigen::Isometry3d body_T_imu = Eigen::Isometry3d::Identity();
  std::optional<std::string> vehicle_config;
};

/// A recorded stereo sequence, read at open: calibration, frame list (left/right paired by
/// timestamp), IMU and poses when present. Images are read on demand by the caller.
/// Immutable after opening; safe for concurrent readers.
class Sequence {
 public:
  explicit Sequence(SequenceData data);

  /// Opens `path` as a KITTI raw drive when it has `image_00/` and `oxts/`, else as an ASL /
  /// EuRoC sequence (docs/interfaces.md, section 2). Throws ssta::Error naming the file (and line).
  static Sequence Open(const std::string& path);

  /// The ASL / EuRoC layout (the folder, or the folder holding `mav0/`). Left/right frames are
  /// paired exactly or to the nearest within 1 ms. Throws ssta::Error naming the file and line
  /// for a missing folder, a malformed CSV row, timestamps out of order or duplicated, or an
  /// invalid calibration. Frames whose image files are missing are skipped with a reason.
  static Sequence OpenAsl(const std::string& path);

  /// A KITTI raw drive (`..._sync` folder: image_00 and image_01 grey rectified, oxts/,
  /// timestamps), with `calib_cam_to_cam.txt`, `calib_velo_to_cam.txt` and
  /// `calib_imu_to_velo.txt` in the drive folder or its parent. OXTS GPS/IMU readings become
  /// local metric poses T_WB (body = the OXTS IMU frame, x forward, z up) the way KITTI's
  /// development kit converts them: Mercator projection scaled at the first latitude, the
  /// first pose at the origin.
  static Sequence OpenKittiRaw(const std::string& path);

  const std::string& root() const { return data_.root; }
  const std::string& format() const { return data_.format; }
  const StereoCalibration& calibration() const { return data_.calibration; }
  const std::vector<StereoFrame>& frames() const { return data_.frames; }
  const std::vector<SkippedFrame>& skipped() const { return data_.skipped; }
  const std::vector<ImuSample>& imu() const { return data_.imu; }
  /// The file the IMU samples were read from ("" without them).
  const std::string& imu_path() const { return data_.imu_path; }
  const std::vector<PoseSample>& poses() const { return data_.poses; }
  /// The file (KITTI: the folder) the poses were read from ("" without them).
  const std::string& pose_path() const { return data_.pose_path; }
  /// Pose of the IMU in the body frame (imu0/sensor.yaml T_BS; identity when absent).
  const Eigen::Isometry3d& body_T_imu() const { return data_.body_T_imu; }
  /// `vehicle.yaml` shipped with the sequence, if any (a config file with a vehicle section).
  const std::optional<std::string>& vehicle_config() const { return data_.vehicle_config; }

  /// Poses are not interpolated across a gap longer than this [ns]: that would be a guess.
  static constexpr std::int64_t kMaxPoseGapNs = 500'000'000;

  /// T_WB at `t`, interpolated (linear position, slerp rotation); nullopt outside the pose
  /// time range, inside a gap longer than kMaxPoseGapNs, or when the sequence has no poses.
  std::optional<Eigen::Isometry3d> WorldTBodyAt(std::int64_t t) const;
  /// Why WorldTBodyAt(t) has no answer, for reports ("" when it has one).
  std::string NoPoseReason(std::int64_t t) const;
  /// Throws ssta::Error "FILE: the WHAT (FIRST to LAST ns) overlap none of the N frames (..)"
  /// when the sequence has frames and none lies in [first, last] (a mismatched recording, not
  /// a few frames to skip).
  void RequireFramesWithin(std::int64_t first, std::int64_t last, const std::string& file,
                           const std::string& what) const;

 private:
  SequenceData data_;
};

/// The grey images of one stereo frame.
struct StereoImages {
  ImageU8 left;
  ImageU8 right;
};

/// Reads both images of `frame` and checks their size against the calibration's resolution
/// (sensor.yaml), so a left and right of different sizes or a resized image is caught at the
/// file. Throws ssta::Error naming the image file that is missing, unreadable, truncated or of
/// the wrong size.
StereoImages ReadStereoImages(const StereoFrame& frame, const StereoCalibration& calibration);

/// Every `every`-th frame from the first, at most `max_frames` of them (0: no limit).
/// Precondition: every >= 1, max_frames >= 0.
std::vector<StereoFrame> SelectFrames(const std::vector<StereoFrame>& frames, int every, int max_frames);

/// Reads a numeric ASL CSV (`#` header line, comma separated, first column int64 ns).
/// Each row must have `columns` values. Throws ssta::Error naming file and line.
struct CsvRow {
  std::int64_t timestamp_ns = 0;
  std::vector<double> values;  ///< the columns after the timestamp
  int line = 0;
};
std::vector<CsvRow> ReadAslNumericCsv(const std::string& path, int columns);

}  // namespace ssta
