#pragma once

// The sensor's path through a map (TraversabilityMap::sensor_path), with a coarse grid over its
// x-y so that the point nearest a map column is found without a walk along the whole path.

#include <cstdint>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

namespace ssta::internal {

class SensorPath {
 public:
  const std::vector<Eigen::Vector3d>& points() const { return points_; }
  void Append(const Eigen::Vector3d& point);
  void Assign(std::vector<Eigen::Vector3d> points);

  /// The x-y of the path's point nearest `xy` in the x-y plane (the first of equals in path
  /// order); `xy` itself when the path is empty.
  Eigen::Vector2d NearestXy(const Eigen::Vector2d& xy) const;

 private:
  static constexpr double kCellM = 4.0;  ///< side of the grid's squares [m]

  static std::int64_t CellIndex(double v);
  static std::int64_t Key(std::int64_t cx, std::int64_t cy);

  std::vector<Eigen::Vector3d> points_;
  /// Indices into points_ of the points in each square, keyed by Key.
  std::unordered_map<std::int64_t, std::vector<std::uint32_t>> cells_;
  std::int64_t min_cx_ = 0, max_cx_ = -1, min_cy_ = 0, max_cy_ = -1;  ///< the squares' extent
};

}  // namespace ssta::internal
