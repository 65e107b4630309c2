#include "analysis/hidden_drops.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "ssta/core/error.h"

namespace ssta::internal {

namespace {

/// sqrt(x^2 + y^2) of two height sigmas (no overflow to guard against, unlike std::hypot).
inline float Hypot(float x, float y) { return std::sqrt(x * x + y * y); }

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

/// How high the wall that column point `b` stands on (OnAPitsWall) rises into view above B [m]:
/// the highest of the points beyond B that stay within the steep face, each no farther from
/// the camera than its rise allows at tan_max_slope, give or take three sigmas of B's range.
/// The first point beyond that ends the wall.
float VisibleWallRise(const std::vector<ColumnPoint>& column, std::size_t b, float range_b,
                      const Eigen::Vector2f& origin, float tan_max_slope, float per_m2) {
  const ColumnPoint& base = column[b];
  const float range_slack = 3.0f * per_m2 * range_b * range_b;
  float highest = 0.0f;
  for (std::size_t j = b + 1; j < column.size(); ++j) {
    const ColumnPoint& w = column[j];
    const float rise = w.p.z() - base.p.z();
    const float run = (w.p.head<2>() - origin).norm() - range_b;
    if (run > std::max(rise, 0.0f) / tan_max_slope + range_slack) break;
    highest = std::max(highest, rise);
  }
  return highest;
}

/// The lip's marks with the edge point each is measured from (its seed), so that the marks of a
/// column can reach along the rows a step radius from the same edge point.
struct LipMarks {
  /// `seed_buffer` is reused from frame to frame (resized when the size differs): a seed is
  /// written with its mark and read only where a mark is, so it needs no clearing.
  LipMarks(int width, int height, Image<Eigen::Vector2f>* seed_buffer) : weight(width, height, 0), seed(*seed_buffer) {
    if (seed.width() != width || seed.height() != height) {
      seed = Image<Eigen::Vector2f>(width, height, Eigen::Vector2f::Zero());
    }
  }

  /// Marks the points of image column `u` (`column`, as FindHiddenDrops gathers it) within
  /// `radius` of column[edge] (horizontally) with `w`, walking each way from it up to the first
  /// point beyond. A point keeps the larger weight, and that mark's seed.
  void AroundEdge(const std::vector<ColumnPoint>& column, std::size_t edge, int u, std::uint8_t w, float radius) {
    const Eigen::Vector2f centre = column[edge].p.head<2>();
    const auto mark = [&](std::size_t j) {
      if ((column[j].p.head<2>() - centre).norm() > radius) return false;
      std::uint8_t& current = weight(column[j].v, u);
      if (w > current) {
        current = w;
        seed(column[j].v, u) = centre;
      }
      return true;
    };
    for (std::size_t j = edge + 1; j-- > 0 && mark(j);) {
    }
    for (std::size_t j = edge + 1; j < column.size() && mark(j); ++j) {
    }
  }

  ImageU8 weight;
  Image<Eigen::Vector2f>& seed;
};

/// The marks spread along the rows: each mark reaches the points of its row within `radius` of
/// its seed, up to the first point beyond; a gap of no depth wider than kMaxGapPx ends it too.
/// `stride`: the columns that were marked.
ImageU8 SpreadAlongRows(const Image3f& cloud, const Eigen::Isometry3f& world_T, const LipMarks& marks, float radius,
                        int stride) {
  constexpr int kMaxGapPx = 16;
  ImageU8 spread = marks.weight;
  for (int v = 0; v < cloud.height(); ++v) {
    for (int u = 0; u < cloud.width(); u += stride) {
      const std::uint8_t weight = marks.weight(v, u);
      if (weight == 0) continue;
      const Eigen::Vector2f& centre = marks.seed(v, u);
      for (const int step : {-stride, stride}) {
        int gap = 0;
        for (int w = u + step; w >= 0 && w < cloud.width() && gap <= kMaxGapPx; w += step) {
          const Eigen::Vector3f& q = cloud(v, w);
          if (!q.allFinite() || q.z() <= 0.0f) {
            gap += stride;
            continue;
          }
          gap = 0;
          if (((world_T * q).head<2>() - centre).norm() > radius) break;
          spread(v, w) = std::max(spread(v, w), weight);
        }
      }
    }
  }
  return spread;
}

}  // namespace

ImageU8 FindHiddenDrops(const Image3f& cloud, const Eigen::Isometry3d& world_T_rectified, double depth_noise_per_m2,
                        const VehicleOptions& vehicle, double range_m, int stride) {
  SSTA_CHECK(stride >= 1, "FindHiddenDrops: stride must be at least 1");
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
  // The edges are marked along the columns, then spread along the rows, so the lip reaches a
  // step radius from its edge in every direction, as the vehicle's rule measures it, also
  // beside an edge the columns cross obliquely (the sides of a pit).
  thread_local Image<Eigen::Vector2f> seed_of_thread;
  LipMarks marks(cloud.width(), cloud.height(), &seed_of_thread);
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
      // The next view up the column lands lower than A by more than semi_step beyond the noise
      // of both heights (tested first: most points end here), or there is nothing beyond A.
      const bool last = i + 1 == column.size();
      const float drop = last ? 0.0f : a.p.z() - column[i + 1].p.z();
      const float noise = last ? 0.0f : 3.0f * Hypot(a.sigma, column[i + 1].sigma);
      if (!last && drop <= semi_step + noise) continue;
      // A lies on a surface, not on a stray match: its neighbour towards the camera is near
      // its height.
      if (std::abs(before.p.z() - a.p.z()) > semi_step + 3.0f * Hypot(before.sigma, a.sigma)) continue;
      const float range_a = (a.p.head<2>() - origin).norm();
      const float tan_ray = (camera_z - a.p.z()) / std::max(range_a, 1e-3f);
      if (tan_ray <= 0.0f) continue;  // a ray over A that rises lands on nothing below it
      // The view lands on the far wall of a pit that rises back to the near rim's height, give
      // or take the noise: that wall drops to the same hidden floor, so its rim is a lip too.
      bool far_rim = false;
      if (!last) {
        // The next view lands beyond A and lower by more than the vehicle may step; or lower
        // by less, on the wall of a pit.
        const ColumnPoint& b = column[i + 1];
        const float range_b = (b.p.head<2>() - origin).norm();
        if (range_b <= range_a) continue;
        if (drop <= max_step + noise) {
          if (!OnAPitsWall(column, i + 1, range_b, origin, tan_max_slope, per_m2)) continue;
          far_rim = VisibleWallRise(column, i + 1, range_b, origin, tan_max_slope, per_m2) >= drop - noise;
        }
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
      marks.AroundEdge(column, i, u, weight, radius);
      // The wall's foot B stands where the far rim does, give or take the wall's slope.
      if (far_rim) marks.AroundEdge(column, i + 1, u, weight, radius);
    }
  }
  return SpreadAlongRows(cloud, world_T, marks, radius, stride);
}

ImageU8 FindFramesHiddenDrops(const Image3f& cloud, const Eigen::Vector3d& up_camera, double depth_noise_per_m2,
                              const VehicleOptions& vehicle, double range_m) {
  Eigen::Isometry3d level = Eigen::Isometry3d::Identity();
  level.linear() = Eigen::Quaterniond::FromTwoVectors(up_camera, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return FindHiddenDrops(cloud, level, depth_noise_per_m2, vehicle, range_m, 1);
}

}  // namespace ssta::internal
