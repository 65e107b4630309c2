// The only translation unit that includes PCL (its stereo headers pull in much of pcl_common).
#include "pcl_stereo.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <vector>

#include <pcl/stereo/stereo_matching.h>

#include "ratio_filter.h"
#include "ssta/core/error.h"

namespace ssta::internal {
namespace {

/// Reads the protected results of a PCL matcher. PCL 1.13 keeps them in plain arrays:
/// - disp_map_: width*height shorts, disparity * 16 (4 fractional bits from PCL's parabola
///   sub-pixel fit), in the frame of the images passed to compute(), x offset already added.
///   Values <= 0 are invalid: 0 (not computed, or disparity index 0 — PCL cannot tell these
///   apart), -2*16 (ratio filter), -4*16 (peak filter), -8 (left-right check).
/// - pp_ref_img_ / pp_trg_img_: the pre-processed images (only when pre-processing is on).
template <class Matcher>
class Exposed : public Matcher {
 public:
  const short* disparity16() const { return this->disp_map_; }
  const unsigned char* preprocessed_left() const { return this->pp_ref_img_; }
  const unsigned char* preprocessed_right() const { return this->pp_trg_img_; }
};

ImageU8 FromBuffer(const unsigned char* data, int width, int height) {
  ImageU8 out(width, height);
  std::copy(data, data + out.size(), out.data());
  return out;
}

/// Mirrors the columns: the right-to-left pass matches the mirrored right image against the
/// mirrored left one, so that disparities stay positive (as PCL's own left-right check does).
ImageU8 Mirror(const ImageU8& image) {
  ImageU8 out(image.width(), image.height());
  for (int v = 0; v < image.height(); ++v) {
    std::reverse_copy(image.row(v), image.row(v) + image.width(), out.row(v));
  }
  return out;
}

/// One PCL matching pass of `ref` against `trg` (disparity index d: ref(u) ~ trg(u - d)) with
/// PCL's ratio filter and left-right check off; our ratio filter then marks the pixels it
/// rejects with -1. Returns PCL's fixed-point map (see Exposed).
template <class Matcher, class Configure>
std::vector<short> RunPass(const ImageU8& ref, const ImageU8& trg,
                           const StereoMatcherOptions& options, int radius,
                           const Configure& configure) {
  const int w = ref.width();
  const int h = ref.height();
  const int num = options.num_disparities;
  Exposed<Matcher> matcher;
  configure(matcher);
  matcher.setMaxDisparity(num);
  matcher.setXOffset(0);
  // PCL 1.13's ratio filter (pcl::doStereoRatioFilter) takes std::min_element over
  // [acc, acc + dbest - 1) and [acc + dbest + 2, acc + maxdisp). When the best index is 0 the
  // first range has last < first; when it is maxdisp - 1 the second has; min_element then walks
  // off the cost array until it faults. Index 0 is common: in a textureless area every cost
  // ties and the first (index 0) wins. With dbest = 1 or maxdisp - 2 the empty range's end is
  // dereferenced (the neighbour acc[0], or one past the array). Padding the range cannot avoid
  // this (the best can still land on the padded ends, and index 0 cannot be padded when the
  // range starts at 0), so PCL's filter stays off and the same test runs afterwards on our own,
  // bounds-safe cost curve (ApplyRatioFilter), for BB on exactly the cost PCL minimised.
  matcher.setRatioFilter(0);
  matcher.setPeakFilter(options.pcl_peak_filter);
  matcher.setPreProcessing(options.pcl_preprocessing);
  // PCL's own left-right check rejects every pixel whose partner lies in the right image's
  // last num_disparities columns, which its right-to-left pass never computes (a strip as wide
  // as the search range minus the disparity). ComputePclDisparity checks instead, skipping
  // those partners as OpenCV does.
  matcher.setLeftRightCheck(false);
  // compute() takes non-const pointers: give it copies.
  std::vector<unsigned char> a(ref.data(), ref.data() + ref.size());
  std::vector<unsigned char> b(trg.data(), trg.data() + trg.size());
  matcher.compute(a.data(), b.data(), w, h);
  SSTA_CHECK(matcher.disparity16() != nullptr, "PCL stereo matcher produced no disparity map");
  std::vector<short> disp16(matcher.disparity16(), matcher.disparity16() + a.size());
  if (options.pcl_ratio_filter <= 0) return disp16;

  // The sub-pixel fit moves a value by at most half a pixel towards the better neighbour, so
  // (s + 7) / 16 recovers PCL's integer best index.
  ImageI32 index(w, h, -1);
  for (std::size_t i = 0; i < disp16.size(); ++i) {
    if (disp16[i] > 0) index[i] = std::min((disp16[i] + 7) / 16, num - 1);
  }
  const bool pre = matcher.preprocessed_left() != nullptr && options.pcl_preprocessing;
  ApplyRatioFilter(pre ? FromBuffer(matcher.preprocessed_left(), w, h) : ref,
                   pre ? FromBuffer(matcher.preprocessed_right(), w, h) : trg, radius, num, 0,
                   options.pcl_ratio_filter, &index);
  for (std::size_t i = 0; i < disp16.size(); ++i) {
    if (disp16[i] > 0 && index[i] < 0) disp16[i] = -1;
  }
  return disp16;
}

template <class Matcher, class Configure>
ImageF Run(const ImageU8& left, const ImageU8& right, const StereoMatcherOptions& options,
           int radius, int first_column, const Configure& configure) {
  const int w = left.width();
  const int h = left.height();
  const int x0 = options.min_disparity;
  const int num = options.num_disparities;

  // PCL's own x offset (setXOffset) is left at 0 and the right image is shifted here instead:
  // AdaptiveCostSOStereoMatching starts its columns at max_disp + 1 without adding the offset,
  // so with an offset it reads right-image pixels from the previous row. Shifting by x0
  // (right'(u) = right(u - x0), edge replicated) makes index d mean disparity x0 + d for both.
  ImageU8 shifted(w, h);
  for (int v = 0; v < h; ++v) {
    const std::uint8_t* src = right.row(v);
    std::uint8_t* dst = shifted.row(v);
    for (int u = 0; u < w; ++u) dst[u] = src[std::max(u - x0, 0)];
  }
  std::vector<short> disp16 = RunPass<Matcher>(left, shifted, options, radius, configure);

  if (options.left_right_check) {
    // Right-to-left pass on the mirrored pair: right pixel ur sits at mirrored column w-1-ur.
    const std::vector<short> mirrored =
        RunPass<Matcher>(Mirror(shifted), Mirror(left), options, radius, configure);
    const auto whole = [](short s) { return static_cast<int>(std::lround(s / 16.0)); };
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) {
        short& s = disp16[static_cast<std::size_t>(v) * w + u];
        if (s <= 0) continue;
        const int p1 = whole(s);
        const int ur = u - p1;
        const int um = w - 1 - ur;
        if (ur < 0 || um < first_column) continue;  // the right pass has no value there
        const short sr = mirrored[static_cast<std::size_t>(v) * w + um];
        // sr == 0 is PCL's index 0; sr < 0 is a pixel one of the filters rejected.
        const int p2 = sr >= 0 ? whole(sr) : -(num + 1 + options.left_right_max_diff);
        if (std::abs(p1 - p2) > options.left_right_max_diff) s = -8;
      }
    }
  }

