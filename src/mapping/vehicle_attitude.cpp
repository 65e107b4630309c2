#include "ssta/mapping/vehicle_attitude.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include <Eigen/Eigenvalues>

#include "ssta/core/error.h"
#include "ssta/core/units.h"

namespace ssta {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kBand = 0.8;  // the attitude cost starts at this fraction of a limit

/// Sums of the least-squares plane fit, in coordinates relative to a fixed point.
struct PlaneSums {
  double n = 0, x = 0, y = 0, z = 0, xx = 0, xy = 0, yy = 0, xz = 0, yz = 0;
  void Add(double px, double py, double pz) {
    n += 1;
    x += px;
    y += py;
    z += pz;
    xx += px * px;
    xy += px * py;
    yy += py * py;
    xz += px * pz;
    yz += py * pz;
  }
};

/// The attitude on the plane of `s` for heading `yaw`, unjudged; NaN when the points are fewer
/// than 3 or nearly collinear.
VehicleAttitude AttitudeOfSums(const PlaneSums& s, double yaw) {
  VehicleAttitude a;
  a.heights = static_cast<int>(s.n);
  if (s.n < 3) return a;
  const double mx = s.x / s.n, my = s.y / s.n, mz = s.z / s.n;
  Eigen::Matrix2d cov;
  cov << s.xx / s.n - mx * mx, s.xy / s.n - mx * my, s.xy / s.n - mx * my, s.yy / s.n - my * my;
  const double trace = cov.trace(), det = cov.determinant();
  const double smaller = 0.5 * (trace - std::sqrt(std::max(0.0, trace * trace - 4.0 * det)));
  if (!(smaller >= 1e-6)) return a;
  const Eigen::Vector2d t(s.xz / s.n - mx * mz, s.yz / s.n - my * mz);
  const Eigen::Vector2d g = cov.inverse() * t;  // dz/dx, dz/dy
  const Eigen::Vector2d d(std::cos(yaw), std::sin(yaw)), left(-std::sin(yaw), std::cos(yaw));
  const double along = g.dot(d), across = g.dot(left);
  a.pitch_deg = RadToDeg(std::atan(along)) + 0.0;  // + 0.0: level ground prints 0.00, not -0.00
  a.roll_deg = RadToDeg(std::atan2(across, std::sqrt(1.0 + along * along))) + 0.0;
  return a;
}

}  // namespace

void JudgeAttitude(const VehicleOptions& vehicle, VehicleAttitude* a) {
  if (!std::isfinite(a->pitch_deg) || !std::isfinite(a->roll_deg)) {
    a->verdict = TravClass::kUnknown;
    a->cost = kNaN;
    return;
  }
  const double pitch_f = a->pitch_deg >= 0.0 ? a->pitch_deg / vehicle.max_pitch_deg : -a->pitch_deg / vehicle.max_descent_deg;
  const double f = std::max(pitch_f, std::abs(a->roll_deg) / vehicle.max_roll_deg);
  if (f <= kBand) {
    a->verdict = TravClass::kTraversable;
    a->cost = 0.0;
  } else if (f <= 1.0) {
    a->verdict = TravClass::kSemiTraversable;
    a->cost = 0.25 + 0.5 * (f - kBand) / (1.0 - kBand);
  } else {
    a->verdict = TravClass::kNonTraversable;
    a->cost = 1.0;
  }
}

VehicleAttitude AttitudeOnGround(const std::vector<Eigen::Vector3d>& ground, double yaw, const VehicleOptions& vehicle) {
  // Relative to the first finite point: the sums stay small wherever the map lies.
  Eigen::Vector3d ref = Eigen::Vector3d::Zero();
  bool have_ref = false;
  PlaneSums s;
  for (const Eigen::Vector3d& p : ground) {
    if (!p.allFinite()) continue;
    if (!have_ref) {
      ref = p;
      have_ref = true;
    }
    s.Add(p.x() - ref.x(), p.y() - ref.y(), p.z() - ref.z());
  }
  VehicleAttitude a = AttitudeOfSums(s, yaw);
  JudgeAttitude(vehicle, &a);
  return a;
}

