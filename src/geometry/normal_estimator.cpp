#include "ssta/geometry/normal_estimator.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Geometry>

#include "geometry/smallest_eigenvector.h"

namespace ssta {
namespace {

constexpr int kMinSmoothingSizePx = 3;
constexpr int kMaxSmoothingSizePx = 201;  // radius 100, x2 with depth-dependent smoothing fits u8
constexpr int kMinRadiusPx = 1;           // 3 x 3 is the smallest window that yields a normal
constexpr std::uint8_t kFarPx = 255;      // distance-map value "no edge nearby"
// A window (or each half-window of the gradient methods) needs this fraction of valid points.
constexpr double kMinValidFraction = 0.25;
// Depth-dependent smoothing: side = smoothing_size_px * sqrt(Z / kReferenceDepthM), clamped.
constexpr double kReferenceDepthM = 5.0;
constexpr double kMinDepthScale = 0.5;
constexpr double kMaxDepthScale = 2.0;
// Covariance sums use fixed point so that their precision does not depend on how far the rest
// of the frame lies: a window's sums of squared coordinates must stay below this (2^62).
constexpr double kMaxWindowSumOfSquares = 4.6e18;

bool Fail(std::string* error, const std::string& message) {
  if (error) *error = message;
  return false;
}

inline bool IsValidPoint(const Eigen::Vector3f& p) {
  return p.z() > 0.0f && std::isfinite(p.z()) && std::isfinite(p.x()) && std::isfinite(p.y());
}

inline int MinCount(int area) {
  return std::max(3, static_cast<int>(std::ceil(kMinValidFraction * area)));
}

// Orients `n` towards the camera (n . p < 0) and stores it as a unit float vector.
inline void StoreOriented(const Eigen::Vector3d& n, const Eigen::Vector3f& p, Eigen::Vector3f* out) {
  const double squared_norm = n.squaredNorm();
  if (!(squared_norm > 0.0) || !std::isfinite(squared_norm)) return;
  const double sign = (n.x() * p.x() + n.y() * p.y() + n.z() * p.z()) > 0.0 ? -1.0 : 1.0;
  *out = (n * (sign / std::sqrt(squared_norm))).cast<float>();
}

}  // namespace

NormalMethod ParseNormalMethod(const std::string& name) {
  if (name == "covariance") return NormalMethod::kCovarianceMatrix;
  if (name == "average_3d_gradient") return NormalMethod::kAverage3dGradient;
  if (name == "average_depth_change") return NormalMethod::kAverageDepthChange;
  throw Error("method: unknown normal method '" + name +
              "' (expected covariance, average_3d_gradient or average_depth_change)");
}

const char* NormalMethodName(NormalMethod method) {
  switch (method) {
    case NormalMethod::kCovarianceMatrix: return "covariance";
    case NormalMethod::kAverage3dGradient: return "average_3d_gradient";
    case NormalMethod::kAverageDepthChange: return "average_depth_change";
  }
  return "unknown";
}

bool NormalOptions::IsValid(std::string* error) const {
  if (method != NormalMethod::kCovarianceMatrix && method != NormalMethod::kAverage3dGradient &&
      method != NormalMethod::kAverageDepthChange) {
    return Fail(error, "method: must be covariance, average_3d_gradient or average_depth_change");
  }
  if (!(smoothing_size_px >= kMinSmoothingSizePx && smoothing_size_px <= kMaxSmoothingSizePx)) {
    return Fail(error, "smoothing_size_px: must be in [" + std::to_string(kMinSmoothingSizePx) +
                           ", " + std::to_string(kMaxSmoothingSizePx) + "] pixels");
  }
  if (!(max_depth_change_factor > 0.0 && max_depth_change_factor <= 100.0)) {
    return Fail(error, "max_depth_change_factor: must be in (0, 100] 1/m (inverse-depth jump)");
  }
  return true;
}

NormalEstimator::NormalEstimator(const NormalOptions& options) : options_(options) {
  std::string error;
  if (!options_.IsValid(&error)) throw Error(error);
}

const Image3f& NormalEstimator::Compute(const Image3f& cloud) {
  const int width = cloud.width();
  const int height = cloud.height();
  if (normals_.width() != width || normals_.height() != height) {
    normals_ = Image3f(width, height, NanVector3f());
    radius_ = ImageU8(width, height, 0);
    distance_ = ImageU8(width, height, kFarPx);
  } else {
    normals_.Fill(NanVector3f());
  }
  if (cloud.empty()) return normals_;

  ComputeWindowRadii(cloud);
  if (max_abs_coordinate_m_ <= 0.0) return normals_;  // no valid point at all
  switch (options_.method) {
    case NormalMethod::kCovarianceMatrix: ComputeCovariance(cloud); break;
    case NormalMethod::kAverage3dGradient: ComputeAverage3dGradient(cloud); break;
    case NormalMethod::kAverageDepthChange: ComputeAverageDepthChange(cloud); break;
  }
  return normals_;
}

// Marks depth-edge pixels (distance 0), runs a two-pass chessboard distance transform and
// derives each pixel's window radius. Also records the largest coordinate (for the fixed-point
// scale) and the pinhole scale fx, fy from the extreme valid pixels.
void NormalEstimator::ComputeWindowRadii(const Image3f& cloud) {
  const int width = cloud.width();
  const int height = cloud.height();
  const int base_radius = options_.smoothing_size_px / 2;
  max_radius_px_ = options_.depth_dependent_smoothing
                       ? static_cast<int>(options_.smoothing_size_px * kMaxDepthScale) / 2
                       : base_radius;
  // A gap of invalid pixels longer than this cannot fit inside any window with valid pixels on
  // both of its sides, so the points at its ends need no comparison.
  const int max_gap = 2 * max_radius_px_ - 1;
  std::vector<float> threshold(static_cast<std::size_t>(max_gap) + 1);
  for (int gap = 0; gap <= max_gap; ++gap) {
    threshold[gap] = static_cast<float>(options_.max_depth_change_factor * std::sqrt(1.0 + gap));
  }

  distance_.Fill(kFarPx);
  last_valid_row_.assign(width, -1);
  last_inverse_depth_.assign(width, 0.0f);
  double max_abs = 0.0;
  int u_min = std::numeric_limits<int>::max(), u_max = -1, v_min = -1, v_max = -1;
  double xhat_at_u_min = 0.0, xhat_at_u_max = 0.0, yhat_at_v_min = 0.0, yhat_at_v_max = 0.0;

  for (int v = 0; v < height; ++v) {
    const Eigen::Vector3f* points = cloud.row(v);
    std::uint8_t* dist = distance_.row(v);
    int last_u = -1;
    float last_rho = 0.0f;
    for (int u = 0; u < width; ++u) {
      const Eigen::Vector3f& p = points[u];
      if (!IsValidPoint(p)) continue;
      const float rho = 1.0f / p.z();
      max_abs = std::max({max_abs, static_cast<double>(std::abs(p.x())),
                          static_cast<double>(std::abs(p.y())), static_cast<double>(p.z())});
      if (last_u >= 0) {
        const int gap = u - last_u - 1;
        if (gap <= max_gap && std::abs(rho - last_rho) > threshold[gap]) {
          dist[u] = 0;
          dist[last_u] = 0;
        }
      } else if (u < u_min) {
        u_min = u;
        xhat_at_u_min = p.x() / p.z();
      }
      const int row_above = last_valid_row_[u];
      if (row_above >= 0) {
        const int gap = v - row_above - 1;
        if (gap <= max_gap && std::abs(rho - last_inverse_depth_[u]) > threshold[gap]) {
          dist[u] = 0;
          distance_(row_above, u) = 0;
        }
      }
      if (v_min < 0) {
        v_min = v;
        yhat_at_v_min = p.y() / p.z();
      }
      if (v != v_max) {
        v_max = v;
        yhat_at_v_max = p.y() / p.z();
      }
      last_valid_row_[u] = v;
      last_inverse_depth_[u] = rho;
      last_u = u;
      last_rho = rho;
    }
    if (last_u > u_max) {
      u_max = last_u;
      xhat_at_u_max = points[last_u].x() / points[last_u].z();
    }
  }
  max_abs_coordinate_m_ = max_abs;
  fx_px_ = (u_max > u_min && xhat_at_u_max != xhat_at_u_min)
               ? (u_max - u_min) / (xhat_at_u_max - xhat_at_u_min)
               : 0.0;
  fy_px_ = (v_max > v_min && yhat_at_v_max != yhat_at_v_min)
               ? (v_max - v_min) / (yhat_at_v_max - yhat_at_v_min)
               : 0.0;

  // Chessboard distance transform (exact for this metric with two raster passes): a square
  // window of radius d - 1 around a pixel at distance d holds no edge pixel.
  auto relax = [](std::uint8_t& d, std::uint8_t neighbour) {
    const int candidate = neighbour + 1;
    if (candidate < d) d = static_cast<std::uint8_t>(candidate);
  };
  for (int v = 0; v < height; ++v) {
    std::uint8_t* d = distance_.row(v);
    const std::uint8_t* above = v > 0 ? distance_.row(v - 1) : nullptr;
    for (int u = 0; u < width; ++u) {
      if (d[u] == 0) continue;
      if (u > 0) relax(d[u], d[u - 1]);
      if (above) {
        relax(d[u], above[u]);
        if (u > 0) relax(d[u], above[u - 1]);
        if (u + 1 < width) relax(d[u], above[u + 1]);
      }
    }
  }
  for (int v = height - 1; v >= 0; --v) {
    std::uint8_t* d = distance_.row(v);
    const std::uint8_t* below = v + 1 < height ? distance_.row(v + 1) : nullptr;
    for (int u = width - 1; u >= 0; --u) {
      if (d[u] == 0) continue;
      if (u + 1 < width) relax(d[u], d[u + 1]);
      if (below) {
        relax(d[u], below[u]);
        if (u > 0) relax(d[u], below[u - 1]);
        if (u + 1 < width) relax(d[u], below[u + 1]);
      }
    }
  }

  // Radius: the smoothing radius, cut by the nearest edge and the image border.
  for (int v = 0; v < height; ++v) {
    const Eigen::Vector3f* points = cloud.row(v);
    const std::uint8_t* d = distance_.row(v);
    std::uint8_t* r_out = radius_.row(v);
    const int border_v = std::min(v, height - 1 - v);
    for (int u = 0; u < width; ++u) {
      const Eigen::Vector3f& p = points[u];
      if (!IsValidPoint(p)) {
        r_out[u] = 0;
        continue;
      }
      int r = base_radius;
      if (options_.depth_dependent_smoothing) {
        const double scale = std::clamp(std::sqrt(p.z() / kReferenceDepthM), kMinDepthScale,
                                        kMaxDepthScale);
        r = static_cast<int>(options_.smoothing_size_px * scale) / 2;
      }
      r = std::min({r, d[u] - 1, border_v, u, width - 1 - u});
      r_out[u] = static_cast<std::uint8_t>(r >= kMinRadiusPx ? r : 0);
    }
  }
}

// Sums over the window of 1, x, y, z and the six products, as integers in units of a per-frame
// quantum q (and q^2): exact box sums whatever the magnitude of the frame's other sums, with
// modular uint64 arithmetic so the running totals may wrap; only a window's sums must fit.
void NormalEstimator::ComputeCovariance(const Image3f& cloud) {
  constexpr int kC = 10;  // n, x, y, z, xx, xy, xz, yy, yz, zz
  const int width = cloud.width();
  const int height = cloud.height();
  const double max_area = std::pow(2.0 * max_radius_px_ + 1.0, 2);
  const double inv_q = std::sqrt(kMaxWindowSumOfSquares / max_area) / max_abs_coordinate_m_;
  const std::size_t row_stride = static_cast<std::size_t>(width + 1) * kC;
  integral_u64_.resize(row_stride * (height + 1));
  std::fill(integral_u64_.begin(), integral_u64_.begin() + row_stride, 0);

  for (int v = 0; v < height; ++v) {
    const std::uint64_t* prev = integral_u64_.data() + row_stride * v;
    std::uint64_t* cur = integral_u64_.data() + row_stride * (v + 1);
    std::fill(cur, cur + kC, 0);
    std::uint64_t acc[kC] = {};
    const Eigen::Vector3f* points = cloud.row(v);
    for (int u = 0; u < width; ++u) {
      const Eigen::Vector3f& p = points[u];
      if (IsValidPoint(p)) {
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
      }
      const std::uint64_t* above = prev + (u + 1) * kC;
      std::uint64_t* out = cur + (u + 1) * kC;
      for (int k = 0; k < kC; ++k) out[k] = above[k] + acc[k];
    }
  }

  for (int v = 0; v < height; ++v) {
    const std::uint8_t* radius = radius_.row(v);
    const Eigen::Vector3f* points = cloud.row(v);
    Eigen::Vector3f* normals = normals_.row(v);
    for (int u = 0; u < width; ++u) {
      const int r = radius[u];
      if (r == 0) continue;
      const std::uint64_t* top = integral_u64_.data() + row_stride * (v - r);
      const std::uint64_t* bottom = integral_u64_.data() + row_stride * (v + r + 1);
      const std::size_t left = static_cast<std::size_t>(u - r) * kC;
      const std::size_t right = static_cast<std::size_t>(u + r + 1) * kC;
      double s[kC];
      for (int k = 0; k < kC; ++k) {
        const std::uint64_t box = bottom[right + k] - bottom[left + k] - top[right + k] + top[left + k];
        s[k] = static_cast<double>(static_cast<std::int64_t>(box));
      }
      const int area = (2 * r + 1) * (2 * r + 1);
      if (s[0] < MinCount(area)) {
        radius_(v, u) = 0;
        continue;
      }
      const double inv_n = 1.0 / s[0];
      const double mx = s[1] * inv_n, my = s[2] * inv_n, mz = s[3] * inv_n;
      Eigen::Vector3d n;
      if (internal::SmallestEigenvector(s[4] * inv_n - mx * mx, s[5] * inv_n - mx * my,
                                        s[6] * inv_n - mx * mz, s[7] * inv_n - my * my,
                                        s[8] * inv_n - my * mz, s[9] * inv_n - mz * mz, &n)) {
        StoreOriented(n, points[u], &normals[u]);
      } else {
        radius_(v, u) = 0;
      }
    }
  }
}

namespace {
// Box sums of a C-channel double integral image with (width + 1) columns per row.
template <int C>
struct BoxSummer {
  const double* data;
  std::size_t row_stride;
  // Sum over rows [v0, v1) and columns [u0, u1).
  void Sum(int v0, int v1, int u0, int u1, double* out) const {
    const double* a = data + row_stride * v0 + static_cast<std::size_t>(u0) * C;
    const double* b = data + row_stride * v0 + static_cast<std::size_t>(u1) * C;
    const double* c = data + row_stride * v1 + static_cast<std::size_t>(u0) * C;
    const double* d = data + row_stride * v1 + static_cast<std::size_t>(u1) * C;
    for (int k = 0; k < C; ++k) out[k] = d[k] - c[k] - b[k] + a[k];
  }
};

// Fills a C-channel double integral image; `values(p, out)` writes the C channel values of a
// valid point (channel 0 is the count and is set here).
template <int C, typename Values>
void BuildIntegral(const Image3f& cloud, std::vector<double>* integral, Values values) {
  const int width = cloud.width();
  const int height = cloud.height();
  const std::size_t row_stride = static_cast<std::size_t>(width + 1) * C;
  integral->resize(row_stride * (height + 1));
  std::fill(integral->begin(), integral->begin() + row_stride, 0.0);
  for (int v = 0; v < height; ++v) {
    const double* prev = integral->data() + row_stride * v;
    double* cur = integral->data() + row_stride * (v + 1);
    std::fill(cur, cur + C, 0.0);
    double acc[C] = {};
    const Eigen::Vector3f* points = cloud.row(v);
    for (int u = 0; u < width; ++u) {
      if (IsValidPoint(points[u])) {
        double add[C];
        values(points[u], add);
        acc[0] += 1.0;
        for (int k = 1; k < C; ++k) acc[k] += add[k];
      }
      const double* above = prev + (u + 1) * C;
      double* out = cur + (u + 1) * C;
      for (int k = 0; k < C; ++k) out[k] = above[k] + acc[k];
    }
  }
}
}  // namespace

// Tangents as differences of the mean points of opposite window halves (right - left,
// bottom - top, each half excluding the centre row or column); for a plane every mean point
// lies on the plane, so the tangents are exact even when invalid pixels unbalance the halves.
void NormalEstimator::ComputeAverage3dGradient(const Image3f& cloud) {
  constexpr int kC = 4;  // n, x, y, z
  const int width = cloud.width();
  const int height = cloud.height();
  BuildIntegral<kC>(cloud, &integral_f64_, [](const Eigen::Vector3f& p, double* out) {
    out[1] = p.x();
    out[2] = p.y();
    out[3] = p.z();
  });
  const BoxSummer<kC> box{integral_f64_.data(), static_cast<std::size_t>(width + 1) * kC};
  auto mean = [](const double* s) -> Eigen::Vector3d {
    const double inv_n = 1.0 / s[0];
    return Eigen::Vector3d(s[1] * inv_n, s[2] * inv_n, s[3] * inv_n);
  };

  for (int v = 0; v < height; ++v) {
    const Eigen::Vector3f* points = cloud.row(v);
    Eigen::Vector3f* normals = normals_.row(v);
    std::uint8_t* radius = radius_.row(v);
    for (int u = 0; u < width; ++u) {
      const int r = radius[u];
      if (r == 0) continue;
      double sl[kC], sr[kC], st[kC], sb[kC];
      box.Sum(v - r, v + r + 1, u - r, u, sl);
      box.Sum(v - r, v + r + 1, u + 1, u + r + 1, sr);
      box.Sum(v - r, v, u - r, u + r + 1, st);
      box.Sum(v + 1, v + r + 1, u - r, u + r + 1, sb);
      const int min_count = MinCount(r * (2 * r + 1));
      if (sl[0] < min_count || sr[0] < min_count || st[0] < min_count || sb[0] < min_count) {
        radius[u] = 0;
        continue;
      }
      const Eigen::Vector3d n = (mean(sr) - mean(sl)).cross(mean(sb) - mean(st));
      StoreOriented(n, points[u], &normals[u]);
      if (!IsFinite(normals[u])) radius[u] = 0;
    }
  }
}

// Inverse depth rho = 1/Z is linear in the normalised image coordinates (xh, yh) = (X/Z, Y/Z)
// on a plane n . P + d = 0: rho = -(n_x xh + n_y yh + n_z) / d, hence linear in (u, v) too:
// rho = a u + b v + c. So n ~ (fx a, fy b, rho - xh fx a - yh fy b) at the pixel.
// a and b come from the mean inverse depth of opposite window halves (left/right, top/bottom);
// the mean pixel coordinates of each half's valid pixels locate where those means apply, so
// invalid pixels or a range cut that unbalance the halves do not bias the gradient (a 2 x 2
// solve). One integral image of inverse depth plus the count and the valid u, v sums.
// fx, fy are recovered from the cloud itself (see ComputeWindowRadii).
void NormalEstimator::ComputeAverageDepthChange(const Image3f& cloud) {
  if (!(fx_px_ > 0.0) || !(fy_px_ > 0.0)) {
    radius_.Fill(0);
    return;
  }
  constexpr int kC = 4;  // n, 1/z, u, v
  const int width = cloud.width();
  const int height = cloud.height();
  {
    const std::size_t row_stride = static_cast<std::size_t>(width + 1) * kC;
    integral_f64_.resize(row_stride * (height + 1));
    std::fill(integral_f64_.begin(), integral_f64_.begin() + row_stride, 0.0);
    for (int v = 0; v < height; ++v) {
      const double* prev = integral_f64_.data() + row_stride * v;
      double* cur = integral_f64_.data() + row_stride * (v + 1);
      std::fill(cur, cur + kC, 0.0);
      double acc[kC] = {};
      const Eigen::Vector3f* points = cloud.row(v);
      for (int u = 0; u < width; ++u) {
        if (IsValidPoint(points[u])) {
          acc[0] += 1.0;
          acc[1] += 1.0 / points[u].z();
          acc[2] += u;
          acc[3] += v;
        }
        const double* above = prev + (u + 1) * kC;
        double* out = cur + (u + 1) * kC;
        for (int k = 0; k < kC; ++k) out[k] = above[k] + acc[k];
      }
    }
  }
  const BoxSummer<kC> box{integral_f64_.data(), static_cast<std::size_t>(width + 1) * kC};

  for (int v = 0; v < height; ++v) {
    const Eigen::Vector3f* points = cloud.row(v);
    Eigen::Vector3f* normals = normals_.row(v);
    std::uint8_t* radius = radius_.row(v);
    for (int u = 0; u < width; ++u) {
      const int r = radius[u];
      if (r == 0) continue;
      double sl[kC], sr[kC], st[kC], sb[kC], sw[kC];
      box.Sum(v - r, v + r + 1, u - r, u, sl);
      box.Sum(v - r, v + r + 1, u + 1, u + r + 1, sr);
      box.Sum(v - r, v, u - r, u + r + 1, st);
      box.Sum(v + 1, v + r + 1, u - r, u + r + 1, sb);
      box.Sum(v - r, v + r + 1, u - r, u + r + 1, sw);
      const int min_count = MinCount(r * (2 * r + 1));
      if (sl[0] < min_count || sr[0] < min_count || st[0] < min_count || sb[0] < min_count) {
        radius[u] = 0;
        continue;
      }
      // Differences of the halves' means (rho, u, v): horizontal pair h, vertical pair w.
      const double il = 1.0 / sl[0], ir = 1.0 / sr[0], it = 1.0 / st[0], ib = 1.0 / sb[0];
      const double h_rho = sr[1] * ir - sl[1] * il;
      const double h_u = sr[2] * ir - sl[2] * il;
      const double h_v = sr[3] * ir - sl[3] * il;
      const double w_rho = sb[1] * ib - st[1] * it;
      const double w_u = sb[2] * ib - st[2] * it;
      const double w_v = sb[3] * ib - st[3] * it;
      const double det = h_u * w_v - h_v * w_u;  // ~ (r + 1)^2 when balanced
      if (!(std::abs(det) > 0.25 * (r + 1) * (r + 1))) {
        radius[u] = 0;
        continue;
      }
      const double inv_det = 1.0 / det;
      const double a = (h_rho * w_v - h_v * w_rho) * inv_det;  // drho/du
      const double b = (h_u * w_rho - h_rho * w_u) * inv_det;  // drho/dv
      const double inv_n = 1.0 / sw[0];
      const double rho = sw[1] * inv_n + a * (u - sw[2] * inv_n) + b * (v - sw[3] * inv_n);
      const Eigen::Vector3f& p = points[u];
      const double xh = p.x() / p.z(), yh = p.y() / p.z();
      const double rho_xh = fx_px_ * a, rho_yh = fy_px_ * b;
      const Eigen::Vector3d n(rho_xh, rho_yh, rho - xh * rho_xh - yh * rho_yh);
      StoreOriented(n, p, &normals[u]);
      if (!IsFinite(normals[u])) radius[u] = 0;
    }
  }
}

Image3f EstimateNormals(const Image3f& cloud_camera, const NormalOptions& options) {
  NormalEstimator estimator(options);
  return estimator.Compute(cloud_camera);
}

}  // namespace ssta
