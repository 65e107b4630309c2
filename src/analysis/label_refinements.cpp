// Refinements 2, 3, 5 and 6 of label_refinements.h: ground consistency, fragments, and the
// two fills of undecided pixels. 1 and 4 are in pixel_slopes.cpp and disparity_faces.cpp.

#include "ssta/analysis/label_refinements.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "analysis/reason_format.h"
#include "ssta/core/error.h"

namespace ssta {
namespace {

/// Along the ray r = p / Z a plane n . x + D = 0 lies at inverse depth -(n . r) / D, so the
/// point's disparity fb / Z differs from the plane's there by fb (n . p + D) / (Z D): its distance
/// to the plane scaled by fb / (Z D) [px]. `p.z()` and D must be non-zero.
double DisparityOffPlanePx(const Eigen::Vector4d& plane, const Eigen::Vector3d& p, double fb) {
  return fb * (plane.head<3>().dot(p) + plane(3)) / (p.z() * plane(3));
}

/// Sets the labels of the pixels of segment s to new_class[s] where that is not 0 (unknown:
/// keep) and the pixel has depth (label != 0).
void RelabelSegments(const ImageI32& segment_ids, const std::vector<std::uint8_t>& new_class, ImageU8* labels) {
  const int num_segments = static_cast<int>(new_class.size());
  for (std::size_t i = 0; i < labels->size(); ++i) {
    const int id = segment_ids[i];
    if (id >= 0 && id < num_segments && new_class[id] != 0 && (*labels)[i] != 0) (*labels)[i] = new_class[id];
  }
}

}  // namespace

void RefineByGroundDisparity(const Image3f& cloud, const ImageI32& segment_ids, double focal_times_baseline,
                             const LabelRefinementOptions& options, AnalysisResult* result) {
  SSTA_CHECK(cloud.width() == segment_ids.width() && cloud.height() == segment_ids.height() &&
                 cloud.width() == result->labels.width() && cloud.height() == result->labels.height(),
             "RefineByGroundDisparity: cloud, segment ids and labels differ in size");
  SSTA_CHECK(focal_times_baseline > 0, "RefineByGroundDisparity: focal_times_baseline must be positive");
  if (!(options.ground_tolerance_px > 0) || !result->ground.found || !result->quality.passed) return;
  const Eigen::Vector4d& plane = result->ground.plane;
  if (!(plane(3) > 0)) return;  // the camera's height above the plane
  // DisparityOffPlanePx; above the horizon no point is consistent.
  const double fb = focal_times_baseline;
  const int num_segments = static_cast<int>(result->segments.size());
  // Only small segments without the ground's verdict can change: the others' pixels are skipped.
  const TravClass ground_class = result->ground.surface_class;
  std::vector<bool> candidate(num_segments, false);
  for (const SegmentResult& seg : result->segments) {
    if (seg.id >= 0 && seg.id < num_segments) candidate[seg.id] = seg.small && seg.verdict != ground_class;
  }
  std::vector<int> points(num_segments, 0), consistent(num_segments, 0);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const int id = segment_ids[i];
    if (id < 0 || id >= num_segments || !candidate[id]) continue;
    const Eigen::Vector3d p = cloud[i].cast<double>();
    if (!(p.z() > 0)) continue;  // also NaN
    ++points[id];
    if (std::abs(DisparityOffPlanePx(plane, p, fb)) <= options.ground_tolerance_px) ++consistent[id];
  }
  std::vector<std::uint8_t> new_class(num_segments, 0);
  bool any = false;
  for (SegmentResult& seg : result->segments) {
    const int id = seg.id;
    if (id < 0 || id >= num_segments || !candidate[id]) continue;
    if (points[id] == 0 || consistent[id] < options.ground_consistent_share * points[id]) continue;
    new_class[id] = static_cast<std::uint8_t>(ground_class);
    any = true;
    seg.verdict = ground_class;
    seg.reason = internal::FormatNumber("small, and on the ground plane within stereo noise:",
                                        100.0 * consistent[id] / points[id], 0,
                                        "% of its points within ground_tolerance_px of the plane's disparity");
  }
  if (any) RelabelSegments(segment_ids, new_class, &result->labels);
}

