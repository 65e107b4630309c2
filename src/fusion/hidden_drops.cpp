#include "fusion/hidden_drops.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "ssta/core/error.h"

namespace ssta::internal {

namespace {

/// One column's point, from the bottom row up: image row, world point, height sigma.
struct ColumnPoint {
  int v;
  Eigen::Vector3f p;
  float sigma;
};

/// Whether column point `b` (an index), where the view over the point before it lands lower,
/// lies on the wall of a pit that hides its floor: the surface at B rises more steeply than the
/// vehicle may climb (tan_max_slope). The first point beyond B that stands three sigmas (at
/// least 1 cm) above it lies no farther from the camera than that rise allows, give or take
/// three sigmas of B's range `range_b`. B is then on a face towards the camera, not on a floor;
/// the floor lies below the view, lower than B, at a depth no view from here bounds.
bool OnAPitsWall(const std::vector<ColumnPoint>& column, std::size_t b, float range_b, const Eigen::Vector2f& origin,
                 float tan_max_slope, float per_m2) {
  const ColumnPoint& base = column[b];
  // The horizontal range stands in for the depth (the camera looks along the ground).
  const float range_sigma = per_m2 * range_b * range_b;
  const float min_rise = std::max(0.01f, 3.0f * base.sigma);
  constexpr std::size_t kMaxWallPoints = 32;
  for (std::size_t j = b + 1; j < column.size() && j <= b + kMaxWallPoints; ++j) {
    const ColumnPoint& w = column[j];
    const float rise = w.p.z() - base.p.z();
    if (rise < min_rise) continue;
    const float run = (w.p.head<2>() - origin).norm() - range_b;
    return run <= rise / tan_max_slope + 3.0f * range_sigma;
  }
  return false;
}

}  // namespace

ImageU8 FindHiddenDrops(const Image3f& cloud, const Eigen::Isometry3d& world_T_rectified, double depth_noise_per_m2,
                        const VehicleOptions& vehicle, double range_m, int stride) {
  SSTA_CHECK(stride >= 1, "FindHiddenDrops: stride must be at least 1");
  ImageU8 lip(cloud.width(), cloud.height(), 0);
  const Eigen::Isometry3f world_T = world_T_rectified.cast<float>();
  const Eigen::Vector2f origin = world_T.translation().head<2>();
  const Eigen::RowVector3f up = world_T.linear().row(2);
  const auto per_m2 = static_cast<float>(std::max(0.0, depth_noise_per_m2));
  const auto max_step = static_cast<float>(vehicle.max_step_m);
  const auto semi_step = static_cast<float>(vehicle.semi_step_m);
  const auto radius = static_cast<float>(vehicle.step_radius_m);
  const auto tan_max_slope = static_cast<float>(std::tan(vehicle.max_slope_deg * 3.14159265358979 / 180.0));
  const float camera_z = world_T.translation().z();
  const auto max_range = static_cast<float>(range_m);
  std::vector<ColumnPoint> column;
  column.reserve(static_cast<std::size_t>(cloud.height()));
  for (int u = 0; u < cloud.width(); u += stride) {
    column.clear();
    for (int v = cloud.height() - 1; v >= 0; --v) {
      const Eigen::Vector3f& q = cloud(v, u);
      if (!q.allFinite() || q.z() <= 0.0f) continue;
      // The depth error seen vertically: sigma_Z |q . up| / Z, with sigma_Z = k Z^2.
      const float sigma = std::max(0.005f, per_m2 * q.z() * std::abs(up.dot(q)));
      column.push_back({v, world_T * q, sigma});
    }
    for (std::size_t i = 1; i < column.size(); ++i) {
      const ColumnPoint& a = column[i];
      const ColumnPoint& before = column[i - 1];
      // A lies on a surface, not on a stray match: its neighbour towards the camera is near
      // its height.
      if (std::abs(before.p.z() - a.p.z()) > semi_step + 3.0f * std::hypot(before.sigma, a.sigma)) continue;
      const float range_a = (a.p.head<2>() - origin).norm();
      const float tan_ray = (camera_z - a.p.z()) / std::max(range_a, 1e-3f);
      if (tan_ray <= 0.0f) continue;  // a ray over A that rises lands on nothing below it
      if (i + 1 < column.size()) {
        // The next view up the column lands beyond A and lower by more than the vehicle may
        // step, beyond the noise of both heights; or lower by less, on the wall of a pit.
        const ColumnPoint& b = column[i + 1];
        const float drop = a.p.z() - b.p.z();
        const float noise = 3.0f * std::hypot(a.sigma, b.sigma);
        if (drop <= semi_step + noise) continue;
        const float range_b = (b.p.head<2>() - origin).norm();
        if (range_b <= range_a) continue;
        if (drop <= max_step + noise && !OnAPitsWall(column, i + 1, range_b, origin, tan_max_slope, per_m2)) continue;
      } else {
        // Nothing beyond A in this column: had a floor lain within max_step below A, the ray
        // over A would have met it within range (before range_a + max_step / tan_ray).
        if (a.v < 2 || range_a + max_step / tan_ray >= max_range) continue;
      }
      // What lies between A and where the ray lands descends more steeply than the ray, or it
      // would be seen. A ray steeper than max_slope_deg hides a drop no wheel may take (weight
      // 1); a flatter one may hide a drivable slope (the far side of a crest), which a nearer
      // view shows: the suspicion weighs tan(ray) / tan(max_slope).
      const auto weight =
          static_cast<std::uint8_t>(std::lround(255.0f * std::clamp(tan_ray / tan_max_slope, 0.02f, 1.0f)));
      for (std::size_t j = i + 1; j-- > 0;) {
        if ((column[j].p.head<2>() - a.p.head<2>()).norm() > radius) break;
        std::uint8_t& w = lip(column[j].v, u);
        w = std::max(w, weight);
      }
    }
  }
  return lip;
}

}  // namespace ssta::internal
