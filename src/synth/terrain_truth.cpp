#include "ssta/synth/terrain_truth.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "ssta/core/units.h"
#include "synth/parallel.h"

namespace ssta::synth {

TerrainTruth::TerrainTruth(const Scene& scene, const VehicleOptions& vehicle, const Eigen::AlignedBox2d& region,
                           int threads)
    : scene_(scene), vehicle_(vehicle) {
  const double radius = vehicle.step_radius_m;
  resolution_m_ = std::clamp(radius / 4.0, 0.01, 0.05);
  origin_ = region.min();
  nx_ = std::max(1, static_cast<int>(std::ceil(region.sizes().x() / resolution_m_)));
  ny_ = std::max(1, static_cast<int>(std::ceil(region.sizes().y() / resolution_m_)));
  // Height of the top surface above the smooth base ground, per cell centre: objects above it,
  // pits below it.
  std::vector<float> relative(static_cast<std::size_t>(nx_) * ny_, 0.0f);
  ParallelFor(ny_, threads, [&](int j) {
    for (int i = 0; i < nx_; ++i) {
      const double x = origin_.x() + (i + 0.5) * resolution_m_, y = origin_.y() + (j + 0.5) * resolution_m_;
      const double base = scene.BaseHeight(x, y);
      const SurfaceHit top = scene.CastRay(Eigen::Vector3d(x, y, base + 100.0), -Eigen::Vector3d::UnitZ(), 300.0);
      relative[static_cast<std::size_t>(j) * nx_ + i] = top.hit ? static_cast<float>(top.p_world.z() - base) : 0.0f;
    }
  });
  // The step of each cell: the range of those heights over the disc of the step radius.
  const int reach = static_cast<int>(std::floor(radius / resolution_m_));
  std::vector<Eigen::Vector2i> disc;
  for (int dj = -reach; dj <= reach; ++dj) {
    for (int di = -reach; di <= reach; ++di) {
      if ((di * di + dj * dj) * resolution_m_ * resolution_m_ <= radius * radius + 1e-12) disc.emplace_back(di, dj);
    }
  }
  step_m_.assign(relative.size(), 0.0f);
  ParallelFor(ny_, threads, [&](int j) {
    for (int i = 0; i < nx_; ++i) {
      float lo = std::numeric_limits<float>::infinity(), hi = -lo;
      for (const Eigen::Vector2i& d : disc) {
        const int ii = i + d.x(), jj = j + d.y();
        if (ii < 0 || jj < 0 || ii >= nx_ || jj >= ny_) continue;
        const float h = relative[static_cast<std::size_t>(jj) * nx_ + ii];
        lo = std::min(lo, h);
        hi = std::max(hi, h);
      }
      step_m_[static_cast<std::size_t>(j) * nx_ + i] = hi - lo;
    }
  });
}

bool TerrainTruth::Cell(double x, double y, int* i, int* j) const {
  *i = static_cast<int>(std::floor((x - origin_.x()) / resolution_m_));
  *j = static_cast<int>(std::floor((y - origin_.y()) / resolution_m_));
  return *i >= 0 && *j >= 0 && *i < nx_ && *j < ny_;
}

double TerrainTruth::StepAt(double x, double y) const {
  int i, j;
  if (!Cell(x, y, &i, &j)) return std::numeric_limits<double>::quiet_NaN();
  return step_m_[static_cast<std::size_t>(j) * nx_ + i];
}

double TerrainTruth::SlopeDeg(const SurfaceHit& hit) const {
  const double own = RadToDeg(std::acos(std::clamp(hit.normal_world.z(), -1.0, 1.0)));
  const bool face = hit.vertical_face || (hit.object_id != 0 && own > vehicle_.max_slope_deg);
  if (!face) return own;
  const Eigen::Vector2d g = scene_.BaseGradient(hit.p_world.x(), hit.p_world.y());
  return RadToDeg(std::atan(g.norm()));
}

std::uint8_t TerrainTruth::ClassOf(const SurfaceHit& hit) const {
  const double step = StepAt(hit.p_world.x(), hit.p_world.y());
  if (!std::isfinite(step)) return kDontCare;
  return static_cast<std::uint8_t>(Worse(vehicle_.ClassifySlope(SlopeDeg(hit)), vehicle_.ClassifyStep(step)));
}

std::uint8_t TerrainTruth::ClassAt(double x, double y) const {
  const SurfaceHit top = scene_.CastRay(Eigen::Vector3d(x, y, scene_.BaseHeight(x, y) + 100.0),
                                        -Eigen::Vector3d::UnitZ(), 300.0);
  if (!top.hit) return kDontCare;
  return ClassOf(top);
}

}  // namespace ssta::synth
