#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include <Eigen/Core>

#include "ssta/analysis/frame_result.h"
#include "ssta/core/image.h"
#include "ssta/io/camera_calibration.h"
#include "ssta/pipeline/config.h"

namespace ssta {

/// The disparity search range a rig needs: the largest disparity of level ground seen at the
/// bottom row of the rectified common area, with cam0's mount (`body_T_camera`) taken to stand
/// its height above the ground (the body origin on the ground), plus 10 %, rounded up to a
/// multiple of 16 and at most half the image width. `fallback` when the mount does not tell a
/// height (cam0 less than 0.1 m above the body origin) or no bottom ray meets the ground; never
/// less than `fallback`.
int AutoNumDisparities(const RectifiedGeometry& geometry, const Eigen::Isometry3d& body_T_camera, int fallback);

/// The paper's per-frame chain: rectify + crop, stereo matching, triangulation, integral-image
/// normals, normal segmentation, SSTA. Not thread-safe: Process() reuses internal buffers;
/// use one pipeline per thread.
class FramePipeline {
 public:
  /// Throws ssta::Error on an invalid config or calibration.
  FramePipeline(const StereoCalibration& calibration, const Config& config);
  ~FramePipeline();

  /// Classifies one raw stereo pair. `up_camera` is the unit up vector in the original (not
  /// rectified) cam0 frame. Throws ssta::Error when the images have the wrong size.
  FrameResult Process(const ImageU8& left, const ImageU8& right, const Eigen::Vector3d& up_camera);

  /// Like Process, but with a given disparity of the rectified, cropped left image [px, 0
  /// invalid] in place of stereo matching: an oracle for measuring the analysis apart from
  /// the matcher (e.g. with a synthetic sequence's gt/disparity). Throws ssta::Error when the
  /// disparity does not have the crop size.
  FrameResult ProcessWithDisparity(const ImageU8& left, const ImageU8& right, ImageF disparity,
                                   const Eigen::Vector3d& up_camera);

  /// Up in the cam0 frame for a body whose up direction is `up_body` (via cam0's T_BS).
  Eigen::Vector3d UpInCamera(const Eigen::Vector3d& up_body) const;

  const RectifiedGeometry& geometry() const;
  const Config& config() const { return config_; }

 private:
  struct Stages;
  FrameResult Run(const ImageU8& left, const ImageU8& right, const ImageF* disparity,
                  const Eigen::Vector3d& up_camera);
  Config config_;
  StereoCalibration calibration_;
  std::unique_ptr<Stages> stages_;
  ImageU8 supported_;  // the frame's supported pixels (analysis.label_min_texture), reused
};

}  // namespace ssta
