#pragma once

// What every sequence driver (classify, build-map, bench, calibrate-mount) does the same way:
// choose the frames, give each its gravity and pose, run it through the per-frame pipeline (or
// its oracles), and skip a frame that cannot be used with its reason, or stop on it when strict.

#include <cstddef>
#include <cstdint>
#include <future>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "ssta/analysis/frame_result.h"
#include "ssta/io/sequence.h"
#include "ssta/pipeline/config.h"
#include "ssta/pipeline/frame_pipeline.h"
#include "ssta/sensors/gravity_provider.h"

namespace ssta {

/// Which frames of a sequence a driver runs over, and what a frame that cannot be used does.
struct FrameSelection {
  int every = 1;        ///< use every n-th frame
  int max_frames = 0;   ///< at most this many frames (0: all)
  /// A frame that cannot be used (unpaired, missing or unreadable image, no pose) is an error
  /// instead of a skip with its reason.
  bool strict = false;
  /// On failure names the command-line option ("every: must be at least 1").
  bool IsValid(std::string* error) const;
};

/// Measurement oracles of a synthetic sequence (its gt/ folder), for splitting the error of
/// the map between the matcher, the analysis and the fusion.
struct Oracles {
  /// Each frame's true disparity (gt/disparity/<ts>.png) instead of stereo matching.
  bool disparity = false;
  /// Each frame's true labels (gt/labels/<ts>.png) where the truth has a verdict, with the
  /// rule LabelRule::kTruth; the frame's own labels and rules elsewhere.
  bool labels = false;
};

/// cam0's mount and the rectification: the one place that composes
/// world_T_rectified = world_T_body * body_T_cam0 * cam0_R_rectified.
class RigChain {
 public:
  RigChain(const Eigen::Isometry3d& body_T_camera, const RectifiedGeometry& geometry);

  /// Replaces cam0's mount (an online refinement's solve).
  void set_body_T_camera(const Eigen::Isometry3d& body_T_camera);
  const Eigen::Isometry3d& body_T_camera() const { return body_T_camera_; }
  /// The rotation from the rectified into the original cam0 frame.
  const Eigen::Matrix3d& camera_R_rectified() const { return camera_R_rectified_; }
  const Eigen::Isometry3d& body_T_rectified() const { return body_T_rectified_; }
  Eigen::Isometry3d WorldTRectified(const Eigen::Isometry3d& world_T_body) const {
    return world_T_body * body_T_rectified_;
  }
  /// Unit up in the original cam0 frame for a body whose up is `up_body`.
  Eigen::Vector3d UpInCamera(const Eigen::Vector3d& up_body) const {
    return (body_T_camera_.linear().transpose() * up_body).normalized();
  }

 private:
  Eigen::Isometry3d body_T_camera_;
  Eigen::Matrix3d camera_R_rectified_;
  Eigen::Isometry3d body_T_rectified_;
};

/// Unit up in the body frame of a pose T_WB (its world z, seen from the body).
inline Eigen::Vector3d UpInBody(const Eigen::Isometry3d& world_T_body) {
  return (world_T_body.linear().transpose() * Eigen::Vector3d::UnitZ()).normalized();
}

/// Thrown when a strict run meets a frame it cannot use: an ssta::Error the per-frame handlers
/// let through.
struct StrictStop : Error {
  using Error::Error;
};

/// The selected frames of one sequence through one FramePipeline, with the sequence's gravity.
/// Not thread-safe (the pipeline reuses its buffers).
class SequenceRun {
 public:
  /// Throws ssta::Error on an invalid selection or config, an unusable calibration, or an IMU
  /// that covers none of the frames; StrictStop when `selection.strict` and the sequence itself
  /// skipped a frame (an unpaired image).
  SequenceRun(const Sequence& sequence, const Config& config, const FrameSelection& selection,
              const Oracles& oracles = {});

  const Sequence& sequence() const { return sequence_; }
  /// The frames to run, in order.
  const std::vector<StereoFrame>& frames() const { return frames_; }
  /// Frames the sequence lists, the ones it could not pair included.
  int frames_listed() const;
  /// The frames the sequence itself skipped (unpaired, missing images), with their reasons.
  const std::vector<SkippedFrame>& sequence_skips() const { return sequence_.skipped(); }
  FramePipeline& pipeline() { return pipeline_; }
  const RectifiedGeometry& geometry() const { return pipeline_.geometry(); }
  const GravityProvider& gravity() const { return gravity_; }

  /// T_WB at frame `t`, roll and pitch from the IMU in use (GravityProvider::WorldTBodyAt);
  /// with `static_platform`, the origin levelled by gravity. Throws ssta::Error with the reason
  /// when the frame has no pose or no attitude.
  Eigen::Isometry3d WorldTBody(std::int64_t t, bool static_platform) const;

  /// Reads `frame`'s images and classifies them with `up_camera` (unit up in the original cam0
  /// frame), through the oracles asked for. Throws ssta::Error when the frame cannot be used.
  /// `left_image_hash`, when given, receives SampledImageHash of the grey left image read.
  FrameResult Classify(const StereoFrame& frame, const Eigen::Vector3d& up_camera,
                       std::uint64_t* left_image_hash = nullptr);

  /// With read-ahead on, each Classify, once it has its frame's images, starts reading (and
  /// decoding) the images of the next frame of frames() on a second thread, so that they are
  /// ready when that frame is classified. The images, results and errors are those of reading
  /// in turn: a frame asked for out of order is read then, and never two reads at once (a bag
  /// is read from one thread at a time). Off by default.
  void set_read_ahead(bool on);

  /// A frame that cannot be used: StrictStop naming it in a strict run, else nothing (the
  /// caller records the skip).
  void RequireNotStrict(std::int64_t t, const std::string& reason) const;

 private:
  const Sequence& sequence_;
  FrameSelection selection_;
  Oracles oracles_;
  FramePipeline pipeline_;
  GravityProvider gravity_;
  std::vector<StereoFrame> frames_;
  /// `frame`'s images: the ones read ahead when they are that frame's, else read now; then,
  /// with read-ahead, the next frame's read is started.
  StereoImages ReadImages(const StereoFrame& frame);
  bool read_ahead_ = false;
  /// The read under way, of frames_[ahead_index_] (valid() when there is one).
  std::future<StereoImages> ahead_;
  std::size_t ahead_index_ = 0;
};

}  // namespace ssta
