#pragma once

#include <algorithm>
#include <string>

#include <Eigen/Core>

#include "ssta/analysis/label_refinements.h"
#include "ssta/analysis/label_rule.h"
#include "ssta/analysis/surface_analyzer.h"
#include "ssta/core/image.h"
#include "ssta/core/option_fields.h"
#include "ssta/stereo/rectifier.h"

namespace ssta {

/// YAML section `analysis`: the whole SSTA stage after segmentation (paper section III-E), one
/// section for users. The code reads its halves: AnalyzeSurfaces the paper's analysis
/// (SurfaceAnalysisOptions), the label refinements their own (LabelRefinementOptions). The
/// YAML keys and their order in written files follow Fields().
struct AnalysisOptions : SurfaceAnalysisOptions, LabelRefinementOptions {
  /// Every field: its key, unit, range and meaning (reading, writing and IsValid come from it).
  static const OptionFields<AnalysisOptions>& Fields();
  /// The first field out of its range, as "key: requirement" in `*error`.
  bool IsValid(std::string* error) const;
};

/// What the stages before the analysis produced for one frame, all on the rectified common
/// area (`geometry`'s crop) and in the rectified cam0 frame.
struct FrameAnalysisInput {
  const RectifiedGeometry* geometry = nullptr;  ///< focal length, principal point, baseline
  const ImageF* disparity = nullptr;            ///< [px], 0 invalid
  const Image3f* cloud = nullptr;               ///< organized points [m], NaN invalid
  const Image3f* normals = nullptr;             ///< unit normals per pixel, NaN where none
  const ImageI32* segment_ids = nullptr;        ///< segment per pixel in [0, num_segments), -1 none
  int num_segments = 0;
  Eigen::Vector3d up_rectified = Eigen::Vector3d::Zero();  ///< unit up in the rectified cam0 frame
  /// Optional, of the cloud's size: 0 where a point has no support in the image
  /// (SupportedPixels); the local steps leave such points out of their height grid. nullptr:
  /// every point is used.
  const ImageU8* supported = nullptr;
};

/// The analysis of one frame after segmentation: the paper's SSTA (AnalyzeSurfaces, eq. 2-5;
/// surface_analyzer.h) followed by the label refinements the analysis options turn on
/// (label_refinements.h), in this order:
///   1. per-pixel slopes (RefineByPixelSlope),
///   2. ground consistency (RefineByGroundDisparity),
///   3. fragments on a neighbour's plane (RefineByFragmentPlanes),
///   4. steps within the step radius of each point (RefineByLocalSteps; step_reference local),
///   5. thin faces from the disparity (RefineByDisparityFaces),
///   6. undecided pixels amid a consensus (FillUndecidedByConsensus),
///   7. undecided pixels by their own height (FillUndecidedByHeight),
///   8. the lips of drop-offs whose foot the frame cannot see (ApplyHiddenDrops),
///   9. the band of a jump that depth noise keeps the frame from placing (ApplySmearedStepBand).
/// Steps 1 and 4-9 run only on a frame that passed the quality check. The costly parts of
/// steps 1, 4, 5 and 8 read inputs no other step changes; they run beside the steps before them, and
/// their results are applied at their places in the chain, so the labels are those of the steps
/// one after the other (the texture mask of analysis.label_min_texture needs the full image and
/// is applied by FramePipeline after this). AnalysisResult::rules names the step that set each
/// pixel's class (LabelRule).
/// Not thread-safe: Analyze reuses the analyzer's buffers; use one analyzer per thread.
class FrameAnalyzer {
 public:
  /// Throws ssta::Error naming the key when `vehicle` or `options` is invalid.
  /// `disparity_sigma_px` (stereo.disparity_sigma_px) is the matcher's noise, from which each
  /// frame's depth noise follows with its focal length and baseline; `match_window_px` the side
  /// of its window at full resolution (stereo.block_size x stereo.downscale), over which
  /// neighbouring pixels share their error (DepthNoise::window_px). `hidden_drop_range_m`: the
  /// range within which a floor below a column's last point would have been seen (the map's,
  /// MappingOptions::FusionFor), for the lips of step 8; 0: such columns mark no lip.
  FrameAnalyzer(const VehicleOptions& vehicle, const AnalysisOptions& options, double disparity_sigma_px = 0.25,
                int match_window_px = 1, double hidden_drop_range_m = 0.0);