namespace {

/// The hosts each fragment (a small segment with points) touches, 4-neighbours in
/// `segment_ids`, in the order met: a host has a well-determined plane, at least
/// fragment_host_min_points points and more than twice the fragment's. A handful at most per
/// fragment (kept as small vectors); empty for the other segments.
std::vector<std::vector<int>> LinkFragmentsToHosts(const ImageI32& segment_ids,
                                                   const std::vector<SegmentResult>& segments,
                                                   const LabelRefinementOptions& options) {
  constexpr double kMinPlaneDistanceM = 0.05;  // planes nearer the camera have no stable disparity
  const int num_segments = static_cast<int>(segments.size());
  std::vector<char> fragment(num_segments, 0), surface(num_segments, 0);
  for (const SegmentResult& seg : segments) {
    fragment[seg.id] = seg.small && seg.inliers > 0;
    surface[seg.id] = seg.inliers >= options.fragment_host_min_points && seg.has_plane &&
                      std::abs(seg.plane(3)) > kMinPlaneDistanceM;
  }
  auto hosts = [&](int host, int frag) { return segments[host].inliers > 2 * segments[frag].inliers; };
  std::vector<std::vector<int>> touches(num_segments);
  auto link = [&](int a, int b) {
    if (a < 0 || b < 0 || a == b) return;
    if (fragment[a] && surface[b] && hosts(b, a)) {
      std::vector<int>& t = touches[a];
      if (std::find(t.begin(), t.end(), b) == t.end()) t.push_back(b);
    } else if (fragment[b] && surface[a] && hosts(a, b)) {
      std::vector<int>& t = touches[b];
      if (std::find(t.begin(), t.end(), a) == t.end()) t.push_back(a);
    }
  };
  const int w = segment_ids.width(), h = segment_ids.height();
  for (int v = 0; v < h; ++v) {
    const std::int32_t* row = segment_ids.row(v);
    const std::int32_t* below = v + 1 < h ? segment_ids.row(v + 1) : nullptr;
    for (int u = 0; u < w; ++u) {
      if (u + 1 < w && row[u] != row[u + 1]) link(row[u], row[u + 1]);
      if (below && row[u] != below[u]) link(row[u], below[u]);
    }
  }
  return touches;
}

/// Per segment, its points with depth (z > 0), and of those the ones within
/// fragment_tolerance_px of the disparity of each touched host's plane (DisparityOffPlanePx).
struct PlaneCounts {
  std::vector<int> points;
  std::vector<std::vector<int>> consistent;  // [id][k]: on the plane of host touches[id][k]
};

/// PlaneCounts of the segments that touch a host; fb = focal length * baseline [px m].
PlaneCounts CountPlaneConsistentPoints(const Image3f& cloud, const ImageI32& segment_ids,
                                       const std::vector<SegmentResult>& segments,
                                       const std::vector<std::vector<int>>& touches, double fb,
                                       const LabelRefinementOptions& options) {
  const int num_segments = static_cast<int>(segments.size());
  PlaneCounts counts;
  counts.points.assign(num_segments, 0);
  counts.consistent.resize(num_segments);
  std::vector<int>& points = counts.points;
  std::vector<std::vector<int>>& consistent = counts.consistent;
  for (int id = 0; id < num_segments; ++id) consistent[id].assign(touches[id].size(), 0);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const int id = segment_ids[i];
    if (id < 0 || id >= num_segments || touches[id].empty()) continue;
    const Eigen::Vector3d p = cloud[i].cast<double>();
    if (!(p.z() > 0)) continue;  // also NaN
    ++points[id];
    for (std::size_t k = 0; k < touches[id].size(); ++k) {
      const Eigen::Vector4d& plane = segments[touches[id][k]].plane;
      consistent[id][k] += std::abs(DisparityOffPlanePx(plane, p, fb)) <= options.fragment_tolerance_px;
    }
  }
  return counts;
}

/// Each segment's host, -1 for none: the touched host whose plane holds most of its points, if
/// those are at least fragment_consistent_share of them; and that share [%], rounded.
struct FragmentHosts {
  std::vector<int> host, share_pct;
};

