#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include <Eigen/Core>

#include "ssta/analysis/surface_analyzer.h"
#include "ssta/core/image.h"
#include "ssta/io/camera_calibration.h"
#include "ssta/pipeline/config.h"

namespace ssta {

/// Wall time of each stage of one frame [ms].
struct StageTimings {
  double rectify_ms = 0, match_ms = 0, triangulate_ms = 0, normals_ms = 0, segment_ms = 0,
         analyze_ms = 0, total_ms = 0;
};

/// Everything one frame produced.
struct FrameResult {
  std::int64_t timestamp_ns = 0;
  ImageU8 left_rectified;   ///< full rectified left image
  ImageF disparity;         ///< cropped to the common area [px], 0 invalid
  Image3f cloud;            ///< organized points of the common area, rectified cam0 frame [m]
  ImageI32 segment_ids;     ///< segment id per pixel of the common area, -1 none
  int num_segments = 0;
  AnalysisResult analysis;  ///< on the cropped area
  /// Class ids at the full rectified size; 0 (unknown) outside the common area.
  ImageU8 labels;
  /// The matcher's inputs (rectified, cropped to the common area), kept for the map's sub-pixel
  /// refinement (map.subpixel_window_px > 0, stereo.subpixel_window_px 0, matched frames only);
  /// empty otherwise.
  ImageU8 left_matched, right_matched;
  Eigen::Vector3d up_rectified = Eigen::Vector3d::Zero();  ///< up in the rectified cam0 frame
  StageTimings timings;
};

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
};

/// The analysis of one frame after segmentation, as FramePipeline runs it (paper III-E and the
/// label refinements the config's analysis section turns on): AnalyzeSurfaces, per-pixel slopes,
/// ground consistency, fragment planes, and where the quality check passed the disparity face
/// test and the two fills of undecided pixels. All images are the common area's (`geometry`);
/// `up_rectified` is up in the rectified cam0 frame. (The texture mask of
/// analysis.label_min_texture needs the full image and is applied by the pipeline after it.)
AnalysisResult AnalyzeFrame(const Config& config, const RectifiedGeometry& geometry, const ImageF& disparity,
                            const Image3f& cloud, const Image3f& normals, const ImageI32& segment_ids,
                            int num_segments, const Eigen::Vector3d& up_rectified);

/// 1 where the common area (crop_width x crop_height at crop_u0, crop_v0 of the full rectified
/// left image) has texture: the grey-level standard deviation of the full image over the
/// `block` x `block` window around the pixel (clipped at the image border) is at least
/// `min_std`; 0 elsewhere. Sky and other blank areas, where matching finds noise.
ImageU8 TexturedPixels(const ImageU8& left_rectified, const RectifiedGeometry& geometry, int block, double min_std);

}  // namespace ssta
