#include "ssta/geometry/normal_estimator.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core/utility.hpp>

#include "geometry/integral_row_ring.h"
#include "geometry/smallest_eigenvector.h"

#include "ssta/core/error.h"

namespace ssta {
namespace {

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

// The eigen solve of one row of trace-1 covariances (structure of arrays).
SSTA_NOINLINE void SmallestEigenvectorsOfRow(
    int n, const float* __restrict cxx, const float* __restrict cxy, const float* __restrict cxz,
    const float* __restrict cyy, const float* __restrict cyz, const float* __restrict czz,
    float* __restrict nx, float* __restrict ny, float* __restrict nz) {
  for (int i = 0; i < n; ++i) {
    internal::SmallestEigenvectorOfUnitTrace(cxx[i], cxy[i], cxz[i], cyy[i], cyz[i], czz[i],
                                             kMinRank2Float, &nx[i], &ny[i], &nz[i]);
  }
}

// double of a two's-complement 64-bit integer given as uint64, without the scalar-only
// int64 -> double conversion (SSE2 has none): the high half converts as an int32, the low half
// through the bits of 2^52 + low. One rounding, like the plain conversion. Vectorises.
inline double Int64ToDouble(std::uint64_t x) {
  constexpr std::uint64_t kTwo52Bits = 0x4330000000000000ull;  // 2^52
  constexpr double kTwo52 = 4503599627370496.0;
  const auto high = static_cast<std::int32_t>(static_cast<std::uint32_t>(x >> 32));
  const std::uint64_t low_bits = (x & 0xffffffffull) | kTwo52Bits;
  double low;
  std::memcpy(&low, &low_bits, sizeof low);
  return static_cast<double>(high) * 4294967296.0 + (low - kTwo52);
}

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

// Trace-1 covariance entries (xx, xy, xz, yy, yz, zz) of a window from its sums s[10] =
// (n, x, y, z, xx, xy, xz, yy, yz, zz), or zeros when it has fewer than min_count points.
// Centred in double (the subtraction cancels), then scaled to trace 1 for the float solver.
// Branch-free.
inline void UnitTraceCovariance(const double* s, double min_count, float* out) {
  const bool counted = s[0] >= min_count;
  const double inv_n = 1.0 / (counted ? s[0] : 1.0);
  const double mx = s[1] * inv_n, my = s[2] * inv_n, mz = s[3] * inv_n;
  const double xx = s[4] * inv_n - mx * mx, yy = s[7] * inv_n - my * my;
  const double zz = s[9] * inv_n - mz * mz;
  const double trace = xx + yy + zz;
  const bool ok = counted & (trace > 0.0);
  const double scale = (ok ? 1.0 : 0.0) / (ok ? trace : 1.0);
  out[0] = static_cast<float>(xx * scale);
  out[1] = static_cast<float>((s[5] * inv_n - mx * my) * scale);
  out[2] = static_cast<float>((s[6] * inv_n - mx * mz) * scale);
  out[3] = static_cast<float>(yy * scale);
  out[4] = static_cast<float>((s[8] * inv_n - my * mz) * scale);
  out[5] = static_cast<float>(zz * scale);
}

// Full-radius covariances of pixels [begin, end) of a row from a channel-planar strip.
SSTA_NOINLINE void CovarianceRow(int begin, int end, int r, double min_count,
                                 const std::uint64_t* __restrict strip, std::size_t plane,
                                 float* __restrict cxx, float* __restrict cxy,
                                 float* __restrict cxz, float* __restrict cyy,
                                 float* __restrict cyz, float* __restrict czz) {
  for (int u = begin; u < end; ++u) {
    double s[10];
    for (int k = 0; k < 10; ++k) {
      const std::size_t o = plane * k;
      s[k] = Int64ToDouble(strip[o + u + r + 1] - strip[o + u - r]);
    }
    float c[6];
    UnitTraceCovariance(s, min_count, c);
    cxx[u] = c[0];
    cxy[u] = c[1];
    cxz[u] = c[2];
    cyy[u] = c[3];
    cyz[u] = c[4];
    czz[u] = c[5];
  }
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

}  // namespace

namespace {

const EnumTable<NormalMethod>& NormalMethods() {
  static const EnumTable<NormalMethod> table("method", {{NormalMethod::kCovarianceMatrix, "covariance"},
                                                        {NormalMethod::kAverage3dGradient, "average_3d_gradient"},
                                                        {NormalMethod::kAverageDepthChange, "average_depth_change"}});
  return table;
}

}  // namespace

NormalMethod ParseNormalMethod(const std::string& name) { return NormalMethods().Parse(name); }

const char* NormalMethodName(NormalMethod method) { return NormalMethods().Name(method).c_str(); }

const OptionFields<NormalOptions>& NormalOptions::Fields() {
  using O = NormalOptions;
  static const OptionFields<O> fields = [] {
    OptionFields<O> f;
    f.push_back(Choice<O>("method", &O::method, NormalMethods(),
                          "covariance | average_3d_gradient | average_depth_change"));
    f.push_back(Integer<O>("smoothing_size_px", &O::smoothing_size_px, Closed(kMinSmoothingSizePx, kMaxSmoothingSizePx),
                           "px", "side of the smoothing window")
                    .Require([](const O& o) { return o.subsample == 1 || o.smoothing_size_px / 2 >= kMinSmoothingSizePx; },
                             "must be at least " + std::to_string(2 * kMinSmoothingSizePx) + " with subsample 2"));
    f.push_back(Real<O>("max_depth_change_factor", &O::max_depth_change_factor, OpenClosed(0, 100), "1/m",
                        "windows stop at jumps of inverse depth above this (a disparity jump of factor * f * b px)"));
    f.push_back(Flag<O>("depth_dependent_smoothing", &O::depth_dependent_smoothing,
                        "the window side scales with sqrt(depth / 5 m), 0.5x to 2x: far ground, whose "
                        "depth noise grows as Z^2, is averaged over more pixels"));
    f.push_back(Integer<O>("subsample", &O::subsample, Closed(1, 2), "",
                           "1 | 2: normals on every 2nd pixel in each direction (about 3x faster)"));
    f.push_back(Integer<O>("threads", &O::threads, Closed(0, 256), "",
                           "bands of rows on this many threads (0: OpenCV's count); the normals are the "
                           "same for any value"));
    return f;
  }();
  return fields;
}

bool NormalOptions::IsValid(std::string* error) const { return CheckOptions(*this, Fields(), error); }

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

NormalEstimator::NormalEstimator(const NormalOptions& options)
    : options_(options), buffers_(std::make_unique<Buffers>()) {
  std::string error;
  if (!options_.IsValid(&error)) throw Error(error);
}

NormalEstimator::~NormalEstimator() = default;
NormalEstimator::NormalEstimator(NormalEstimator&&) noexcept = default;
NormalEstimator& NormalEstimator::operator=(NormalEstimator&&) noexcept = default;

const ImageU8& NormalEstimator::window_radius_px() const { return buffers_->radius; }

const Image3f& NormalEstimator::Compute(const Image3f& cloud) {
  Buffers& b = *buffers_;
  const int width = cloud.width();
  const int height = cloud.height();
  if (b.normals.width() != width || b.normals.height() != height) {
    b.normals = Image3f(width, height, NanVector3f());
    b.radius = ImageU8(width, height, 0);
    b.inverse_depth = ImageF(width, height, 0.0f);
    b.edge = ImageU8(width, height, 0);
  }
  if (cloud.empty()) return b.normals;
  if (options_.subsample == 2) {
    ComputeSubsampled(cloud);
    return b.normals;
  }

  PrepareFrame(cloud);
  const int num_bands = NumBands(height);
  b.bands.resize(static_cast<std::size_t>(num_bands));
  SplitIntoBands(num_bands);
  ComputeWindowRadii(cloud);
  if (b.max_abs_coordinate_m <= 0.0) {  // no valid point at all
    b.normals.Fill(NanVector3f());
    return b.normals;
  }
  if (options_.method == NormalMethod::kAverageDepthChange && !(b.fx_px > 0.0 && b.fy_px > 0.0)) {
    b.radius.Fill(0);  // the pinhole scale could not be recovered from the cloud
    b.normals.Fill(NanVector3f());
    return b.normals;
  }
  ForEachBand(b.band_rows, [&](int band, int v_begin, int v_end) {
    Band& state = b.bands[static_cast<std::size_t>(band)];
    switch (options_.method) {
      case NormalMethod::kCovarianceMatrix:
        ComputeCovariance(cloud, v_begin, v_end, &state);
        break;
      case NormalMethod::kAverage3dGradient:
        ComputeAverage3dGradient(cloud, v_begin, v_end, &state);
        break;
      case NormalMethod::kAverageDepthChange:
        ComputeAverageDepthChange(cloud, v_begin, v_end, &state);
        break;
    }
  });
  return b.normals;
}

// Bands of at least kMinBandRows rows, one per thread: each band builds 2 R extra integral rows
// above it, so thin bands would cost more than they save.
int NormalEstimator::NumBands(int height) const {
  const int threads = options_.threads > 0 ? options_.threads : std::max(1, cv::getNumThreads());
  return std::clamp(height / kMinBandRows, 1, threads);
}

// Band boundaries with about equal work in each band: a row costs its valid points (the window
// sums and the eigen solve) plus a share of its width (building its integral row), so the sky
// at the top of a frame does not leave one thread idle. Any boundaries give the same normals.
void NormalEstimator::SplitIntoBands(int num_bands) {
  Buffers& b = *buffers_;
  const int height = static_cast<int>(b.row_points.size());
  const int width = b.normals.width();
  std::int64_t total = 0;
  for (const int n : b.row_points) total += n + width / 4;
  b.band_rows.assign(static_cast<std::size_t>(num_bands) + 1, height);
  b.band_rows[0] = 0;
  std::int64_t acc = 0;
  int band = 1;
  for (int v = 0; v < height && band < num_bands; ++v) {
    acc += b.row_points[static_cast<std::size_t>(v)] + width / 4;
    // Close band `band - 1` after row v once it holds its share, keeping kMinBandRows rows.
    if (acc * num_bands >= total * band && v + 1 - b.band_rows[band - 1] >= kMinBandRows) {
      b.band_rows[band++] = v + 1;
    }
  }
  for (int k = 1; k <= num_bands; ++k) b.band_rows[k] = std::max(b.band_rows[k], b.band_rows[k - 1]);
}


// The estimator runs on the (even row, even column) points with half the smoothing size, so
// its windows cover the same metric area; each pixel with a valid point then takes its 2 x 2
// block's normal, turned towards its own point (NaN when the block's even pixel has none).
// Its neighbours are two pixels apart, a gap of one (g invalid even points between: 2 g + 1),
// so its depth-edge threshold is the full image's at that gap, sqrt(2) times as large:
// factor * sqrt(2 + 2 g) = sqrt(2) factor * sqrt(1 + g). With the one-pixel threshold, noisy
// far ground at a grazing angle became edge pixels without normals, which cut the hills
// scene's ground beyond its rises off from the ground below (docs/performance.md).
void NormalEstimator::ComputeSubsampled(const Image3f& cloud) {
  Buffers& b = *buffers_;
  const int width = cloud.width();
  const int height = cloud.height();
  const int half_width = (width + 1) / 2, half_height = (height + 1) / 2;
  if (!b.half) {
    NormalOptions half_options = options_;
    half_options.subsample = 1;
    half_options.smoothing_size_px = options_.smoothing_size_px / 2;
    half_options.max_depth_change_factor = options_.max_depth_change_factor * std::sqrt(2.0);
    b.half = std::make_unique<NormalEstimator>(half_options);
  }
  if (b.half_cloud.width() != half_width || b.half_cloud.height() != half_height) {
    b.half_cloud = Image3f(half_width, half_height, NanVector3f());
  }
  for (int v = 0; v < half_height; ++v) {
    const Eigen::Vector3f* src = cloud.row(2 * v);
    Eigen::Vector3f* dst = b.half_cloud.row(v);
    for (int u = 0; u < half_width; ++u) dst[u] = src[2 * u];
  }
  const Image3f& half_normals = b.half->Compute(b.half_cloud);
  const ImageU8& half_radius = b.half->window_radius_px();
  for (int v = 0; v < height; ++v) {
    const Eigen::Vector3f* points = cloud.row(v);
    const Eigen::Vector3f* block_normals = half_normals.row(v / 2);
    const std::uint8_t* block_radius = half_radius.row(v / 2);
    Eigen::Vector3f* normals = b.normals.row(v);
    std::uint8_t* radius = b.radius.row(v);
    for (int u = 0; u < width; ++u) {
      const Eigen::Vector3f& p = points[u];
      const Eigen::Vector3f& n = block_normals[u / 2];
      if (!IsValidPoint(p) || !std::isfinite(n.x())) {
        normals[u] = NanVector3f();
        radius[u] = 0;
        continue;
      }
      normals[u] = n.dot(p) > 0.0f ? Eigen::Vector3f(-n) : n;
      radius[u] = static_cast<std::uint8_t>(std::min(255, 2 * block_radius[u / 2]));
    }
  }
}

// One raster pass: inverse depth per pixel, depth-edge pixels (horizontal and vertical
// neighbours, bridging short gaps of invalid pixels), the largest coordinate (for the fixed-point
// scales) and the pinhole scale fx, fy from the extreme valid pixels.
void NormalEstimator::PrepareFrame(const Image3f& cloud) {
  Buffers& b = *buffers_;
  const int width = cloud.width();
  const int height = cloud.height();
  const int base_radius = options_.smoothing_size_px / 2;
  b.max_radius_px = options_.depth_dependent_smoothing
                        ? static_cast<int>(options_.smoothing_size_px * kMaxDepthScale) / 2
                        : base_radius;
  // A gap of invalid pixels longer than this cannot fit inside any window with valid pixels on
  // both of its sides, so the points at its ends need no comparison.
  const int max_gap = 2 * b.max_radius_px - 1;
  std::vector<float>& threshold = b.edge_threshold;
  threshold.resize(static_cast<std::size_t>(max_gap) + 1);
  for (int gap = 0; gap <= max_gap; ++gap) {
    threshold[gap] = static_cast<float>(options_.max_depth_change_factor * std::sqrt(1.0 + gap));
  }

  b.edge.Fill(0);
  b.row_points.assign(static_cast<std::size_t>(height), 0);
  b.last_valid_row.assign(width, -1);
  b.last_inverse_depth.assign(width, 0.0f);
  float max_abs = 0.0f, max_rho = 0.0f;
  int u_min = std::numeric_limits<int>::max(), u_max = -1, v_min = -1, v_max = -1;
  double xhat_at_u_min = 0.0, xhat_at_u_max = 0.0, yhat_at_v_min = 0.0, yhat_at_v_max = 0.0;
  std::int32_t* last_row = b.last_valid_row.data();
  float* last_rho_column = b.last_inverse_depth.data();

  for (int v = 0; v < height; ++v) {
    const Eigen::Vector3f* points = cloud.row(v);
    float* rho_row = b.inverse_depth.row(v);
    std::uint8_t* edge = b.edge.row(v);
    int last_u = -1;
    float last_rho = 0.0f;
    int row_valid = 0;
    for (int u = 0; u < width; ++u) {
      const Eigen::Vector3f& p = points[u];
      if (!IsValidPoint(p)) {
        rho_row[u] = 0.0f;
        continue;
      }
      ++row_valid;
      const float rho = 1.0f / p.z();
      rho_row[u] = rho;
      max_abs = std::max(max_abs, std::max(std::max(std::abs(p.x()), std::abs(p.y())), p.z()));
      max_rho = std::max(max_rho, rho);
      if (last_u >= 0) {
        const int gap = u - last_u - 1;
        if (gap <= max_gap && std::abs(rho - last_rho) > threshold[gap]) {
          edge[u] = 1;
          edge[last_u] = 1;
        }
      } else if (u < u_min) {
        u_min = u;
        xhat_at_u_min = p.x() / p.z();
      }
      const int row_above = last_row[u];
      if (row_above >= 0) {
        const int gap = v - row_above - 1;
        if (gap <= max_gap && std::abs(rho - last_rho_column[u]) > threshold[gap]) {
          edge[u] = 1;
          b.edge(row_above, u) = 1;
        }
      }
      if (v != v_max) {
        if (v_min < 0) {
          v_min = v;
          yhat_at_v_min = p.y() / p.z();
        }
        v_max = v;
        yhat_at_v_max = p.y() / p.z();
      }
      last_row[u] = v;
      last_rho_column[u] = rho;
      last_u = u;
      last_rho = rho;
    }
    b.row_points[static_cast<std::size_t>(v)] = row_valid;
    if (last_u > u_max) {
      u_max = last_u;
      xhat_at_u_max = points[last_u].x() / points[last_u].z();
    }
  }
  b.max_abs_coordinate_m = max_abs;
  b.max_inverse_depth = max_rho;
  b.fx_px = (u_max > u_min && xhat_at_u_max != xhat_at_u_min)
                ? (u_max - u_min) / (xhat_at_u_max - xhat_at_u_min)
                : 0.0;
  b.fy_px = (v_max > v_min && yhat_at_v_max != yhat_at_v_min)
                ? (v_max - v_min) / (yhat_at_v_max - yhat_at_v_min)
                : 0.0;
}

// Radius per pixel: the smoothing radius (depth-dependent if asked), cut by the image border and
// shrunk until the square window holds no depth-edge pixel (edge counts from a summed-area
// table). Edge pixels themselves get no normal: their window would reach across the edge.
void NormalEstimator::ComputeWindowRadii(const Image3f& cloud) {
  Buffers& b = *buffers_;
  const int width = cloud.width();
  const int height = cloud.height();
  const std::size_t stride = static_cast<std::size_t>(width) + 1;
  b.edge_integral.resize(stride * (height + 1));
  std::int32_t* integral = b.edge_integral.data();
  std::fill(integral, integral + stride, 0);
  for (int v = 0; v < height; ++v) {
    const std::uint8_t* edge = b.edge.row(v);
    const std::int32_t* prev = integral + stride * v;
    std::int32_t* cur = integral + stride * (v + 1);
    std::int32_t acc = 0;
    cur[0] = 0;
    for (int u = 0; u < width; ++u) {
      acc += edge[u];
      cur[u + 1] = prev[u + 1] + acc;
    }
  }
  auto edges_in_window = [&](int v, int u, int r) {
    const std::int32_t* top = integral + stride * (v - r);
    const std::int32_t* bottom = integral + stride * (v + r + 1);
    return bottom[u + r + 1] - bottom[u - r] - top[u + r + 1] + top[u - r];
  };

  // The chessboard distance D to the nearest edge pixel changes by at most 1 between
  // neighbours, and a pixel whose radius the edges cut has D = r + 1 at most: so the next pixel's
  // radius is at most r + 1, and the shrinking starts there instead of at the smoothing radius
  // (same result, since every window larger than the first edge-free one holds an edge).
  const int base_radius = options_.smoothing_size_px / 2;
  // Depth-dependent radius of inverse depth rho: non-increasing in rho (each rounded step is
  // monotonic), so rather than a square root and a division per pixel, the smallest rho at
  // which it is <= k is found once per k (bisection over the float bit patterns), and each
  // pixel walks from its left neighbour's radius - the same integers.
  auto depth_radius = [&](float rho) {
    const double scale =
        std::clamp(std::sqrt(1.0 / (rho * kReferenceDepthM)), kMinDepthScale, kMaxDepthScale);
    return static_cast<int>(options_.smoothing_size_px * scale) / 2;
  };
  const int far_radius = depth_radius(std::numeric_limits<float>::min());
  const int near_radius = depth_radius(std::numeric_limits<float>::max());
  std::vector<float>& at_most = b.radius_threshold;  // [k]: smallest rho with radius <= k
  if (options_.depth_dependent_smoothing) {
    at_most.assign(static_cast<std::size_t>(far_radius) + 1, 0.0f);
    for (int k = near_radius; k < far_radius; ++k) {
      std::uint32_t lo = 0x00800000u, hi = 0x7f7fffffu;  // smallest normal .. largest float
      while (lo < hi) {
        const std::uint32_t mid = lo + (hi - lo) / 2;
        float rho;
        std::memcpy(&rho, &mid, sizeof rho);
        if (depth_radius(rho) <= k) hi = mid; else lo = mid + 1;
      }
      std::memcpy(&at_most[k], &lo, sizeof lo);
    }
  }
  // Rows are independent once the edge table is built: the bands run in parallel.
  ForEachBand(b.band_rows, [&](int, int v_begin, int v_end) {
    for (int v = v_begin; v < v_end; ++v) {
      const float* rho = b.inverse_depth.row(v);
      std::uint8_t* r_out = b.radius.row(v);
      const int border_v = std::min(v, height - 1 - v);
      int edge_bound = std::numeric_limits<int>::max();  // upper bound on this pixel's radius
      int depth_r = far_radius;
      for (int u = 0; u < width; ++u) {
        if (!(rho[u] > 0.0f)) {
          r_out[u] = 0;
          edge_bound = std::numeric_limits<int>::max();
          continue;
        }
        int r = base_radius;
        if (options_.depth_dependent_smoothing) {
          const float p = std::max(rho[u], std::numeric_limits<float>::min());
          while (depth_r > near_radius && p >= at_most[depth_r - 1]) --depth_r;
          while (p < at_most[depth_r]) ++depth_r;
          r = depth_r;
        }
        const int uncut = std::min({r, border_v, u, width - 1 - u});
        r = std::min(uncut, edge_bound);
        while (r >= kMinRadiusPx && edges_in_window(v, u, r) > 0) --r;
        edge_bound = r < uncut ? r + 1 : std::numeric_limits<int>::max();
        r_out[u] = static_cast<std::uint8_t>(r >= kMinRadiusPx ? r : 0);
      }
    }
  });
}

// Sums over the window of 1, x, y, z and the six products, as integers in units of a per-frame
// quantum q (and q^2): exact box sums whatever the magnitude of the frame's other sums.
void NormalEstimator::ComputeCovariance(const Image3f& cloud, int v_begin, int v_end, Band* band) {
  constexpr int kC = 10;  // n, x, y, z, xx, xy, xz, yy, yz, zz
  Buffers& b = *buffers_;
  const int width = cloud.width();
  const int height = cloud.height();
  const int max_r = b.max_radius_px;
  const double max_area = std::pow(2.0 * max_r + 1.0, 2);
  const float inv_q =
      static_cast<float>(std::sqrt(kMaxWindowSumOfSquares / max_area) / b.max_abs_coordinate_m);
  auto& rows = band->covariance_rows;
  rows.Reset(width, height, max_r, v_begin - max_r);
  auto add = [&](int v, int u, std::uint64_t* acc) {
    if (!(b.inverse_depth(v, u) > 0.0f)) return;
    const Eigen::Vector3f& p = cloud(v, u);
    const auto x = static_cast<std::int64_t>(p.x() * inv_q);
    const auto y = static_cast<std::int64_t>(p.y() * inv_q);
    const auto z = static_cast<std::int64_t>(p.z() * inv_q);
    acc[0] += 1;
    acc[1] += static_cast<std::uint64_t>(x);
    acc[2] += static_cast<std::uint64_t>(y);
    acc[3] += static_cast<std::uint64_t>(z);
    acc[4] += static_cast<std::uint64_t>(x * x);
    acc[5] += static_cast<std::uint64_t>(x * y);
    acc[6] += static_cast<std::uint64_t>(x * z);
    acc[7] += static_cast<std::uint64_t>(y * y);
    acc[8] += static_cast<std::uint64_t>(y * z);
    acc[9] += static_cast<std::uint64_t>(z * z);
  };

  const std::size_t row_size = rows.row_size();
  const std::size_t plane = rows.plane();
  band->strip_u64.resize(row_size);
  std::uint64_t* strip = band->strip_u64.data();
  // Per-row structure-of-arrays: the trace-1 covariance entries, then the eigenvectors, so that
  // the eigen solve runs as one branch-free loop the compiler vectorises.
  band->row_soa.resize(static_cast<std::size_t>(width) * 9);
  float* cxx = band->row_soa.data();
  float* cxy = cxx + width;
  float* cxz = cxy + width;
  float* cyy = cxz + width;
  float* cyz = cyy + width;
  float* czz = cyz + width;
  float* nx = czz + width;
  float* ny = nx + width;
  float* nz = ny + width;
  const MinCounts min_counts(max_r);
  for (int v = v_begin; v < v_end; ++v) {
    rows.BuildUpTo(v + max_r + 1, add);
    std::uint8_t* radius = b.radius.row(v);
    const bool full_rows = v >= max_r && v + max_r + 1 <= height;
    // The vectorised full-radius kernel runs over the span of pixels that use the full radius
    // only (none when no pixel is far enough to reach it, as on most of a VGA yard frame);
    // such pixels lie in [max_r, width - max_r) since the border cuts every radius.
    int first_full = width, end_full = 0;
    if (full_rows) {
      for (int u = 0; u < width; ++u) {
        if (radius[u] == max_r) {
          first_full = std::min(first_full, u);
          end_full = u + 1;
        }
      }
    }
    if (end_full > first_full) {
      StripSums(rows.Row(v - max_r), rows.Row(v + max_r + 1), row_size, strip);
      CovarianceRow(first_full, end_full, max_r, min_counts.full[max_r], strip, plane, cxx, cxy,
                    cxz, cyy, cyz, czz);
    }
    for (int u = 0; u < width; ++u) {
      const int r = radius[u];
      if (r == 0 || (r == max_r && full_rows)) continue;
      const std::uint64_t* top = rows.Row(v - r);
      const std::uint64_t* bottom = rows.Row(v + r + 1);
      double s[kC];
      for (int k = 0; k < kC; ++k) {
        s[k] = static_cast<double>(BoxSum<std::int64_t>(top, bottom, plane, u - r, u + r + 1, k));
      }
      float c[6];
      UnitTraceCovariance(s, min_counts.full[r], c);
      cxx[u] = c[0];
      cxy[u] = c[1];
      cxz[u] = c[2];
      cyy[u] = c[3];
      cyz[u] = c[4];
      czz[u] = c[5];
    }
    SmallestEigenvectorsOfRow(width, cxx, cxy, cxz, cyy, cyz, czz, nx, ny, nz);
    const Eigen::Vector3f* points = cloud.row(v);
    Eigen::Vector3f* normals = b.normals.row(v);
    for (int u = 0; u < width; ++u) {
      FinishNormal(Eigen::Vector3f(nx[u], ny[u], nz[u]), points[u], &normals[u], &radius[u]);
    }
  }
}

namespace {

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

// Average 3D gradient normal (unnormalised; 0 when a half has fewer than min_count points)
// from half-window sums of (count, x, y, z) in units of `quantum` [m]. Branch-free.
inline void GradientNormal(const float* l, const float* r, const float* t, const float* b,
                           float min_count, float quantum, float* nx, float* ny, float* nz) {
  const bool ok =
      (l[0] >= min_count) & (r[0] >= min_count) & (t[0] >= min_count) & (b[0] >= min_count);
  // Means in metres, so that the cross product stays within float range.
  const float il = quantum / (ok ? l[0] : 1.0f), ir = quantum / (ok ? r[0] : 1.0f);
  const float it = quantum / (ok ? t[0] : 1.0f), ib = quantum / (ok ? b[0] : 1.0f);
  const float ux = r[1] * ir - l[1] * il, uy = r[2] * ir - l[2] * il, uz = r[3] * ir - l[3] * il;
  const float vx = b[1] * ib - t[1] * it, vy = b[2] * ib - t[2] * it, vz = b[3] * ib - t[3] * it;
  const float keep = ok ? 1.0f : 0.0f;
  *nx = (uy * vz - uz * vy) * keep;
  *ny = (uz * vx - ux * vz) * keep;
  *nz = (ux * vy - uy * vx) * keep;
}

// Inverse-depth plane rho = a u + c v + e through the window from half-window sums of
// (count, rho, u, v): writes a, c and rho at pixel (u, v); ok = 0 when a half has fewer than
// min_count points or the halves' centres are (nearly) collinear. Branch-free.
inline void InverseDepthGradient(const float* l, const float* r, const float* t, const float* b,
                                 const float* w, float u, float v, float radius, float min_count,
                                 float* a, float* c, float* rho, float* ok) {
  bool good = (l[0] >= min_count) & (r[0] >= min_count) & (t[0] >= min_count) & (b[0] >= min_count);
  const float il = 1.0f / (good ? l[0] : 1.0f), ir = 1.0f / (good ? r[0] : 1.0f);
  const float it = 1.0f / (good ? t[0] : 1.0f), ib = 1.0f / (good ? b[0] : 1.0f);
  const float iw = 1.0f / (good ? w[0] : 1.0f);
  // Differences of the halves' means (rho, u, v): horizontal pair h, vertical pair g.
  const float h_rho = r[1] * ir - l[1] * il, h_u = r[2] * ir - l[2] * il;
  const float h_v = r[3] * ir - l[3] * il;
  const float g_rho = b[1] * ib - t[1] * it, g_u = b[2] * ib - t[2] * it;
  const float g_v = b[3] * ib - t[3] * it;
  const float det = h_u * g_v - h_v * g_u;  // (r + 1)^2 when balanced
  const float step = radius + 1.0f;
  good = good & (std::abs(det) > 0.25f * step * step);
  const float inv_det = 1.0f / (good ? det : 1.0f);
  const float da = (h_rho * g_v - h_v * g_rho) * inv_det;
  const float dc = (h_u * g_rho - h_rho * g_u) * inv_det;
  *a = da;
  *c = dc;
  *rho = w[1] * iw + da * (u - w[2] * iw) + dc * (v - w[3] * iw);
  *ok = good ? 1.0f : 0.0f;
}

// Full-radius kernels over pixels [begin, end) of a row: separate functions (SSTA_NOINLINE)
// so that __restrict parameters let the compiler vectorise them.

SSTA_NOINLINE void GradientRow(int begin, int end, int r, float min_count, float quantum,
                               PlanarStrips strips, float* __restrict nx, float* __restrict ny,
                               float* __restrict nz) {
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
    GradientNormal(l, rr, t, bt, min_count, quantum, &nx[u], &ny[u], &nz[u]);
  }
}

SSTA_NOINLINE void DepthChangeRow(int begin, int end, int v, int r, float min_count,
                                  PlanarStrips strips, float* __restrict ga, float* __restrict gc,
                                  float* __restrict rho, float* __restrict ok) {
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
  const float fv = static_cast<float>(v), fr = static_cast<float>(r);
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
    InverseDepthGradient(l, rr, t, bt, w, static_cast<float>(u), fv, fr, min_count, &ga[u], &gc[u],
                         &rho[u], &ok[u]);
  }
}

}  // namespace