/// FragmentHosts from the hosts each segment touches and the points on their planes.
FragmentHosts ChooseHosts(const std::vector<std::vector<int>>& touches, const PlaneCounts& counts,
                          const LabelRefinementOptions& options) {
  const int num_segments = static_cast<int>(touches.size());
  FragmentHosts hosts;
  hosts.host.assign(num_segments, -1);
  hosts.share_pct.assign(num_segments, 0);
  for (int id = 0; id < num_segments; ++id) {
    int best = -1, best_count = 0;
    for (std::size_t k = 0; k < touches[id].size(); ++k) {
      if (counts.consistent[id][k] > best_count) {
        best_count = counts.consistent[id][k];
        best = touches[id][k];
      }
    }
    if (best < 0 || best_count < options.fragment_consistent_share * counts.points[id]) continue;
    hosts.host[id] = best;
    hosts.share_pct[id] = static_cast<int>(std::lround(100.0 * best_count / counts.points[id]));
  }
  return hosts;
}

/// Gives each fragment that has a host its host's verdict and reason, and relabels its pixels.
/// A host may itself be a fragment of a larger host (it has more than twice the points, so the
/// chains end): a fragment takes the verdict at the end of its chain, whatever the order of the
/// segment ids.
void AdoptHostVerdicts(const FragmentHosts& hosts, const ImageI32& segment_ids, AnalysisResult* result) {
  const std::vector<int>& host = hosts.host;
  const std::vector<int>& share_pct = hosts.share_pct;
  const int num_segments = static_cast<int>(host.size());
  std::vector<std::uint8_t> new_class(num_segments, 0);
  bool any = false;
  for (int id = 0; id < num_segments; ++id) {
    if (host[id] < 0) continue;
    int root = host[id];
    while (host[root] >= 0) root = host[root];
    SegmentResult& seg = result->segments[id];
    seg.verdict = result->segments[root].verdict;  // a root is never changed here
    new_class[id] = static_cast<std::uint8_t>(seg.verdict);
    any = true;
    seg.reason = "small, on the plane of segment " + std::to_string(host[id]) + " within stereo noise: " +
                 std::to_string(share_pct[id]) + "% of its points (" + std::string(ClassName(seg.verdict)) + ")";
  }
  if (any) RelabelSegments(segment_ids, new_class, &result->labels);
}

}  // namespace

void RefineByFragmentPlanes(const Image3f& cloud, const ImageI32& segment_ids, double focal_times_baseline,
                            const LabelRefinementOptions& options, AnalysisResult* result) {
  SSTA_CHECK(cloud.width() == segment_ids.width() && cloud.height() == segment_ids.height() &&
                 cloud.width() == result->labels.width() && cloud.height() == result->labels.height(),
             "RefineByFragmentPlanes: cloud, segment ids and labels differ in size");
  SSTA_CHECK(focal_times_baseline > 0, "RefineByFragmentPlanes: focal_times_baseline must be positive");
  if (!(options.fragment_tolerance_px > 0) || !result->quality.passed) return;
  const std::vector<std::vector<int>> touches = LinkFragmentsToHosts(segment_ids, result->segments, options);
  const PlaneCounts counts =
      CountPlaneConsistentPoints(cloud, segment_ids, result->segments, touches, focal_times_baseline, options);
  const FragmentHosts hosts = ChooseHosts(touches, counts, options);
  AdoptHostVerdicts(hosts, segment_ids, result);
}

