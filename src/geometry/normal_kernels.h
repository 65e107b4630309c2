#pragma once

// Private: what NormalEstimator's methods share (normal_estimator.cpp, normal_covariance.cpp,
// normal_average_3d_gradient.cpp, normal_average_depth_change.cpp): the limits, the box sums over
// integral rows and strips, the row loop over full-radius windows, and the estimator's buffers.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core/utility.hpp>

#include "geometry/integral_row_ring.h"
#include "geometry/smallest_eigenvector.h"
#include "ssta/core/error.h"
#include "ssta/geometry/normal_estimator.h"

namespace ssta {
namespace normals {

constexpr int kMinSmoothingSizePx = 3;
constexpr int kMaxSmoothingSizePx = 201;  // radius 100, x2 with depth-dependent smoothing fits u8
constexpr int kMinRadiusPx = 1;           // 3 x 3 is the smallest window that yields a normal
// A window (or each half-window of the gradient methods) needs this fraction of valid points.
constexpr double kMinValidFraction = 0.25;
constexpr int kMinBandRows = 32;  // rows per band at least, when the sweep runs on several threads
// Depth-dependent smoothing: side = smoothing_size_px * sqrt(Z / kReferenceDepthM), clamped.
constexpr double kReferenceDepthM = 5.0;
constexpr double kMinDepthScale = 0.5;
constexpr double kMaxDepthScale = 2.0;
// Covariance sums use fixed point so that their precision does not depend on how far the rest
// of the frame lies: a window's sums of squared coordinates must stay below this (2^62). The
// quantum is then max|coordinate| * (2r+1) / 2.1e9: 0.12 um for a 13 x 13 window and points up
// to 20 m, 3 um with a stereo outlier at 500 m (3 x 3 windows at 1.5 m span 1 cm).
constexpr double kMaxWindowSumOfSquares = 4.6e18;
// The gradient methods sum first-order values in 64-bit fixed point: a window's sum of
// |quantised value| must stay below 2^51 (exact, vectorisable conversion to double). The
// quantum is then max|value| * (2r+1)^2 / 2.2e15: far below float precision.
constexpr double kMaxWindowSum64 = 2.2e15;
// Covariance windows whose lambda2 * lambda3 / trace^2 is below this are (nearly) collinear.
constexpr float kMinRank2Float = 1e-6f;


inline bool IsValidPoint(const Eigen::Vector3f& p) {
  return p.z() > 0.0f && std::isfinite(p.z()) && std::isfinite(p.x()) && std::isfinite(p.y());
}

// Sum over rows [top, bottom) and columns [c0, c1) of channel k of channel-planar integral
// rows `top`, `bottom` (planes `plane` apart), as a signed value: the unsigned sums wrap, the
// box fits.
template <typename S, typename T>
inline S BoxSum(const T* top, const T* bottom, std::size_t plane, int c0, int c1, int k) {
  const std::size_t o = plane * k;
  const T sum = static_cast<T>(bottom[o + c1] - bottom[o + c0] - top[o + c1] + top[o + c0]);
  return static_cast<S>(sum);
}

inline int MinCount(int area) {
  return std::max(3, static_cast<int>(std::ceil(kMinValidFraction * area)));
}

// Minimum valid points per radius r = 0..max_radius, for the full window and for a half.
struct MinCounts {
  std::vector<int> full, half;
  explicit MinCounts(int max_radius) {
    for (int r = 0; r <= max_radius; ++r) {
      full.push_back(MinCount((2 * r + 1) * (2 * r + 1)));
      half.push_back(MinCount(r * (2 * r + 1)));
    }
  }
};

// Vertical strip sums: out[i] = bottom[i] - top[i] over a whole integral row (wrapping), so
// that a box over the rows between them and columns [c0, c1) is out[c1] - out[c0]. Computed
// once per output row for the full radius, which most pixels use.
template <typename T>
inline void StripSums(const T* top, const T* bottom, std::size_t n, T* out) {
  for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<T>(bottom[i] - top[i]);
}

// Channel k of the box over columns [c0, c1) of a channel-planar strip, signed.
template <typename S, typename T>
inline S StripBox(const T* strip, std::size_t plane, int c0, int c1, int k) {
  const std::size_t o = plane * k;
  return static_cast<S>(static_cast<T>(strip[o + c1] - strip[o + c0]));
}

// Row kernels take __restrict pointers so that the compiler vectorises their loops; GCC drops
// __restrict when such a function is inlined into its caller, so they stay out of line.
#if defined(__GNUC__)
#define SSTA_NOINLINE __attribute__((noinline))
#else
#define SSTA_NOINLINE
#endif


// double of a two's-complement integer |x| < 2^51 given as uint64, cheaper still: add the bits
// of 1.5 * 2^52 and subtract it as a double. Vectorises.
inline double Int52ToDouble(std::uint64_t x) {
  constexpr std::uint64_t kMagicBits = 0x4338000000000000ull;  // 1.5 * 2^52
  constexpr double kMagic = 6755399441055744.0;
  const std::uint64_t bits = x + kMagicBits;
  double d;
  std::memcpy(&d, &bits, sizeof d);
  return d - kMagic;
}

// Writes the unit normal oriented towards the camera, or NaN (and radius 0) for a zero vector.
inline void FinishNormal(const Eigen::Vector3f& n, const Eigen::Vector3f& p, Eigen::Vector3f* out,
                         std::uint8_t* radius) {
  const float squared_norm = n.squaredNorm();
  if (*radius == 0 || !(squared_norm > 0.0f) || !std::isfinite(squared_norm)) {
    *out = NanVector3f();
    *radius = 0;
    return;
  }
  const float sign = n.dot(p) > 0.0f ? -1.0f : 1.0f;
  *out = n * (sign / std::sqrt(squared_norm));
}

// Runs body(band, v_begin, v_end) for each band of rows [rows[k], rows[k + 1]), the bands on
// OpenCV's threads.
template <typename Body>
void ForEachBand(const std::vector<int>& rows, const Body& body) {
  const int num_bands = static_cast<int>(rows.size()) - 1;
  auto run = [&](int band) {
    const int v_begin = rows[static_cast<std::size_t>(band)];
    const int v_end = rows[static_cast<std::size_t>(band) + 1];
    if (v_end > v_begin) body(band, v_begin, v_end);
  };
  if (num_bands == 1) {
    run(0);
    return;
  }
  cv::parallel_for_(
      cv::Range(0, num_bands),
      [&](const cv::Range& range) {
        for (int band = range.start; band < range.end; ++band) run(band);
      },
      num_bands);
}

// Box sums over the full window (w) and its four halves (l, r, t, b: left/right of the centre
// column, above/below the centre row) of a 4-channel quantity, as floats.
struct HalfSums {
  float l[4], r[4], t[4], b[4], w[4];
};

// Half and full window sums of pixel u at radius r from integral rows (generic path).
inline HalfSums HalfSumsFromRows(const std::uint64_t* top, const std::uint64_t* middle_top,
                                 const std::uint64_t* middle_bottom, const std::uint64_t* bottom,
                                 std::size_t plane, int u, int r) {
  HalfSums s;
  for (int k = 0; k < 4; ++k) {
    s.l[k] = static_cast<float>(BoxSum<std::int64_t>(top, bottom, plane, u - r, u, k));
    s.r[k] = static_cast<float>(BoxSum<std::int64_t>(top, bottom, plane, u + 1, u + r + 1, k));
    s.t[k] = static_cast<float>(BoxSum<std::int64_t>(top, middle_top, plane, u - r, u + r + 1, k));
    s.b[k] =
        static_cast<float>(BoxSum<std::int64_t>(middle_bottom, bottom, plane, u - r, u + r + 1, k));
    s.w[k] = static_cast<float>(BoxSum<std::int64_t>(top, bottom, plane, u - r, u + r + 1, k));
  }
  return s;
}

// Channel planes of the full-radius strips of one output row: plane k of strip `full` holds
// channel k of (integral row v + R + 1) - (integral row v - R) for columns 0..width, etc.
struct PlanarStrips {
  const std::uint64_t* full[4];
  const std::uint64_t* upper[4];  // rows v - R .. v - 1
  const std::uint64_t* lower[4];  // rows v + 1 .. v + R
};

// Fills the three strips (each 4 planes x (width + 1)) from channel-planar integral rows.
inline PlanarStrips MakePlanarStrips(const std::uint64_t* top, const std::uint64_t* middle_top,
                                     const std::uint64_t* middle_bottom,
                                     const std::uint64_t* bottom, std::size_t plane,
                                     std::uint64_t* storage) {
  const std::size_t row_size = 4 * plane;
  std::uint64_t* full = storage;
  std::uint64_t* upper = full + row_size;
  std::uint64_t* lower = upper + row_size;
  StripSums(top, bottom, row_size, full);
  StripSums(top, middle_top, row_size, upper);
  StripSums(middle_bottom, bottom, row_size, lower);
  PlanarStrips strips;
  for (int k = 0; k < 4; ++k) {
    strips.full[k] = full + plane * k;
    strips.upper[k] = upper + plane * k;
    strips.lower[k] = lower + plane * k;
  }
  return strips;
}

// Sum over columns [a, b) of a strip plane, as a float.
inline float PlaneBox(const std::uint64_t* plane, int a, int b) {
  return static_cast<float>(Int52ToDouble(plane[b] - plane[a]));
}

// Runs pixel(u, l, r, t, b, w) for the pixels [begin, end) of a row whose window has the full
// radius `r`, with the box sums of 4 channels over the window's halves (l, r, t, b as in
// HalfSums) and the whole window (w) read from `strips`. The strip planes are __restrict here,
// once for every method; `pixel` is inlined into this out-of-line loop, which the compiler then
// vectorises.
template <typename Pixel>
SSTA_NOINLINE void StripRow(int begin, int end, int r, const PlanarStrips& strips, Pixel pixel) {
  const std::uint64_t* __restrict f0 = strips.full[0];
  const std::uint64_t* __restrict f1 = strips.full[1];
  const std::uint64_t* __restrict f2 = strips.full[2];
  const std::uint64_t* __restrict f3 = strips.full[3];
  const std::uint64_t* __restrict p0 = strips.upper[0];
  const std::uint64_t* __restrict p1 = strips.upper[1];
  const std::uint64_t* __restrict p2 = strips.upper[2];
  const std::uint64_t* __restrict p3 = strips.upper[3];
  const std::uint64_t* __restrict q0 = strips.lower[0];
  const std::uint64_t* __restrict q1 = strips.lower[1];
  const std::uint64_t* __restrict q2 = strips.lower[2];
  const std::uint64_t* __restrict q3 = strips.lower[3];
  for (int u = begin; u < end; ++u) {
    const int a = u - r, b = u + r + 1;
    const float l[4] = {PlaneBox(f0, a, u), PlaneBox(f1, a, u), PlaneBox(f2, a, u),
                        PlaneBox(f3, a, u)};
    const float rr[4] = {PlaneBox(f0, u + 1, b), PlaneBox(f1, u + 1, b), PlaneBox(f2, u + 1, b),
                         PlaneBox(f3, u + 1, b)};
    const float t[4] = {PlaneBox(p0, a, b), PlaneBox(p1, a, b), PlaneBox(p2, a, b),
                        PlaneBox(p3, a, b)};
    const float bt[4] = {PlaneBox(q0, a, b), PlaneBox(q1, a, b), PlaneBox(q2, a, b),
                         PlaneBox(q3, a, b)};
    const float w[4] = {PlaneBox(f0, a, b), PlaneBox(f1, a, b), PlaneBox(f2, a, b),
                        PlaneBox(f3, a, b)};
    pixel(u, l, rr, t, bt, w);
  }
}

}  // namespace normals

// What one sweep over a band of output rows needs for itself: its integral rows start at the
// band (IntegralRowRing's first_row), so bands run on separate threads and give exactly the
// normals of one sweep over the whole image.
struct NormalEstimator::Band {
  internal::IntegralRowRing<std::uint64_t, 10> covariance_rows;
  internal::IntegralRowRing<std::uint64_t, 4> first_order_rows;
  std::vector<float> row_soa;             // per-row structure of arrays
  std::vector<std::uint64_t> strip_u64;   // full-radius strip sums of the current row
  std::vector<std::uint64_t> strips_u64;  // full, top-half and bottom-half strips
};

struct NormalEstimator::Buffers {
  Image3f normals;
  ImageU8 radius;                            // per-pixel window radius [px]
  ImageF inverse_depth;                      // 1/Z [1/m], 0 where the point is invalid
  ImageU8 edge;                              // 1 at depth-edge pixels
  std::vector<std::int32_t> edge_integral;   // summed-area table of `edge`
  std::vector<std::int32_t> last_valid_row;  // per column, for the vertical edge scan
  std::vector<float> last_inverse_depth;     // per column, 1/Z at last_valid_row [1/m]
  std::vector<float> edge_threshold;         // inverse-depth jump per gap length [1/m]
  std::vector<float> radius_threshold;       // depth-dependent radius: see ComputeWindowRadii
  std::vector<Band> bands;                   // one per band of output rows (NumBands)
  std::vector<int> row_points;               // valid points per row (PrepareFrame)
  std::vector<int> band_rows;                // band k is rows [band_rows[k], band_rows[k + 1])
  double max_abs_coordinate_m = 0.0;      // of this frame's valid points
  double max_inverse_depth = 0.0;         // [1/m]
  int max_radius_px = 0;                  // largest radius any pixel may use
  // Pinhole scale recovered from the cloud (X/Z = (u - cu) / fx): 0 when it cannot be.
  double fx_px = 0.0;
  double fy_px = 0.0;
  // subsample 2: the (even row, even column) points and the estimator that runs on them.
  Image3f half_cloud;
  std::unique_ptr<NormalEstimator> half;
};

}  // namespace ssta
