#include "ssta/analysis/surface_analyzer.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <unordered_map>
#include <utility>

#include <Eigen/Eigenvalues>

#include "analysis/reason_format.h"
#include "ssta/core/error.h"
#include "ssta/core/units.h"

namespace ssta {
namespace {

using internal::FormatNumber;

std::string ClassReason(const SegmentResult& s) {
  std::ostringstream r;
  r << std::fixed << std::setprecision(1) << "slope " << s.slope_deg << " deg ("
    << ClassName(s.slope_class) << ")";
  if (std::isfinite(s.step_m)) {
    r << std::setprecision(3) << ", step " << s.step_m << " m (" << ClassName(s.step_class) << ")";
  }
  return r.str();
}

/// Step classes by reachability from the ground segment (StepReference::kReachable): returns
/// the class per segment (traversable / semi / non-traversable) and, in `jump_m`, the mean
/// boundary height jump of the crossing that reached it [m] (0 for the ground, NaN unreached).
std::vector<TravClass> ReachableStepClasses(const Image3f& cloud, const ImageI32& ids,
                                            const std::vector<SegmentResult>& segments, int ground_id,
                                            const Eigen::Vector3d& up, const VehicleOptions& vehicle,
                                            std::vector<double>* jump_m) {
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
  // Adjacency: the neighbour, the crossing's class by its median jump, and its mean jump.
  struct Link {
    int to;
    int step_class;
    double mean_jump;
  };
  std::vector<std::vector<Link>> links(segments.size());
  for (const auto& [key, e] : edges) {
    const int a = static_cast<int>(key >> 32), b = static_cast<int>(key & 0xffffffffu);
    const int c = 2 * e.within_semi >= e.n ? 1 : (2 * e.within_max >= e.n ? 2 : 3);
    links[a].push_back({b, c, e.sum / e.n});
    links[b].push_back({a, c, e.sum / e.n});
  }
  // Breadth-first from the ground, first over traversable crossings and segments only, then
  // also over semi-traversable ones: a segment's class is the first level that reaches it.
  std::vector<int> level(segments.size(), 0);  // 0: not reached
  jump_m->assign(segments.size(), std::numeric_limits<double>::quiet_NaN());
  level[ground_id] = 1;
  (*jump_m)[ground_id] = 0.0;
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
        (*jump_m)[link.to] = link.mean_jump;
        queue.push_back(link.to);
      }
    }
  }
  std::vector<TravClass> reach(segments.size(), TravClass::kNonTraversable);
  for (std::size_t s = 0; s < segments.size(); ++s) {
    if (level[s] != 0) reach[s] = static_cast<TravClass>(level[s]);
  }
  return reach;
}

}  // namespace

StepReference ParseStepReference(const std::string& name) {
  if (name == "dominant_plane") return StepReference::kDominantPlane;
  if (name == "reachable") return StepReference::kReachable;
  if (name == "reachable_large") return StepReference::kReachableLarge;
  throw Error("unknown step reference '" + name + "' (dominant_plane, reachable, reachable_large)");
}

std::string StepReferenceName(StepReference reference) {
  switch (reference) {
    case StepReference::kReachable:
      return "reachable";
    case StepReference::kReachableLarge:
      return "reachable_large";
    case StepReference::kDominantPlane:
      break;
  }
  return "dominant_plane";
}

SmallSegmentPolicy ParseSmallSegmentPolicy(const std::string& name) {
  if (name == "paper") return SmallSegmentPolicy::kPaper;
  if (name == "obstacles") return SmallSegmentPolicy::kObstacles;
  if (name == "all") return SmallSegmentPolicy::kAll;
  throw Error("unknown small-segment policy '" + name + "' (paper, obstacles, all)");
}

std::string SmallSegmentPolicyName(SmallSegmentPolicy policy) {
  switch (policy) {
    case SmallSegmentPolicy::kPaper: return "paper";
    case SmallSegmentPolicy::kObstacles: return "obstacles";
    case SmallSegmentPolicy::kAll: return "all";
  }
  return "obstacles";
}

