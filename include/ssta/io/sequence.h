#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "ssta/core/image.h"
#include "ssta/io/camera_calibration.h"

namespace ssta {

/// One stereo frame of a sequence: the paired left/right images.
struct StereoFrame {
  std::int64_t timestamp_ns = 0;  ///< left image time
  /// The image files; for a bag, "BAG:TOPIC@STAMP" names the message (for reports).
  std::string left_path;
  std::string right_path;
  /// For a bag: the pair's index in the bag's frame list (-1 for image files).
  std::int64_t message_index = -1;
};

/// The grey images of one stereo frame.
struct StereoImages {
  ImageU8 left;
  ImageU8 right;
};

/// Where a sequence keeps its images when they are not files (a bag): reads one frame's pair
/// as grey images of the calibration's size. Safe for concurrent calls.
class StereoImageSource {
 public:
  virtual ~StereoImageSource() = default;
  virtual StereoImages Read(const StereoFrame& frame) const = 0;
};

/// Which topics of a ROS bag make the sequence (docs/bags.md). An empty field is found
/// automatically; "none" for `imu` or `pose` uses none.
struct BagTopics {
  std::string left;        ///< sensor_msgs/Image or CompressedImage, the left camera
  std::string right;       ///< the right camera
  std::string imu;         ///< sensor_msgs/Imu
  std::string pose;        ///< nav_msgs/Odometry topic, or "/tf"
  std::string pose_frame;  ///< the body frame: its pose is the vehicle pose, the cameras are mounted on it
  /// Read a truncated bag (a recording cut off by a crash or a copy) up to its last complete
  /// message, with a warning (SequenceData::warnings), instead of refusing it.
  bool allow_truncated = false;
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
  /// Reads frames whose images are not files (bags); null for image files.
  std::shared_ptr<const StereoImageSource> image_source;
  /// What the reader assumed where the recording was silent (a bag without a camera mount in
  /// /tf_static, say), one sentence each, for reports.
  std::vector<std::string> notes;
  /// What of the recording is missing from the sequence (a truncated bag read with
  /// BagTopics::allow_truncated), one sentence each: runs report them and maps record them.
  std::vector<std::string> warnings;
};

/// A recorded stereo sequence, read at open: calibration, frame list (left/right paired by
/// timestamp), IMU and poses when present. Images are read on demand by the caller.
/// Immutable after opening; safe for concurrent readers.
class Sequence {
 public:
  explicit Sequence(SequenceData data);

  /// Opens `path` as a ROS bag (a `.bag` file, a rosbag2 folder, a `.mcap` or `.db3` file:
  /// OpenBag with `topics`), a KITTI raw drive when it has `image_00/` and `oxts/`, else as an
  /// ASL / EuRoC sequence (docs/interfaces.md, section 2). Throws ssta::Error naming the file
  /// (and line). Defined with the bag readers: link ssta::bags (ssta::ssta does).
  static Sequence Open(const std::string& path, const BagTopics& topics = {});

  /// A ROS 1 bag or a ROS 2 bag (MCAP or sqlite3) as a sequence (docs/bags.md): left and right
  /// images with their CameraInfo as the calibration (a raw pair as a folder's sensor.yaml holds
  /// it: K, D and the relative pose from R and P, its images as recorded, so that the
  /// pipeline's Rectifier rectifies them as a folder's; rectified topics, and distortion models
  /// CameraCalibration cannot hold, as the rectified pair P describes), Imu samples, poses from
  /// Odometry or /tf, the camera and IMU mounts from /tf_static. Frames pair as in an ASL
  /// sequence (header stamps, exact or nearest within 1 ms). Reads every message's header at
  /// open; images are decoded as frames are read. Throws ssta::Error naming the bag and topic,
  /// and for a truncated bag (an MCAP cut off before its end, a rosbag2 folder holding fewer
  /// messages than its metadata.yaml lists; with topics.allow_truncated read up to its last
  /// complete message, with a warning) or a ROS 1 bag cut off before its index. Defined with the
  /// bag readers: link ssta::bags (ssta::ssta does).
  static Sequence OpenBag(const std::string& path, const BagTopics& topics = {});

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
  /// What the reader assumed where the recording was silent (bags), for reports.
  const std::vector<std::string>& notes() const { return data_.notes; }
  /// What of the recording the sequence lacks (a truncated bag read anyway), for reports.
  const std::vector<std::string>& warnings() const { return data_.warnings; }

  /// The grey images of `frame`, from its files or its bag, checked against the calibration's
  /// size. Throws ssta::Error naming the file (or bag and message).
  StereoImages ReadImages(const StereoFrame& frame) const;

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

/// Reads both images of `frame` and checks their size against the calibration's resolution
/// (sensor.yaml), so a left and right of different sizes or a resized image is caught at the
/// file. Throws ssta::Error naming the image file that is missing, unreadable, truncated or of
/// the wrong size.
StereoImages ReadStereoImages(const StereoFrame& frame, const StereoCalibration& calibration);

/// The skipped frames grouped by reason, one line each ("  skipped N (first at T ns): REASON"),
/// in the order the reasons first occur, at most 10 reasons; "" when none was skipped.
std::string DescribeSkipped(const std::vector<SkippedFrame>& skipped);

/// Writes `sequence` in the ASL layout under `out` (docs/interfaces.md, section 2): the images
/// as read (grey; raw when the bag's images were raw, with the raw calibration), both
/// sensor.yaml, imu0 and pose0 when present. `progress(done, total)` is called per frame. Throws ssta::Error naming the
/// file it cannot write.
void WriteAslSequence(const Sequence& sequence, const std::string& out,
                      const std::function<void(int, int)>& progress = {});

/// Pairs two ascending timestamp lists as every sequence reader does (docs/interfaces.md,
/// section 2): for each left time [ns], the index of the nearest right time when it is within
/// 1 ms, else -1.
std::vector<std::ptrdiff_t> PairNearestWithin1Ms(const std::vector<std::int64_t>& left,
                                                 const std::vector<std::int64_t>& right);

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