double HeadingCost(double class_cost, const VehicleAttitude& attitude) {
  if (std::isnan(class_cost)) return kNaN;
  if (std::isnan(attitude.cost)) return class_cost;
  return std::max(class_cost, attitude.cost);
}

bool HeadingCostOptions::IsValid(std::string* error) const {
  auto fail = [&](const std::string& message) {
    if (error != nullptr) *error = message;
    return false;
  };
  if (headings < 0 || headings > 360) return fail("headings: must be in 0..360 (0: no heading layers)");
  if (!(footprint_length_m > 0.0 && footprint_length_m <= 100.0)) return fail("footprint_length_m: must be in (0, 100] m");
  if (!(footprint_width_m > 0.0 && footprint_width_m <= 100.0)) return fail("footprint_width_m: must be in (0, 100] m");
  return true;
}

std::string HeadingName(int k, int headings) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%g", 360.0 * k / headings);
  return buffer;
}

std::vector<ImageF> HeadingCosts(const GridProjection& grid, const VehicleOptions& vehicle,
                                 const HeadingCostOptions& options) {
  std::string error;
  if (!options.IsValid(&error)) throw Error("heading costs: " + error);
  const int w = grid.width(), h = grid.height();
  if (grid.surface_z_m.width() != w || grid.surface_z_m.height() != h) {
    throw Error("heading costs: the grid has no surface heights (surface_z_m) of its size");
  }
  const double res = grid.resolution_m;
  std::vector<ImageF> layers;
  for (int k = 0; k < options.headings; ++k) {
    const double yaw = 2.0 * kPi * k / options.headings;
    // The pixels (du, dv) the footprint centred at a pixel touches, by the separating axes of
    // TraversabilityMap::QueryFootprint: the world's x and y, the rectangle's length and width.
    const double c = std::cos(yaw), s = std::sin(yaw);
    const double half_l = 0.5 * options.footprint_length_m, half_w = 0.5 * options.footprint_width_m;
    const double extent_x = std::abs(c) * half_l + std::abs(s) * half_w;
    const double extent_y = std::abs(s) * half_l + std::abs(c) * half_w;
    const double half_cell = 0.5 * res, cell_along = half_cell * (std::abs(c) + std::abs(s));
    constexpr double kOverlap = 1e-9;
    struct Offset {
      int du, dv;
      double dx, dy;
    };
    std::vector<Offset> offsets;
    const int reach_x = static_cast<int>(std::ceil(extent_x / res)) + 1;
    const int reach_y = static_cast<int>(std::ceil(extent_y / res)) + 1;
    for (int dj = -reach_y; dj <= reach_y; ++dj) {
      for (int di = -reach_x; di <= reach_x; ++di) {
        const double dx = di * res, dy = dj * res;
        const double along = c * dx + s * dy, across = -s * dx + c * dy;
        const bool apart = std::abs(dx) >= extent_x + half_cell - kOverlap ||
                           std::abs(dy) >= extent_y + half_cell - kOverlap ||
                           std::abs(along) >= half_l + cell_along - kOverlap ||
                           std::abs(across) >= half_w + cell_along - kOverlap;
        if (!apart) offsets.push_back({di, -dj, dx, dy});  // +y is up the image
      }
    }
    ImageF layer(w, h, std::numeric_limits<float>::quiet_NaN());
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) {
        const float class_cost = grid.cost(v, u);
        if (std::isnan(class_cost)) continue;
        const float z0 = grid.surface_z_m(v, u);
        PlaneSums sums;
        for (const Offset& o : offsets) {
          const int uu = u + o.du, vv = v + o.dv;
          if (uu < 0 || vv < 0 || uu >= w || vv >= h) continue;
          const float z = grid.surface_z_m(vv, uu);
          if (std::isfinite(z)) sums.Add(o.dx, o.dy, std::isfinite(z0) ? z - z0 : z);
        }
        VehicleAttitude a = AttitudeOfSums(sums, yaw);
        JudgeAttitude(vehicle, &a);
        layer(v, u) = static_cast<float>(HeadingCost(class_cost, a));
      }
    }
    layers.push_back(std::move(layer));
  }
  return layers;
}

}  // namespace ssta
