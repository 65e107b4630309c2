#include "analysis/reachable_steps.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_map>

namespace ssta::internal {
namespace {

/// A crossing from a segment to an adjacent one: the neighbour, the crossing's class by its
/// median jump, and its mean jump [m].
struct Link {
  int to;
  int step_class;
  double mean_jump;
};

/// Per segment, its crossings to the segments it touches (4-adjacent pixels with points), from
/// the height jumps |(p_i - p_j) . up| between the adjacent points across each boundary.
std::vector<std::vector<Link>> BoundaryCrossings(const Image3f& cloud, const ImageI32& ids, std::size_t num_segments,
                                                 const Eigen::Vector3d& up, const VehicleOptions& vehicle) {
  struct Edge {
    int n = 0, within_semi = 0, within_max = 0;
    double sum = 0.0;
  };
  std::unordered_map<std::uint64_t, Edge> edges;
  const Eigen::Vector3f up_f = up.cast<float>();
  auto add = [&](std::size_t i, std::size_t j) {
    const int a = ids[i], b = ids[j];
    if (a < 0 || b < 0 || a == b || !IsFinite(cloud[i]) || !IsFinite(cloud[j])) return;
    const double dh = std::abs((cloud[i] - cloud[j]).dot(up_f));
    const std::uint64_t key =
        (static_cast<std::uint64_t>(std::min(a, b)) << 32) | static_cast<std::uint32_t>(std::max(a, b));
    Edge& e = edges[key];
    ++e.n;
    e.within_semi += dh <= vehicle.semi_step_m;
    e.within_max += dh <= vehicle.max_step_m;
    e.sum += dh;
  };
  const int w = cloud.width(), h = cloud.height();
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * w + u;
      if (u + 1 < w) add(i, i + 1);
      if (v + 1 < h) add(i, i + w);
    }
  }
  std::vector<std::vector<Link>> links(num_segments);
  for (const auto& [key, e] : edges) {
    const int a = static_cast<int>(key >> 32), b = static_cast<int>(key & 0xffffffffu);
    const int c = 2 * e.within_semi >= e.n ? 1 : (2 * e.within_max >= e.n ? 2 : 3);
    links[a].push_back({b, c, e.sum / e.n});
    links[b].push_back({a, c, e.sum / e.n});
  }
  return links;
}

}  // namespace

ReachableSteps ReachableStepClasses(const Image3f& cloud, const ImageI32& ids,
                                    const std::vector<SegmentResult>& segments, int ground_id,
                                    const Eigen::Vector3d& up, const VehicleOptions& vehicle) {
  const std::vector<std::vector<Link>> links = BoundaryCrossings(cloud, ids, segments.size(), up, vehicle);
  // Breadth-first from the ground, first over traversable crossings and segments only, then
  // also over semi-traversable ones: a segment's class is the first level that reaches it.
  ReachableSteps reach;
  std::vector<double>& jump_m = reach.jump_m;
  std::vector<int> level(segments.size(), 0);  // 0: not reached
  jump_m.assign(segments.size(), std::numeric_limits<double>::quiet_NaN());
  level[ground_id] = 1;
  jump_m[ground_id] = 0.0;
  for (int L = 1; L <= 2; ++L) {
    std::vector<int> queue;
    for (std::size_t s = 0; s < segments.size(); ++s) {
      if (level[s] != 0) queue.push_back(static_cast<int>(s));
    }
    for (std::size_t q = 0; q < queue.size(); ++q) {
      const SegmentResult& from = segments[queue[q]];
      // Only a segment a vehicle can drive on leads on to its neighbours.
      if (!from.has_plane || static_cast<int>(from.slope_class) > L) continue;
      for (const Link& link : links[queue[q]]) {
        if (level[link.to] != 0 || link.step_class > L) continue;
        level[link.to] = L;
        jump_m[link.to] = link.mean_jump;
        queue.push_back(link.to);
      }
    }
  }
  reach.step_class.assign(segments.size(), TravClass::kNonTraversable);
  for (std::size_t s = 0; s < segments.size(); ++s) {
    if (level[s] != 0) reach.step_class[s] = static_cast<TravClass>(level[s]);
  }
  return reach;
}

}  // namespace ssta::internal