  /// Precondition: every input is set and of the cloud's size.
  AnalysisResult Analyze(const FrameAnalysisInput& input);

 private:
  /// The steps after the two lanes of a judged frame, in order: local steps, faces, consensus
  /// fill, height fill, lips.
  void ApplyAfterBoth(const FrameAnalysisInput& in, AnalysisResult* a);

  VehicleOptions vehicle_;
  AnalysisOptions options_;
  double disparity_sigma_px_;
  int match_window_px_;
  double hidden_drop_range_m_;
  ImageU8 slope_classes_;   // step 1's classes, kept between frames
  DisparityFaces faces_;    // step 4's faces, kept between frames
  ImageU8 step_classes_;    // the local steps' classes, kept between frames
  ImageU8 lips_;            // step 8's lip mask (FindHiddenDrops), until it joins the result
  LabelRuleTracker rule_tracker_;  // the labels before each step, for AnalysisResult::rules
};

/// The grey levels a texture test asks for in a frame: its configured `min_std`, raised to the
/// frame's noise floor (FrameResult::texture_noise_floor); a test that is off (0) stays off.
inline double TextureThreshold(double min_std, double noise_floor) {
  return min_std > 0.0 ? std::max(min_std, noise_floor) : 0.0;
}

/// 1 where the common area (crop_width x crop_height at crop_u0, crop_v0 of the full rectified
/// left image) has texture: the grey-level standard deviation of the full image over the
/// `block` x `block` window around the pixel (clipped at the image border) is at least
/// `min_std`; 0 elsewhere. Sky and other blank areas, where matching finds noise.
ImageU8 TexturedPixels(const ImageU8& left_rectified, const RectifiedGeometry& geometry, int block, double min_std);

/// 1 where a pixel of the common area has a disparity its surroundings support: texture
/// (TexturedPixels) or, without it, a ray that points below the horizon (`up_rectified`: up in
/// the rectified cam0 frame), where a blank surface is a surface (far ground loses its texture
/// with range); 0 above the horizon without texture: the sky, where matching finds noise.
ImageU8 SupportedPixels(const ImageU8& left_rectified, const RectifiedGeometry& geometry, int block, double min_std,
                        const Eigen::Vector3d& up_rectified);

/// SupportedPixels judged with the disparity (the common area's, [px], 0 invalid), column by
/// column from the bottom up against the closest valid pixel within 32 rows below:
/// - a floating piece of the matcher's noise is not supported: on a run of one surface (each
///   pixel's disparity within max(1 px, 10 %) of the one below) that begins nearer than the pixel
///   below it (its disparity larger by more than that), it starts at the first pixel below the
///   horizon without texture along its row (the standard deviation along the rows of the block,
///   pooled, below `min_std`: a horizontal edge fixes no disparity) and takes the rest of the
///   run below the horizon, with or without texture. (Above the horizon a leaning trunk crosses a column above the far ground
///   it hides nothing of; points there are above the camera.) A surface standing on the ground is
///   never nearer than what is seen just below it; in a blank band near the horizon the matcher
///   finds disparities of nearby things hanging in the air above far ground;
/// - a pixel without texture above the horizon is supported where it continues a supported
///   surface below it (its disparity within max(1 px, 5 %) of the one below) and lies near
///   enough for its depth to be known to 5 % (disparity >= 5 px): a blank wall above a textured
///   base or window, not a blank sky.
ImageU8 SupportedPixels(const ImageU8& left_rectified, const RectifiedGeometry& geometry, int block, double min_std,
                        const Eigen::Vector3d& up_rectified, const ImageF& disparity);

}  // namespace ssta