// Tangents as differences of the mean points of opposite window halves (right - left,
// bottom - top, each half excluding the centre row or column); for a plane every mean point
// lies on the plane, so the tangents are exact even when invalid pixels unbalance the halves.
// Sums in 64-bit fixed point, means back in metres. Pixels with the
// full radius go through a vectorised row kernel, the others through the same maths one by one.
void NormalEstimator::ComputeAverage3dGradient(const Image3f& cloud, int v_begin, int v_end,
                                               Band* band) {
  Buffers& b = *buffers_;
  const int width = cloud.width();
  const int height = cloud.height();
  const int max_r = b.max_radius_px;
  const double max_area = std::pow(2.0 * max_r + 1.0, 2);
  const float inv_q = static_cast<float>(kMaxWindowSum64 / (max_area * b.max_abs_coordinate_m));
  const float quantum = 1.0f / inv_q;
  auto& rows = band->first_order_rows;
  rows.Reset(width, height, max_r, v_begin - max_r);
  auto add = [&](int v, int u, std::uint64_t* acc) {
    if (!(b.inverse_depth(v, u) > 0.0f)) return;
    const Eigen::Vector3f& p = cloud(v, u);
    acc[0] += 1;
    acc[1] += static_cast<std::uint64_t>(static_cast<std::int64_t>(p.x() * inv_q));
    acc[2] += static_cast<std::uint64_t>(static_cast<std::int64_t>(p.y() * inv_q));
    acc[3] += static_cast<std::uint64_t>(static_cast<std::int64_t>(p.z() * inv_q));
  };

  band->strips_u64.resize(12 * (static_cast<std::size_t>(width) + 1));
  band->row_soa.resize(3 * static_cast<std::size_t>(width));
  float* nx = band->row_soa.data();
  float* ny = nx + width;
  float* nz = ny + width;
  const MinCounts min_counts(max_r);
  for (int v = v_begin; v < v_end; ++v) {
    rows.BuildUpTo(v + max_r + 1, add);
    std::uint8_t* radius = b.radius.row(v);
    const bool full_rows = v >= max_r && v + max_r + 1 <= height;
    if (full_rows && width > 2 * max_r) {
      const PlanarStrips strips =
          MakePlanarStrips(rows.Row(v - max_r), rows.Row(v), rows.Row(v + 1),
                           rows.Row(v + max_r + 1), rows.plane(), band->strips_u64.data());
      GradientRow(max_r, width - max_r, max_r, static_cast<float>(min_counts.half[max_r]), quantum,
                  strips, nx, ny, nz);
    }
    for (int u = 0; u < width; ++u) {
      const int r = radius[u];
      if (r == 0 || (r == max_r && full_rows)) continue;
      const HalfSums s = HalfSumsFromRows(rows.Row(v - r), rows.Row(v), rows.Row(v + 1),
                                          rows.Row(v + r + 1), rows.plane(), u, r);
      GradientNormal(s.l, s.r, s.t, s.b, static_cast<float>(min_counts.half[r]), quantum, &nx[u],
                     &ny[u], &nz[u]);
    }
    const Eigen::Vector3f* points = cloud.row(v);
    Eigen::Vector3f* normals = b.normals.row(v);
    for (int u = 0; u < width; ++u) {
      FinishNormal(Eigen::Vector3f(nx[u], ny[u], nz[u]), points[u], &normals[u], &radius[u]);
    }
  }
}

