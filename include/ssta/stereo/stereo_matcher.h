#pragma once

#include <string>

#include "ssta/core/option_fields.h"
#include "ssta/core/image.h"

namespace ssta {

/// Stereo matching algorithms (YAML `stereo.algorithm`).
enum class MatcherType {
  kBlockMatching,     ///< "bm": OpenCV StereoBM
  kSemiGlobal,        ///< "sgbm": OpenCV StereoSGBM
  kPclBlockBased,     ///< "pcl_bb": PCL BlockBasedStereoMatching (the paper's BB)
  kPclAdaptiveCost,   ///< "pcl_acso": PCL AdaptiveCostSOStereoMatching (the paper's ACSO)
};

/// OpenCV StereoSGBM's cost aggregation (YAML `stereo.sgbm_mode`).
enum class SgbmMode {
  kThreeWay,  ///< "3way": 3 directions per pass, fastest (OpenCV MODE_SGBM_3WAY)
  kFive,      ///< "sgbm": 5 directions, single pass (MODE_SGBM)
  kHh4,       ///< "hh4": 4 directions, two passes (MODE_HH4)
  kHh,        ///< "hh": 8 directions, two passes, full-image cost volume (MODE_HH)
};
/// Parses "3way", "sgbm", "hh4", "hh"; throws ssta::Error otherwise.
SgbmMode ParseSgbmMode(const std::string& name);
std::string SgbmModeName(SgbmMode mode);

/// Parses "bm", "sgbm", "pcl_bb", "pcl_acso"; throws ssta::Error (message starts with
/// "algorithm:") otherwise.
MatcherType ParseMatcherType(const std::string& name);
/// The YAML name of `type` (inverse of ParseMatcherType).
std::string MatcherTypeName(MatcherType type);

/// 1 where `image` has texture in the area of w x h pixels at (u0, v0): the grey-level standard
/// deviation over the `block` x `block` window around the pixel (clipped at the image border,
/// which may lie outside the area) is at least `min_std`; 0 elsewhere. Exact (64-bit integral
/// images). The mask of `stereo.min_texture` and of `map.min_texture`.
ImageU8 TextureMask(const ImageU8& image, int u0, int v0, int w, int h, int block, double min_std);

/// The standard deviation of `image`'s sensor noise [grey levels], estimated from the image
/// itself (Immerkaer, "Fast noise variance estimation", 1996): the mask [1 -2 1; -2 4 -2;
/// 1 -2 1] cancels every grey level that is locally planar, and its response to white noise of
/// sigma has mean absolute value sqrt(2 / pi) 6 sigma. Texture and edges only add to the
/// response, and the noise is the same everywhere, so the estimate is the 10th percentile over
/// the 32 x 32 px tiles (tiles without any response, clipped or blank, are left out), which
/// lies about 5 % below the noise (the tiles' own scatter). 0 when no tile has a response, or
/// the image is smaller than a tile.
double ImageNoiseSigma(const ImageU8& image);

/// Refines `disparity` (of `left` against `right`, all three the same size; 0 = none) to
/// sub-pixel precision in place: the refinement of StereoMatcherOptions::subpixel_window_px
/// with a `window` x `window` window (odd, >= 1) and `iterations` Gauss-Newton steps (the
/// matcher takes 2). Used by the matcher with that option, and on its own for the map's points
/// (map.subpixel_window_px, 1 step: a second moved no map figure, docs/accuracy.md). With
/// `surface_ids` (same size; e.g. segment ids, -1 none), only pixels whose whole window lies in
/// one id >= 0 are refined: the refinement assumes one smooth surface per window. Sizes that
/// differ or a bad window are broken preconditions (ssta::InternalError).
void RefineDisparitySubpixel(const ImageU8& left, const ImageU8& right, int window, int iterations,
                             ImageF* disparity, const ImageI32* surface_ids = nullptr);

/// YAML section `stereo`.
struct StereoMatcherOptions {
  MatcherType algorithm = MatcherType::kSemiGlobal;
  int min_disparity = 0;       ///< smallest disparity searched [px], >= 0
  int num_disparities = 64;    ///< search range [px], a positive multiple of 16
  /// A pipeline (FramePipeline) widens num_disparities to the largest disparity of level ground
  /// in view of its rig, from cam0's mount and the rectified focal length and baseline
  /// (AutoNumDisparities); the matcher itself uses num_disparities as it is.
  bool auto_num_disparities = true;
  /// [px] 1-sigma of the disparity the matcher delivers on textured surfaces: the stereo noise
  /// model. A point at depth Z has a depth sigma of Z^2 sigma_d / (f b); the map's range, its
  /// height fusion and the ground plane's quality check follow from it.
  double disparity_sigma_px = 0.25;
  int block_size = 9;          ///< matching window side [px], odd, >= 3 (>= 5 for bm); for
                               ///< pcl_acso the length of the aggregation column
  SgbmMode sgbm_mode = SgbmMode::kThreeWay;  ///< sgbm only: cost aggregation directions
  /// sgbm only: SGBM's smoothness penalties per pixel of the matching window. A disparity step
  /// of 1 px between neighbours costs sgbm_p1 * block_size^2 (OpenCV's P1), a larger jump
  /// sgbm_p2 * block_size^2 (P2, > P1). Higher values give smoother, denser disparities and
  /// blur small objects into their background. 8 and 32 are OpenCV's usual grey-image values;
  /// what others do on real road images is in docs/performance.md.
  int sgbm_p1 = 8;
  int sgbm_p2 = 32;  ///< see sgbm_p1; must exceed it
  int uniqueness_ratio = 10;   ///< [%] bm/sgbm: best cost must beat the second best by this margin
  bool left_right_check = true;///< reject pixels whose right-to-left match disagrees (SGBM: always)
  int left_right_max_diff = 1; ///< [px] allowed disagreement of the left-right check (SGBM: >= 1)
  int speckle_window_size = 100;  ///< [px] blobs smaller than this are removed (all); 0 disables
  int speckle_range = 2;          ///< [px] max disparity step between neighbours of one blob
  /// [grey levels] pixels whose left-image standard deviation over the block window is below
  /// this get no disparity: sensor noise on a textureless sky or wall matches anywhere. 0: off.
  double min_texture = 0.0;
  /// [px] pixels this close to the left or right image border, or whose partner lies this close
  /// to the right image's left border, get no disparity: the two matching windows run off their
  /// images at different columns there (and SGBM's horizontal paths start there), so the
  /// disparities are biased. The top and bottom rows keep theirs: rows are epipolar lines, both
  /// windows see the same padding. 0: off.
  int border_margin = 4;
  /// [px, odd] sub-pixel refinement window (0: off). Matchers interpolate a parabola through
  /// three costs, which pulls disparities towards whole pixels ("pixel locking"): far ground
  /// becomes terraces. Refinement (two steps) warps the right image by each pixel's disparity
  /// (linear interpolation), takes each pixel's Gauss-Newton correction of the grey-level
  /// residual, and sets the disparity to the window's mean disparity plus the window's mean
  /// correction weighted by the squared image gradient (box filters: O(1) per pixel; the plain
  /// mean keeps a slanted surface unbiased where the weights are uneven). Windows spanning more
  /// than 1 px of disparity or a hole, and results more than 1 px off, keep the matcher's value.
  /// Measured in docs/accuracy.md: disparity error /2 to /3, per-frame classes slightly lower.
  int subpixel_window_px = 0;
  // PCL matchers only.
  /// [%] ratio filter: reject a pixel whose best window cost (sum of absolute differences,
  /// block_size window) is not below (100 - value)% of the best cost at least 2 px away;
  /// 0 disables. Applied by SSTA, not PCL, because PCL 1.13's filter crashes at the ends of
  /// the range. For pcl_acso it tests the local window cost, not the optimised one.
  int pcl_ratio_filter = 20;
  int pcl_peak_filter = 0;     ///< PCL peak filter (cost curvature threshold), 0 disables
  bool pcl_preprocessing = true;  ///< PCL's local mean removal (9x9) and clamping of both images
  int acso_smoothness_strong = 100;  ///< ACSO smoothness penalty for jumps > 1 px, >= weak
  int acso_smoothness_weak = 20;     ///< ACSO smoothness penalty for 1 px steps
  double acso_gamma_s = 10.0;        ///< ACSO spatial bandwidth of the adaptive weights [px],
                                     ///< a whole number (PCL takes an int)
  double acso_gamma_c = 25.0;        ///< ACSO grey-level bandwidth of the adaptive weights,
                                     ///< a whole number (PCL takes an int)
  /// 1: match at full resolution. 2: match both images at half size (area average), with the
  /// disparity range, block, speckle window and speckle range halved (the range rounded up to
  /// a multiple of 16, the block kept odd and >= the matcher's minimum), then give each full-
  /// resolution pixel twice the disparity interpolated bilinearly from the four nearest
  /// half-size pixels where they agree within 1 px, else twice its own half-size pixel's (no
  /// value blends across an edge). About 4 to 8 times faster; what it costs in accuracy is in
  /// docs/performance.md. min_texture applies at full resolution.
  int downscale = 1;

