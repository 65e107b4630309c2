#include "sensor_path.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "ssta/core/error.h"

namespace ssta::internal {

std::int64_t SensorPath::CellIndex(double v) { return static_cast<std::int64_t>(std::floor(v / kCellM)); }

std::int64_t SensorPath::Key(std::int64_t cx, std::int64_t cy) {
  return static_cast<std::int64_t>(static_cast<std::uint64_t>(cx) << 32 ^ (static_cast<std::uint64_t>(cy) & 0xFFFFFFFFu));
}

void SensorPath::Append(const Eigen::Vector3d& point) {
  SSTA_CHECK(points_.size() < std::numeric_limits<std::uint32_t>::max(), "the sensor path holds too many points");
  const std::int64_t cx = CellIndex(point.x()), cy = CellIndex(point.y());
  if (points_.empty()) {
    min_cx_ = max_cx_ = cx;
    min_cy_ = max_cy_ = cy;
  } else {
    min_cx_ = std::min(min_cx_, cx), max_cx_ = std::max(max_cx_, cx);
    min_cy_ = std::min(min_cy_, cy), max_cy_ = std::max(max_cy_, cy);
  }
  cells_[Key(cx, cy)].push_back(static_cast<std::uint32_t>(points_.size()));
  points_.push_back(point);
}

void SensorPath::Assign(std::vector<Eigen::Vector3d> points) {
  points_.clear();
  cells_.clear();
  for (const Eigen::Vector3d& p : points) Append(p);
}

Eigen::Vector2d SensorPath::NearestXy(const Eigen::Vector2d& xy) const {
  if (points_.empty()) return xy;
  const std::int64_t cx = CellIndex(xy.x()), cy = CellIndex(xy.y());
  double best_d2 = std::numeric_limits<double>::infinity();
  std::uint32_t best = 0;
  const auto visit = [&](std::int64_t x, std::int64_t y) {
    const auto it = cells_.find(Key(x, y));
    if (it == cells_.end()) return;
    for (std::uint32_t i : it->second) {
      const double d2 = (points_[i].head<2>() - xy).squaredNorm();
      if (d2 < best_d2 || (d2 == best_d2 && i < best)) best_d2 = d2, best = i;
    }
  };
  // Far off the path's squares, the rings up to them hold more squares than the path points:
  // walk the path instead.
  const std::int64_t gap = std::max({min_cx_ - cx, cx - max_cx_, min_cy_ - cy, cy - max_cy_, std::int64_t{0}});
  if (static_cast<double>(2 * gap + 1) * static_cast<double>(2 * gap + 1) > 4.0 * static_cast<double>(points_.size())) {
    for (std::uint32_t i = 0; i < points_.size(); ++i) {
      const double d2 = (points_[i].head<2>() - xy).squaredNorm();
      if (d2 < best_d2) best_d2 = d2, best = i;
    }
    return points_[best].head<2>();
  }
  // Rings of squares about xy's: a point in ring k + 1 lies at least k squares' sides away.
  const std::int64_t rings = std::max({std::abs(cx - min_cx_), std::abs(cx - max_cx_), std::abs(cy - min_cy_),
                                       std::abs(cy - max_cy_)});
  for (std::int64_t k = 0; k <= rings; ++k) {
    for (std::int64_t x = cx - k; x <= cx + k; ++x) {
      visit(x, cy - k);
      if (k > 0) visit(x, cy + k);
    }
    for (std::int64_t y = cy - k + 1; y <= cy + k - 1; ++y) {
      visit(cx - k, y);
      visit(cx + k, y);
    }
    const double reach = static_cast<double>(k) * kCellM;
    if (best_d2 <= reach * reach) break;
  }
  return points_[best].head<2>();
}

}  // namespace ssta::internal
