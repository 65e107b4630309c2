#pragma once

#include <string>

#include "ssta/core/image.h"

namespace ssta {

/// Stereo matching algorithms (YAML `stereo.algorithm`).
enum class MatcherType {
  kBlockMatching,     ///< "bm": OpenCV StereoBM
  kSemiGlobal,        ///< "sgbm": OpenCV StereoSGBM
  kPclBlockBased,     ///< "pcl_bb": PCL BlockBasedStereoMatching (the paper's BB)
  kPclAdaptiveCost,   ///< "pcl_acso": PCL AdaptiveCostSOStereoMatching (the paper's ACSO)
};

/// Parses "bm", "sgbm", "pcl_bb", "pcl_acso"; throws ssta::Error otherwise.
MatcherType ParseMatcherType(const std::string& name);
std::string MatcherTypeName(MatcherType type);

/// YAML section `stereo`.
struct StereoMatcherOptions {
  MatcherType algorithm = MatcherType::kSemiGlobal;
  int min_disparity = 0;       ///< [px]
  int num_disparities = 64;    ///< search range [px], a positive multiple of 16
  int block_size = 7;          ///< matching window side [px], odd, >= 3 (>= 5 for bm)
  int uniqueness_ratio = 10;   ///< [%] best cost must beat the second best by this margin
  bool left_right_check = true;///< reject pixels whose right-to-left match disagrees
  int left_right_max_diff = 1; ///< [px] allowed disagreement of the left-right check
  int speckle_window_size = 100;  ///< [px] blobs smaller than this are removed; 0 disables
  int speckle_range = 2;          ///< [px] max disparity variation inside one blob
  // PCL matchers only.
  int pcl_ratio_filter = 20;   ///< [%] PCL ratio filter, 0 disables
  int pcl_peak_filter = 0;     ///< PCL peak filter, 0 disables
  bool pcl_preprocessing = true;  ///< PCL's x-Sobel-like image pre-processing
  int acso_smoothness_strong = 100;  ///< ACSO smoothness penalty, strong
  int acso_smoothness_weak = 20;     ///< ACSO smoothness penalty, weak
  double acso_gamma_s = 10.0;        ///< ACSO spatial bandwidth of the adaptive weights

  bool IsValid(std::string* error) const;
};

/// Computes a disparity image of the left image of a rectified pair.
/// Output: disparity in pixels (sub-pixel where the algorithm gives it), 0 where invalid.
/// Thread-safe: Compute() may run concurrently on one matcher.
class StereoMatcher {
 public:
  /// Throws ssta::Error when the options are invalid.
  explicit StereoMatcher(const StereoMatcherOptions& options);
  /// Precondition (ssta::Error): same size, at least num_disparities + block_size wide.
  ImageF Compute(const ImageU8& left, const ImageU8& right) const;
  const StereoMatcherOptions& options() const { return options_; }

 private:
  StereoMatcherOptions options_;
};

}  // namespace ssta