const OptionFields<AnalysisOptions>& AnalysisOptions::Fields() {
  using O = AnalysisOptions;
  static const OptionFields<O> fields = [] {
    OptionFields<O> f;
    f.push_back(Real<O>("inliers_min_ratio", &O::inliers_min_ratio, ClosedOpen(0, 1), "",
                        "inliers_min = ratio * width * height (eq. 4): smaller segments are small"));
    f.push_back(Flag<O>("pixel_slopes", &O::pixel_slopes,
                        "a traversable or semi pixel whose own normal is steeper takes that slope class "
                        "(smooth hillsides have no segment boundary); false: the paper"));
    f.push_back(Integer<O>("pixel_slope_window_px", &O::pixel_slope_window_px, Closed(1, 255), "px",
                           "that normal is the mean over a box this wide within the pixel's segment; 1: its own")
                    .Require([](const O& o) { return o.pixel_slope_window_px % 2 == 1; }, "must be odd"));
    f.push_back(Choice<O>("step_reference", &O::step_reference,
                          {StepReference::kDominantPlane, StepReference::kReachable, StepReference::kReachableLarge},
                          StepReferenceName,
                          "dominant_plane: centroid distance to the ground plane (eq. 5) | reachable: class "
                          "of the best way from the ground across segment boundaries | reachable_large: "
                          "eq. 5, but a large segment that eq. 5 calls non-traversable takes its reachable class"));
    f.push_back(Choice<O>("small_segments", &O::small_segments,
                          {SmallSegmentPolicy::kPaper, SmallSegmentPolicy::kObstacles, SmallSegmentPolicy::kAll},
                          SmallSegmentPolicyName,
                          "what segments below inliers_min get: paper (undecided) | obstacles (non-traversable "
                          "when off the ground by more than max_step_m or steeper than max_slope_deg) | all "
                          "(obstacles, and any with min_plane_points points gets its class)"));
    f.push_back(Integer<O>("min_plane_points", &O::min_plane_points, AtLeast(3), "points",
                           "fewest points for the slope of a small segment to count"));
    f.push_back(Real<O>("min_ground_share", &O::min_ground_share, Closed(0, 1), "",
                        "quality check: least share of the depth pixels on the ground plane"));
    f.push_back(Real<O>("max_ground_rms_m", &O::max_ground_rms_m, Above(0), "m",
                        "quality check: largest RMS of the ground plane fit"));
    f.push_back(Real<O>("ground_tolerance_px", &O::ground_tolerance_px, Closed(0, 16), "px",
                        "a small segment whose disparities lie this close to the ground plane's is ground "
                        "(disparity noise does not grow with range); 0: off"));
    f.push_back(Real<O>("ground_consistent_share", &O::ground_consistent_share, OpenClosed(0, 1), "",
                        "share of a small segment's points that must be that close"));
    f.push_back(Real<O>("fragment_tolerance_px", &O::fragment_tolerance_px, Closed(0, 16), "px",
                        "a small segment whose points lie within this of a large neighbour's plane, in "
                        "disparity along their rays, is a piece of it and takes its verdict; 0: off"));
    f.push_back(Real<O>("fragment_consistent_share", &O::fragment_consistent_share, OpenClosed(0, 1), "",
                        "share of the small segment's points that must be that close"));
    f.push_back(Integer<O>("fragment_host_min_points", &O::fragment_host_min_points, AtLeast(3), "points",
                           "fewest points of a segment whose plane takes in fragments (and more than twice "
                           "the fragment's)"));
    f.push_back(Integer<O>("undecided_fill_radius_px", &O::undecided_fill_radius_px, Closed(0, 64), "px",
                           "an undecided pixel takes the class that undecided_fill_share of the decided pixels "
                           "within this radius hold; 0: off"));
    f.push_back(Real<O>("undecided_fill_share", &O::undecided_fill_share, OpenClosed(0.5, 1), "",
                        "share of the window's decided pixels that must agree"));
    f.push_back(Flag<O>("undecided_height_fill", &O::undecided_height_fill,
                        "an undecided pixel left then takes the step class of its own height above the "
                        "ground plane where that is drivable"));
    f.push_back(Real<O>("label_min_texture", &O::label_min_texture, ClosedOpen(0, 128), "grey levels",
                        "pixels whose left-image standard deviation over the stereo block is lower are "
                        "labelled unknown (sky, blank walls); 0: off"));
    f.push_back(OddOrOff<O>("face_window_px", &O::face_window_px, Closed(3, 63), "px",
                            "thin vertical faces (a curb's front): the disparity fitted along the image column "
                            "over this many rows gives the surface's rise along the column; 0: off"));
    f.push_back(Integer<O>("face_columns_px", &O::face_columns_px, Closed(1, 63), "px",
                           "the column fits of this many neighbouring columns are pooled; 1: each alone")
                    .Require([](const O& o) { return o.face_columns_px % 2 == 1; }, "must be odd"));
    f.push_back(Real<O>("face_min_slope_deg", &O::face_min_slope_deg, Open(0, 90), "deg",
                        "a pixel rising steeper than this along its column is on a face: non-traversable"));
    f.push_back(Real<O>("face_grow_tolerance_px", &O::face_grow_tolerance_px, Closed(0, 5), "px",
                        "rows within the window whose disparity is a face's within this join it; 0: off"));
    return f;
  }();
  return fields;
}