void FillUndecidedByConsensus(const LabelRefinementOptions& options, ImageU8* labels,
                              const ImageU8* step_classes) {
  const int r = options.undecided_fill_radius_px;
  if (r <= 0) return;
  SSTA_CHECK(step_classes == nullptr ||
                 (step_classes->width() == labels->width() && step_classes->height() == labels->height()),
             "FillUndecidedByConsensus: step classes and labels differ in size");
  constexpr std::uint8_t kUndecided = static_cast<std::uint8_t>(TravClass::kUndecided);
  const int w = labels->width(), h = labels->height();
  bool any = false;
  for (std::size_t i = 0; i < labels->size() && !any; ++i) any = (*labels)[i] == kUndecided;
  if (!any) return;
  // Integral images of the three decided classes: (w + 1) x (h + 1), row-major, per thread.
  const std::size_t stride = static_cast<std::size_t>(w) + 1;
  // Every entry is written below except row 0 and column 0, which are cleared: no full reset.
  thread_local std::vector<std::int32_t> integral[3];
  for (auto& table : integral) {
    table.resize(stride * (h + 1));
    std::fill(table.begin(), table.begin() + stride, 0);
  }
  for (int v = 0; v < h; ++v) {
    const std::uint8_t* row = labels->row(v);
    std::int32_t run[3] = {0, 0, 0};
    for (auto& table : integral) table[(v + 1) * stride] = 0;
    for (int u = 0; u < w; ++u) {
      const std::uint8_t c = row[u];
      for (int k = 0; k < 3; ++k) {
        run[k] += c == k + 1;
        integral[k][(v + 1) * stride + u + 1] = integral[k][v * stride + u + 1] + run[k];
      }
    }
  }
  auto box = [&](int k, int u0, int v0, int u1, int v1) {  // inclusive-exclusive corners
    const std::vector<std::int32_t>& t = integral[k];
    return t[v1 * stride + u1] - t[v0 * stride + u1] - t[v1 * stride + u0] + t[v0 * stride + u0];
  };
  for (int v = 0; v < h; ++v) {
    std::uint8_t* row = labels->row(v);
    const int v0 = std::max(0, v - r), v1 = std::min(h, v + r + 1);
    for (int u = 0; u < w; ++u) {
      if (row[u] != kUndecided) continue;
      const int u0 = std::max(0, u - r), u1 = std::min(w, u + r + 1);
      int counts[3], decided = 0, best = 0;
      for (int k = 0; k < 3; ++k) {
        counts[k] = box(k, u0, v0, u1, v1);
        decided += counts[k];
        if (counts[k] > counts[best]) best = k;
      }
      // Labels change only after the window sums are taken from the integral images, so the
      // pass reads the labels as they were.
      if (decided == 0 || counts[best] < options.undecided_fill_share * decided) continue;
      const std::uint8_t fill = static_cast<std::uint8_t>(best + 1);
      // Beside a jump the noise could not place: only the obstacle's class may fill it.
      if (step_classes != nullptr && (*step_classes)(v, u) == kUndecided &&
          fill != static_cast<std::uint8_t>(TravClass::kNonTraversable)) {
        continue;
      }
      row[u] = fill;
    }
  }
}

void ApplyHiddenDrops(const ImageU8& lip, ImageU8* labels) {
  SSTA_CHECK(labels != nullptr && lip.width() == labels->width() && lip.height() == labels->height(),
             "ApplyHiddenDrops: the lip mask and the labels differ in size");
  constexpr auto kNon = static_cast<std::uint8_t>(TravClass::kNonTraversable);
  constexpr auto kUndecided = static_cast<std::uint8_t>(TravClass::kUndecided);
  constexpr std::uint8_t kSure = 255;  // the ray over the edge is steeper than max_slope_deg
  for (std::size_t i = 0; i < lip.size(); ++i) {
    std::uint8_t& label = (*labels)[i];
    if (lip[i] == 0 || label == 0 || label == kNon || label > kUndecided) continue;
    label = lip[i] == kSure ? kNon : kUndecided;
  }
}

void FillUndecidedByHeight(const Image3f& cloud, double focal_times_baseline, const VehicleOptions& vehicle,
                           const LabelRefinementOptions& options, AnalysisResult* result) {
  if (!options.undecided_height_fill || !result->quality.passed || !result->ground.found) return;
  ImageU8& labels = result->labels;
  SSTA_CHECK(cloud.width() == labels.width() && cloud.height() == labels.height(),
             "FillUndecidedByHeight: cloud and labels differ in size");
  SSTA_CHECK(focal_times_baseline > 0, "FillUndecidedByHeight: focal_times_baseline must be positive");
  const Eigen::Vector4d& plane = result->ground.plane;
  constexpr std::uint8_t kUndecided = static_cast<std::uint8_t>(TravClass::kUndecided);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (labels[i] != kUndecided || !IsFinite(cloud[i])) continue;
    const Eigen::Vector3d p = cloud[i].cast<double>();
    const double height = plane.head<3>().dot(p) + plane(3);  // signed: negative below the plane
    TravClass c = vehicle.ClassifyStep(std::abs(height));
    if (c == TravClass::kSemiTraversable && height < 0) c = TravClass::kUndecided;
    if (options.ground_tolerance_px > 0 &&
        std::abs(DisparityOffPlanePx(plane, p, focal_times_baseline)) <= options.ground_tolerance_px) {
      c = result->ground.surface_class;  // on the ground plane: the ground's class
    }
    if (c == TravClass::kTraversable || c == TravClass::kSemiTraversable) labels[i] = static_cast<std::uint8_t>(c);
  }
}

}  // namespace ssta