// Inverse depth rho = 1/Z is linear in the normalised image coordinates (xh, yh) = (X/Z, Y/Z)
// on a plane n . P + d = 0: rho = -(n_x xh + n_y yh + n_z) / d, hence linear in (u, v) too:
// rho = a u + c v + e. So n ~ (fx a, fy c, rho - xh fx a - yh fy c) at the pixel.
// a and c come from the mean inverse depth of opposite window halves (left/right, top/bottom);
// the mean pixel coordinates of each half's valid pixels locate where those means apply, so
// invalid pixels or a range cut that unbalance the halves do not bias the gradient (a 2 x 2
// solve). One integral image of inverse depth plus the count and the valid u, v sums.
// fx, fy are recovered from the cloud itself (see PrepareFrame).
void NormalEstimator::ComputeAverageDepthChange(const Image3f& cloud, int v_begin, int v_end,
                                                Band* band) {
  Buffers& b = *buffers_;
  const int width = cloud.width();
  const int height = cloud.height();
  const int max_r = b.max_radius_px;
  const double max_area = std::pow(2.0 * max_r + 1.0, 2);
  const float inv_q = static_cast<float>(kMaxWindowSum64 / (max_area * b.max_inverse_depth));
  const float quantum = 1.0f / inv_q;  // [1/m]
  auto& rows = band->first_order_rows;
  rows.Reset(width, height, max_r, v_begin - max_r);
  auto add = [&](int v, int u, std::uint64_t* acc) {
    const float rho = b.inverse_depth(v, u);
    if (!(rho > 0.0f)) return;
    acc[0] += 1;
    acc[1] += static_cast<std::uint64_t>(static_cast<std::int64_t>(rho * inv_q));
    acc[2] += static_cast<std::uint64_t>(u);
    acc[3] += static_cast<std::uint64_t>(v);
  };

  band->strips_u64.resize(12 * (static_cast<std::size_t>(width) + 1));
  band->row_soa.resize(4 * static_cast<std::size_t>(width));
  float* ga = band->row_soa.data();
  float* gc = ga + width;
  float* rho_centre = gc + width;
  float* ok = rho_centre + width;
  const MinCounts min_counts(max_r);
  const float fx = static_cast<float>(b.fx_px), fy = static_cast<float>(b.fy_px);
  for (int v = v_begin; v < v_end; ++v) {
    rows.BuildUpTo(v + max_r + 1, add);
    std::uint8_t* radius = b.radius.row(v);
    const bool full_rows = v >= max_r && v + max_r + 1 <= height;
    if (full_rows && width > 2 * max_r) {
      const PlanarStrips strips =
          MakePlanarStrips(rows.Row(v - max_r), rows.Row(v), rows.Row(v + 1),
                           rows.Row(v + max_r + 1), rows.plane(), band->strips_u64.data());
      DepthChangeRow(max_r, width - max_r, v, max_r, static_cast<float>(min_counts.half[max_r]),
                     strips, ga, gc, rho_centre, ok);
    }
    for (int u = 0; u < width; ++u) {
      const int r = radius[u];
      if (r == 0 || (r == max_r && full_rows)) continue;
      const HalfSums s = HalfSumsFromRows(rows.Row(v - r), rows.Row(v), rows.Row(v + 1),
                                          rows.Row(v + r + 1), rows.plane(), u, r);
      InverseDepthGradient(s.l, s.r, s.t, s.b, s.w, static_cast<float>(u), static_cast<float>(v),
                           static_cast<float>(r), static_cast<float>(min_counts.half[r]), &ga[u],
                           &gc[u], &rho_centre[u], &ok[u]);
    }
    const Eigen::Vector3f* points = cloud.row(v);
    const float* rho_row = b.inverse_depth.row(v);
    Eigen::Vector3f* normals = b.normals.row(v);
    for (int u = 0; u < width; ++u) {
      if (radius[u] == 0 || ok[u] == 0.0f) {
        normals[u] = NanVector3f();
        radius[u] = 0;
        continue;
      }
      const Eigen::Vector3f& p = points[u];
      const float xh = p.x() * rho_row[u], yh = p.y() * rho_row[u];
      // Back from fixed point to 1/m, keeping the squared norm within float range.
      const float rho_xh = fx * ga[u] * quantum, rho_yh = fy * gc[u] * quantum;
      const float rho = rho_centre[u] * quantum;
      FinishNormal(Eigen::Vector3f(rho_xh, rho_yh, rho - xh * rho_xh - yh * rho_yh), p, &normals[u],
                   &radius[u]);
    }
  }
}

Image3f EstimateNormals(const Image3f& cloud_camera, const NormalOptions& options) {
  NormalEstimator estimator(options);
  return estimator.Compute(cloud_camera);
}

}  // namespace ssta