bool AnalysisOptions::IsValid(std::string* error) const { return CheckOptions(*this, Fields(), error); }

Eigen::Vector3d PlaneAccumulator::Mean() const {
  SSTA_CHECK(count_ >= 1, "the mean of no points");
  return sum_ / count_;
}

PlaneFit PlaneAccumulator::Fit() const {
  SSTA_CHECK(count_ >= 3, "a plane fit needs at least 3 points");
  PlaneFit fit;
  fit.count = count_;
  fit.centroid = sum_ / count_;
  Eigen::Matrix3d sum_sq;
  sum_sq << xx_, xy_, xz_, xy_, yy_, yz_, xz_, yz_, zz_;
  Eigen::Matrix3d cov = sum_sq / count_ - fit.centroid * fit.centroid.transpose();
  cov = 0.5 * (cov + cov.transpose());
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(cov);
  fit.normal = solver.eigenvectors().col(0).normalized();  // eigenvalues ascending
  fit.rms_m = std::sqrt(std::max(0.0, solver.eigenvalues()(0)));
  return fit;
}

AnalysisResult AnalyzeSurfaces(const Image3f& cloud, const ImageI32& segment_ids, int num_segments,
                               const Eigen::Vector3d& up_camera, const VehicleOptions& vehicle,
                               const AnalysisOptions& options) {
  SSTA_CHECK(cloud.width() == segment_ids.width() && cloud.height() == segment_ids.height(),
             "cloud and segment ids differ in size");
  SSTA_CHECK(std::abs(up_camera.norm() - 1.0) < 1e-6, "up_camera must be a unit vector");
  SSTA_CHECK(num_segments >= 0, "negative segment count");

  AnalysisResult result;
  result.inliers_min = static_cast<int>(
      std::ceil(options.inliers_min_ratio * cloud.width() * cloud.height()));
  result.min_plane_points = options.min_plane_points;

  // Moments per segment in one pass over the pixels.
  std::vector<PlaneAccumulator> moments(num_segments);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3f& p = cloud[i];
    if (!IsFinite(p)) continue;
    ++result.depth_pixels;
    const int id = segment_ids[i];
    if (id >= 0) {
      SSTA_CHECK(id < num_segments, "segment id out of range");
      moments[id].Add(p.cast<double>());
    }
  }

  // Plane, slope and slope class per segment (eq. 3).
  result.segments.resize(num_segments);
  for (int id = 0; id < num_segments; ++id) {
    SegmentResult& s = result.segments[id];
    s.id = id;
    s.inliers = moments[id].count();
    s.small = s.inliers < result.inliers_min;
    s.step_m = std::numeric_limits<double>::quiet_NaN();
    if (s.inliers == 0) continue;
    s.centroid = moments[id].Mean();
    if (s.inliers < 3) {
      s.reason = "too few points for a plane";
      continue;
    }
    const PlaneFit fit = moments[id].Fit();
    s.has_plane = true;
    s.centroid = fit.centroid;
    s.normal = fit.normal.dot(up_camera) < 0 ? -fit.normal : fit.normal;
    s.plane << s.normal, -s.normal.dot(s.centroid);
    s.rms_m = fit.rms_m;
    s.slope_deg = RadToDeg(std::acos(std::clamp(s.normal.dot(up_camera), -1.0, 1.0)));
    s.slope_class = vehicle.ClassifySlope(s.slope_deg);
  }

  // Dominant ground plane: the largest traversable, large-enough segment below the camera.
  GroundPlane& ground = result.ground;
  for (const SegmentResult& s : result.segments) {
    if (!s.has_plane || s.small || s.slope_class != TravClass::kTraversable) continue;
    const double camera_height = s.plane(3);  // signed distance of the camera origin
    if (camera_height <= 0) continue;         // the plane is above the camera
    if (!ground.found || s.inliers > result.segments[ground.segment_id].inliers) {
      ground.found = true;
      ground.segment_id = s.id;
    }
  }

  QualityCheck& quality = result.quality;
  if (!ground.found) {
    quality.reason = "no dominant ground plane (no large traversable segment below the camera)";
  } else {
    const SegmentResult& g = result.segments[ground.segment_id];
    ground.plane = g.plane;
    ground.camera_height_m = g.plane(3);
    ground.rms_m = g.rms_m;
    ground.share = result.depth_pixels > 0 ? static_cast<double>(g.inliers) / result.depth_pixels : 0.0;
    if (ground.camera_height_m < vehicle.min_camera_height_m ||
        ground.camera_height_m > vehicle.max_camera_height_m) {
      quality.reason = FormatNumber("implausible camera height", ground.camera_height_m, 2, " m") +
                       FormatNumber(" above the ground plane (vehicle expects", vehicle.min_camera_height_m, 2, "") +
                       FormatNumber(" to", vehicle.max_camera_height_m, 2, " m)");
    } else if (ground.rms_m > options.max_ground_rms_m) {
      quality.reason = FormatNumber("ground plane too rough: RMS", ground.rms_m, 3, " m") +
                       FormatNumber(" > max_ground_rms_m", options.max_ground_rms_m, 3, "");
    } else if (ground.share < options.min_ground_share) {
      quality.reason = FormatNumber("ground plane too small: share", ground.share, 3, "") +
                       FormatNumber(" < min_ground_share", options.min_ground_share, 3, "");
    } else {
      quality.passed = true;
    }
  }

  std::vector<TravClass> reach;
  std::vector<double> reach_jump_m;
  if (quality.passed && options.step_reference != StepReference::kDominantPlane) {
    reach = ReachableStepClasses(cloud, segment_ids, result.segments, ground.segment_id, up_camera, vehicle,
                                 &reach_jump_m);
  }

  // Step to the ground plane (eq. 5) and the verdict per segment.
  for (SegmentResult& s : result.segments) {
    if (s.inliers == 0) continue;
    if (!quality.passed) {
      s.verdict = TravClass::kUndecided;
      s.reason = "frame failed the quality check";
      continue;
    }
    s.ground = s.id == ground.segment_id;
    s.step_m = s.ground ? 0.0 : std::abs(ground.plane.head<3>().dot(s.centroid) + ground.plane(3));
    s.step_class = vehicle.ClassifyStep(s.step_m);
    const bool by_reach =
        !reach.empty() && (options.step_reference == StepReference::kReachable ||
                           (!s.small && s.step_class == TravClass::kNonTraversable));
    if (by_reach) {
      s.step_class = reach[s.id];
      // Reached: the jump of the crossing that reached it; unreached: eq. 5's distance.
      if (std::isfinite(reach_jump_m[s.id])) s.step_m = reach_jump_m[s.id];
    }
    if (!s.has_plane) {
      // One or two points: no slope, but their height above the ground still tells an obstacle.
      const bool obstacle =
          options.small_segments != SmallSegmentPolicy::kPaper && s.step_class == TravClass::kNonTraversable;
      s.verdict = obstacle ? TravClass::kNonTraversable : TravClass::kUndecided;
      if (obstacle) s.reason = "small segment, obstacle: step " + std::to_string(s.step_m) + " m";
      continue;
    }
    const TravClass worst = Worse(s.slope_class, s.step_class);
    const bool planar = s.inliers >= options.min_plane_points;  // its slope can be trusted
    const SmallSegmentPolicy policy = options.small_segments;
    if (!s.small) {
      s.verdict = worst;
      s.reason = ClassReason(s);
    } else if (policy == SmallSegmentPolicy::kAll && planar) {
      s.verdict = worst;
      s.reason = "small segment: " + ClassReason(s);
    } else if (policy != SmallSegmentPolicy::kPaper &&
               (s.step_class == TravClass::kNonTraversable ||
                (planar && s.slope_class == TravClass::kNonTraversable))) {
      s.verdict = TravClass::kNonTraversable;
      s.reason = "small segment, obstacle: " + ClassReason(s);
    } else {
      s.verdict = TravClass::kUndecided;
      s.reason = "small segment (" + std::to_string(s.inliers) + " < " +
                 std::to_string(result.inliers_min) + " px)";
    }
  }

  // Per-pixel labels.
  result.labels = ImageU8(cloud.width(), cloud.height(), static_cast<std::uint8_t>(TravClass::kUnknown));
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!IsFinite(cloud[i])) continue;
    const int id = segment_ids[i];
    const TravClass c = id >= 0 ? result.segments[id].verdict : TravClass::kUndecided;
    result.labels[i] = static_cast<std::uint8_t>(c);
  }
  return result;
}

}  // namespace ssta
