#pragma once

#include <cstdint>

#include <Eigen/Core>

#include "ssta/analysis/surface_analyzer.h"
#include "ssta/core/image.h"

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
  /// The LabelRule (label_rule.h) that set each label, at the labels' size; `outside` outside
  /// the common area.
  ImageU8 rules;
  /// The matcher's inputs (rectified, cropped to the common area), kept for the map's sub-pixel
  /// refinement (map.subpixel_window_px > 0, stereo.subpixel_window_px 0, matched frames only);
  /// empty otherwise.
  ImageU8 left_matched, right_matched;
  /// [px] The matcher's block (stereo.block_size): texture is measured over this window.
  int texture_block_px = 0;
  /// [grey levels] Labels are 0 where the texture is below this (analysis.label_min_texture
  /// raised to texture_noise_floor, TextureThreshold; 0: no mask was applied).
  double labels_min_texture = 0.0;
  /// [grey levels] The left image's sensor noise (ImageNoiseSigma) times
  /// analysis.texture_noise_multiple: no texture test asks for less. 0: not measured.
  double texture_noise_floor = 0.0;
  /// The frame's stereo depth noise: a point at depth Z errs by this times Z^2 along its ray
  /// (disparity sigma / (f b)) [1/m]; 0: unknown.
  double depth_noise_per_m2 = 0.0;
  Eigen::Vector3d up_rectified = Eigen::Vector3d::Zero();  ///< up in the rectified cam0 frame
  StageTimings timings;
};

}  // namespace ssta
