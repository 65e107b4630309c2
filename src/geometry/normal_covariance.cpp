// NormalMethod::kCovarianceMatrix: the smallest eigenvector of each window's covariance.

#include "geometry/normal_kernels.h"

namespace ssta {

using namespace normals;

namespace {

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

/// The per-row structure of arrays of the covariance sweep, `width` floats each: the trace-1
/// covariance entries, then the eigenvectors, so that the eigen solve runs as one branch-free
/// loop the compiler vectorises.
struct CovarianceRowArrays {
  float* cxx;
  float* cxy;
  float* cxz;
  float* cyy;
  float* cyz;
  float* czz;
  float* nx;
  float* ny;
  float* nz;
};

/// CovarianceRowArrays in `storage`, resized to 9 x width floats (its capacity is kept).
CovarianceRowArrays MakeCovarianceRowArrays(int width, std::vector<float>* storage) {
  storage->resize(static_cast<std::size_t>(width) * 9);
  CovarianceRowArrays a;
  a.cxx = storage->data();
  a.cxy = a.cxx + width;
  a.cxz = a.cxy + width;
  a.cyy = a.cxz + width;
  a.cyz = a.cyy + width;
  a.czz = a.cyz + width;
  a.nx = a.czz + width;
  a.ny = a.nx + width;
  a.nz = a.ny + width;
  return a;
}

/// Columns [first, end) of a row; empty when end <= first.
struct ColumnSpan {
  int first, end;
};

/// The span from the first to the last pixel of a row whose radius is max_r [px]. Such pixels
/// lie in [max_r, width - max_r) since the border cuts every radius.
inline ColumnSpan FullRadiusSpan(const std::uint8_t* radius, int width, int max_r) {
  int first_full = width, end_full = 0;
  for (int u = 0; u < width; ++u) {
    if (radius[u] == max_r) {
      first_full = std::min(first_full, u);
      end_full = u + 1;
    }
  }
  return {first_full, end_full};
}

/// Trace-1 covariances of the pixels of row v whose radius r [px] is neither 0 nor
/// `kernel_radius` (the radius whose pixels CovarianceRow took on this row; 0 when it ran on
/// none), one by one from box sums over the integral rows v - r and v + r + 1.
void PartialRadiusCovariances(const internal::IntegralRowRing<std::uint64_t, 10>& rows, int v,
                              const std::uint8_t* radius, int width, int kernel_radius,
                              const MinCounts& min_counts, const CovarianceRowArrays& out) {
  constexpr int kC = 10;  // n, x, y, z, xx, xy, xz, yy, yz, zz
  const std::size_t plane = rows.plane();
  for (int u = 0; u < width; ++u) {
    const int r = radius[u];
    if (r == 0 || r == kernel_radius) continue;
    const std::uint64_t* top = rows.Row(v - r);
    const std::uint64_t* bottom = rows.Row(v + r + 1);
    double s[kC];
    for (int k = 0; k < kC; ++k) {
      s[k] = static_cast<double>(BoxSum<std::int64_t>(top, bottom, plane, u - r, u + r + 1, k));
    }
    float c[6];
    UnitTraceCovariance(s, min_counts.full[r], c);
    out.cxx[u] = c[0];
    out.cxy[u] = c[1];
    out.cxz[u] = c[2];
    out.cyy[u] = c[3];
    out.cyz[u] = c[4];
    out.czz[u] = c[5];
  }
}

}  // namespace

// Sums over the window of 1, x, y, z and the six products, as integers in units of a per-frame
// quantum q (and q^2): exact box sums whatever the magnitude of the frame's other sums.
void NormalEstimator::ComputeCovariance(const Image3f& cloud, int v_begin, int v_end, Band* band) {
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
  band->strip_u64.resize(row_size);
  std::uint64_t* strip = band->strip_u64.data();
  const CovarianceRowArrays soa = MakeCovarianceRowArrays(width, &band->row_soa);
  const MinCounts min_counts(max_r);
  for (int v = v_begin; v < v_end; ++v) {
    rows.BuildUpTo(v + max_r + 1, add);
    std::uint8_t* radius = b.radius.row(v);
    const bool full_rows = v >= max_r && v + max_r + 1 <= height;
    // The vectorised full-radius kernel runs over the span of pixels that use the full radius
    // only (none when no pixel is far enough to reach it, as on most of a VGA yard frame).
    const ColumnSpan full =
        full_rows ? FullRadiusSpan(radius, width, max_r) : ColumnSpan{width, 0};
    if (full.end > full.first) {
      StripSums(rows.Row(v - max_r), rows.Row(v + max_r + 1), row_size, strip);
      CovarianceRow(full.first, full.end, max_r, min_counts.full[max_r], strip, rows.plane(),
                    soa.cxx, soa.cxy, soa.cxz, soa.cyy, soa.cyz, soa.czz);
    }
    PartialRadiusCovariances(rows, v, radius, width, full_rows ? max_r : 0, min_counts, soa);
    SmallestEigenvectorsOfRow(width, soa.cxx, soa.cxy, soa.cxz, soa.cyy, soa.cyz, soa.czz, soa.nx,
                              soa.ny, soa.nz);
    const Eigen::Vector3f* points = cloud.row(v);
    Eigen::Vector3f* normals = b.normals.row(v);
    for (int u = 0; u < width; ++u) {
      FinishNormal(Eigen::Vector3f(soa.nx[u], soa.ny[u], soa.nz[u]), points[u], &normals[u],
                   &radius[u]);
    }
  }
}

}  // namespace ssta