  /// Every field: its key, unit, range and meaning (reading, writing and IsValid come from it).
  static const OptionFields<StereoMatcherOptions>& Fields();
  /// The first field out of its range, as "key: requirement" in `*error`.
  bool IsValid(std::string* error) const;
};

/// Computes a disparity image of the left image of a rectified pair.
/// Output: disparity in pixels (sub-pixel where the algorithm gives it; 1/16 px steps), 0 where
/// invalid: not matched, rejected by a filter, or u < min_disparity + num_disparities for the
/// PCL matchers (search range outside the right image). The PCL matchers cannot report the
/// smallest disparity of the range (PCL stores it as 0 = invalid).
/// Thread-safe: Compute() may run concurrently on one matcher (each call builds its own
/// OpenCV / PCL matcher object).
class StereoMatcher {
 public:
  /// Throws ssta::Error (the IsValid message) when the options are invalid.
  explicit StereoMatcher(const StereoMatcherOptions& options);
  /// Precondition (ssta::Error naming the sizes): same size, at least
  /// min_disparity + num_disparities + block_size wide and block_size high.
  ImageF Compute(const ImageU8& left, const ImageU8& right) const;
  const StereoMatcherOptions& options() const { return options_; }

 private:
  ImageF ComputeAtHalfSize(const ImageU8& left, const ImageU8& right) const;
  StereoMatcherOptions options_;
};

}  // namespace ssta