  ImageF out(w, h, 0.0f);
  for (int v = 0; v < h; ++v) {
    for (int u = x0 + num; u < w; ++u) {
      const short s = disp16[static_cast<std::size_t>(v) * w + u];
      if (s > 0) out(v, u) = static_cast<float>(x0) + static_cast<float>(s) / 16.0f;
    }
  }
  return out;
}

}  // namespace

ImageF ComputePclDisparity(const ImageU8& left, const ImageU8& right,
                           const StereoMatcherOptions& options) {
  SSTA_CHECK(left.width() == right.width() && left.height() == right.height(),
             "ComputePclDisparity: images differ in size");
  const int radius = options.block_size / 2;
  const int num = options.num_disparities;
  // First column each PCL algorithm computes (its loops start there): BB needs its whole window
  // and search range inside the image, ACSO only the search range.
  if (options.algorithm == MatcherType::kPclBlockBased) {
    return Run<pcl::BlockBasedStereoMatching>(
        left, right, options, radius, num + radius + 1,
        [radius](pcl::BlockBasedStereoMatching& m) { m.setRadius(radius); });
  }
  SSTA_CHECK(options.algorithm == MatcherType::kPclAdaptiveCost,
             "ComputePclDisparity: not a PCL algorithm");
  return Run<pcl::AdaptiveCostSOStereoMatching>(
      left, right, options, radius, num + 1, [&options, radius](pcl::AdaptiveCostSOStereoMatching& m) {
        m.setRadius(radius);
        m.setGammaS(static_cast<int>(std::lround(options.acso_gamma_s)));
        m.setGammaC(static_cast<int>(std::lround(options.acso_gamma_c)));
        m.setSmoothStrong(options.acso_smoothness_strong);
        m.setSmoothWeak(options.acso_smoothness_weak);
      });
}

}  // namespace ssta::internal
