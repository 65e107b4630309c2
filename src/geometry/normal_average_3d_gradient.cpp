// NormalMethod::kAverage3dGradient: the cross product of the window's two tangents.

#include "geometry/normal_kernels.h"

namespace ssta {

using namespace normals;

namespace {

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

// Full-radius normals of pixels [begin, end) of a row.
void GradientRow(int begin, int end, int r, float min_count, float quantum, const PlanarStrips& strips, float* nx,
                 float* ny, float* nz) {
  StripRow(begin, end, r, strips,
           [=](int u, const float* l, const float* rr, const float* t, const float* bt, const float*) {
             GradientNormal(l, rr, t, bt, min_count, quantum, &nx[u], &ny[u], &nz[u]);
           });
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

}  // namespace ssta
