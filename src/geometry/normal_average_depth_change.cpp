// NormalMethod::kAverageDepthChange: the plane of inverse depth through the window.

#include "geometry/normal_kernels.h"

namespace ssta {

using namespace normals;

namespace {

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

// Full-radius inverse-depth gradients of pixels [begin, end) of row v.
void DepthChangeRow(int begin, int end, int v, int r, float min_count, const PlanarStrips& strips, float* ga,
                    float* gc, float* rho, float* ok) {
  const float fv = static_cast<float>(v), fr = static_cast<float>(r);
  StripRow(begin, end, r, strips,
           [=](int u, const float* l, const float* rr, const float* t, const float* bt, const float* w) {
             InverseDepthGradient(l, rr, t, bt, w, static_cast<float>(u), fv, fr, min_count, &ga[u], &gc[u],
                                  &rho[u], &ok[u]);
           });
}

}  // namespace

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

}  // namespace ssta
