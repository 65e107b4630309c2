#include "ssta/analysis/surface_analyzer.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <unordered_map>
#include <utility>

#include <Eigen/Eigenvalues>

#include "ssta/core/error.h"
#include "ssta/core/units.h"

namespace ssta {
namespace {



std::string Format(const char* label, double value, int precision, const char* unit) {
  std::ostringstream s;
  s << label << " " << std::fixed << std::setprecision(precision) << value << unit;
  return s.str();
}

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
      quality.reason = Format("implausible camera height", ground.camera_height_m, 2, " m") +
                       Format(" above the ground plane (vehicle expects", vehicle.min_camera_height_m, 2, "") +
                       Format(" to", vehicle.max_camera_height_m, 2, " m)");
    } else if (ground.rms_m > options.max_ground_rms_m) {
      quality.reason = Format("ground plane too rough: RMS", ground.rms_m, 3, " m") +
                       Format(" > max_ground_rms_m", options.max_ground_rms_m, 3, "");
    } else if (ground.share < options.min_ground_share) {
      quality.reason = Format("ground plane too small: share", ground.share, 3, "") +
                       Format(" < min_ground_share", options.min_ground_share, 3, "");
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

namespace {

// The column step takes __restrict pointers so that the compiler vectorises it; GCC drops
// __restrict when such a function is inlined, so it stays out of line.
#if defined(__GNUC__)
#define SSTA_ANALYSIS_NOINLINE __attribute__((noinline))
#else
#define SSTA_ANALYSIS_NOINLINE
#endif

/// Sliding-window sum along one line of `n` samples, restricted to runs of equal segment id:
/// out[i] = sum of in[j] with |i - j| <= r and ids[j] == ids[i] within the run holding i.
/// `in` holds x, y, z and a weight (1 for a finite normal, 0 otherwise) per sample.
void RunSum(const Eigen::Vector4f* in, const std::int32_t* ids, int n, int r, Eigen::Vector4f* out) {
  int start = 0;
  while (start < n) {
    int end = start + 1;
    while (end < n && ids[end] == ids[start]) ++end;
    Eigen::Vector4f acc = Eigen::Vector4f::Zero();
    int lo = start, hi = start;  // acc sums [lo, hi)
    for (int i = start; i < end; ++i) {
      const int want_hi = std::min(end, i + r + 1), want_lo = std::max(start, i - r);
      while (hi < want_hi) acc += in[hi++];
      while (lo < want_lo) acc -= in[lo++];
      out[i] = acc;
    }
    start = end;
  }
}

/// Steady-state column update of one row (see SegmentBoxSums): per column, add the row entering
/// the window when it lies in the pixel's run, subtract the row leaving it when that did. The
/// masks multiply by 1 or 0, which adds exactly what the branchy update added (or exactly 0),
/// so the sums stay the same to the bit; branch-free, the loop vectorises.
SSTA_ANALYSIS_NOINLINE void ColumnStep(int n, int v, int r, const std::int32_t* __restrict run_end,
                                       const std::int32_t* __restrict run_start, const float* __restrict add,
                                       const float* __restrict sub, float* __restrict sum, float* __restrict out) {
  for (int u = 0; u < n; ++u) {
    const float in = v + r < run_end[u] ? 1.0f : 0.0f;
    const float gone = v - r - 1 >= run_start[u] ? 1.0f : 0.0f;
    for (int k = 0; k < 4; ++k) {
      const int i = 4 * u + k;
      sum[i] = (sum[i] + in * add[i]) - gone * sub[i];
      out[i] = sum[i];
    }
  }
}

/// Sums of the finite unit normals (x, y, z and their count) in a window x window box around
/// each pixel, counting only pixels of the same segment along each row and then each column
/// (separable, so O(1) per pixel). Staying inside a segment keeps a ramp's edge from blurring
/// into the ground next to it. Calls on_row(v, sums) with the sums of each row v in turn.
///
/// The row sums (RunSum) are made just in time into a ring of the 2r + 2 rows the column pass
/// needs, and the column pass runs down all columns at once, streaming rows: per column the
/// same additions and subtractions in the same order as RunSum over that column, so the same
/// sums to the bit as summing whole transposed images, with cache-resident buffers instead of
/// several frame-sized ones. Where a vertical run starts its window is summed afresh; elsewhere
/// one branch-free step (ColumnStep) adds the row entering and subtracts the row leaving, from
/// each pixel's run end found beforehand. The buffers are kept per thread (no allocation per
/// frame).
template <typename OnRow>
void SegmentBoxSums(const Image3f& normals, const ImageI32& ids, int window, OnRow&& on_row) {
  const int w = normals.width(), h = normals.height(), r = window / 2;
  const std::size_t stride = static_cast<std::size_t>(w);
  const int slots = std::min(h, 2 * r + 2);
  thread_local std::vector<Eigen::Vector4f> row_in, ring, column_sum, out, zeros;
  thread_local std::vector<std::int32_t> run_start, run_end;
  thread_local std::vector<Eigen::Vector4f*> row_slot;  // row j's slot in the ring
  row_in.resize(stride);
  ring.resize(stride * slots);
  column_sum.resize(stride);
  out.resize(stride);
  zeros.assign(stride, Eigen::Vector4f::Zero());
  run_start.resize(stride);
  run_end.resize(stride * static_cast<std::size_t>(h));
  // run_end(v, u): the first row below v where column u's id changes (h at the bottom).
  for (int v = h - 1; v >= 0; --v) {
    std::int32_t* end = run_end.data() + stride * v;
    if (v == h - 1) {
      std::fill(end, end + w, h);
      continue;
    }
    const std::int32_t* id = ids.row(v);
    const std::int32_t* below = ids.row(v + 1);
    const std::int32_t* end_below = end + stride;
    for (int u = 0; u < w; ++u) end[u] = id[u] == below[u] ? end_below[u] : v + 1;
  }
  row_slot.resize(static_cast<std::size_t>(h));
  for (int j = 0; j < h; ++j) row_slot[j] = ring.data() + stride * static_cast<std::size_t>(j % slots);
  auto row_sums = [&](int j) { return row_slot[j]; };
  int next_row = 0;  // the next row whose row sums are not made yet
  float* sum = column_sum.data()->data();
  for (int v = 0; v < h; ++v) {
    for (const int need = std::min(h - 1, v + r); next_row <= need; ++next_row) {
      const Eigen::Vector3f* n = normals.row(next_row);
      const std::int32_t* id = ids.row(next_row);
      for (int u = 0; u < w; ++u) {
        const bool ok = id[u] >= 0 && std::isfinite(n[u].x()) && std::isfinite(n[u].y()) && std::isfinite(n[u].z());
        row_in[u] = ok ? Eigen::Vector4f(n[u].x(), n[u].y(), n[u].z(), 1.0f) : Eigen::Vector4f::Zero();
      }
      RunSum(row_in.data(), id, w, r, row_sums(next_row));
    }
    const std::int32_t* id = ids.row(v);
    const std::int32_t* end = run_end.data() + stride * v;
    const Eigen::Vector4f* add = v + r < h ? row_sums(v + r) : zeros.data();
    const Eigen::Vector4f* sub = v - r - 1 >= 0 ? row_sums(v - r - 1) : zeros.data();
    ColumnStep(w, v, r, end, run_start.data(), add->data(), sub->data(), sum, out.data()->data());
    const std::int32_t* above = v > 0 ? ids.row(v - 1) : nullptr;
    for (int u = 0; u < w; ++u) {
      if (v > 0 && id[u] == above[u]) continue;
      // A run starts: its window is rows [v, min(end, v + r + 1)), added in order.
      run_start[u] = v;
      Eigen::Vector4f acc = Eigen::Vector4f::Zero();
      for (int j = v; j < std::min(end[u], v + r + 1); ++j) acc += row_sums(j)[u];
      column_sum[u] = acc;
      out[u] = acc;
    }
    on_row(v, out.data());
  }
}

}  // namespace

void RefineByPixelSlope(const Image3f& normals, const Eigen::Vector3d& up_camera, const VehicleOptions& vehicle,
                        ImageU8* labels, const ImageI32* segment_ids, int window_px) {
  SSTA_CHECK(normals.width() == labels->width() && normals.height() == labels->height(),
             "normals and labels differ in size");
  thread_local ImageU8 slope_classes;
  PixelSlopeClasses(normals, up_camera, vehicle, segment_ids, window_px, &slope_classes);
  ApplyPixelSlopeClasses(slope_classes, labels);
}

void PixelSlopeClasses(const Image3f& normals, const Eigen::Vector3d& up_camera, const VehicleOptions& vehicle,
                       const ImageI32* segment_ids, int window_px, ImageU8* slope_classes) {
  SSTA_CHECK(window_px >= 1 && window_px % 2 == 1, "RefineByPixelSlope: window_px must be odd and positive");
  if (slope_classes->width() != normals.width() || slope_classes->height() != normals.height()) {
    *slope_classes = ImageU8(normals.width(), normals.height(), 0);
  }
  const Eigen::Vector3f up = up_camera.cast<float>();
  const float cos_semi = static_cast<float>(std::cos(DegToRad(vehicle.semi_slope_deg)));
  const float cos_max = static_cast<float>(std::cos(DegToRad(vehicle.max_slope_deg)));
  // c: |cos| of the slope at the pixel; NaN compares false: no class is forced.
  auto slope_class = [&](float c) -> std::uint8_t {
    if (c < cos_max) return static_cast<std::uint8_t>(TravClass::kNonTraversable);
    if (c < cos_semi) return static_cast<std::uint8_t>(TravClass::kSemiTraversable);
    return 0;
  };
  if (window_px == 1) {
    for (std::size_t i = 0; i < normals.size(); ++i) {
      (*slope_classes)[i] = slope_class(std::abs(normals[i].dot(up)));
    }
    return;
  }
  SSTA_CHECK(segment_ids != nullptr && segment_ids->width() == normals.width() &&
                 segment_ids->height() == normals.height(),
             "RefineByPixelSlope: averaging needs segment ids of the normals' size");
  SegmentBoxSums(normals, *segment_ids, window_px, [&](int v, const Eigen::Vector4f* sums) {
    std::uint8_t* row = slope_classes->row(v);
    for (int u = 0; u < normals.width(); ++u) {
      float c = std::numeric_limits<float>::quiet_NaN();
      const Eigen::Vector3f sum = sums[u].head<3>();
      const float norm = sum.norm();
      if (sums[u][3] >= 0.5f && norm > 1e-6f) c = std::abs(sum.dot(up)) / norm;
      row[u] = slope_class(c);
    }
  });
}

// A traversable or semi-traversable pixel takes the worse of its label and its slope's class.
void ApplyPixelSlopeClasses(const ImageU8& slope_classes, ImageU8* labels) {
  SSTA_CHECK(slope_classes.width() == labels->width() && slope_classes.height() == labels->height(),
             "ApplyPixelSlopeClasses: slope classes and labels differ in size");
  for (std::size_t i = 0; i < labels->size(); ++i) {
    std::uint8_t& label = (*labels)[i];
    if (label == 1 || label == 2) label = std::max(label, slope_classes[i]);
  }
}

void RefineByGroundDisparity(const Image3f& cloud, const ImageI32& segment_ids, double focal_times_baseline,
                             const AnalysisOptions& options, AnalysisResult* result) {
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
  // Only small segments without a traversable verdict can change: the others' pixels are skipped.
  std::vector<bool> candidate(num_segments, false);
  for (const SegmentResult& seg : result->segments) {
    if (seg.id >= 0 && seg.id < num_segments) candidate[seg.id] = seg.small && seg.verdict != TravClass::kTraversable;
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
    new_class[id] = static_cast<std::uint8_t>(TravClass::kTraversable);
    any = true;
    seg.verdict = TravClass::kTraversable;
    seg.reason = Format("small, and on the ground plane within stereo noise:", 100.0 * consistent[id] / points[id],
                        0, "% of its points within ground_tolerance_px of the plane's disparity");
  }
  if (any) RelabelSegments(segment_ids, new_class, &result->labels);
}

void RefineByDisparityFaces(const ImageF& disparity, double f, double cu, double cv, const Eigen::Vector3d& up_camera,
                            const AnalysisOptions& options, ImageU8* labels) {
  if (options.face_window_px == 0) return;
  SSTA_CHECK(disparity.width() == labels->width() && disparity.height() == labels->height(),
             "RefineByDisparityFaces: disparity and labels differ in size");
  thread_local DisparityFaces faces;
  FindDisparityFaces(disparity, f, cu, cv, up_camera, options, &faces);
  ApplyDisparityFaces(faces, disparity, options, labels);
}

void FindDisparityFaces(const ImageF& disparity, double f, double cu, double cv, const Eigen::Vector3d& up_camera,
                        const AnalysisOptions& options, DisparityFaces* faces) {
  faces->seeds.clear();
  if (faces->marks.width() != disparity.width() || faces->marks.height() != disparity.height()) {
    faces->marks = ImageU8(disparity.width(), disparity.height(), 0);
  } else {
    faces->marks.Fill(0);
  }
  if (options.face_window_px == 0) return;
  SSTA_CHECK(options.face_window_px >= 3 && options.face_window_px % 2 == 1,
             "RefineByDisparityFaces: face_window_px must be odd and at least 3");
  SSTA_CHECK(options.face_columns_px >= 1 && options.face_columns_px % 2 == 1,
             "RefineByDisparityFaces: face_columns_px must be odd and at least 1");
  SSTA_CHECK(f > 0, "RefineByDisparityFaces: focal length must be positive");
  constexpr float kMaxRowJumpPx = 0.5f;  // a larger step between rows is a depth edge, not a face
  const int w = disparity.width(), h = disparity.height(), k = options.face_window_px / 2;
  const int r = options.face_columns_px / 2;
  if (h < 2 * k + 1) return;
  const Eigen::Vector3d up = up_camera.normalized();
  const double sin_min = std::sin(DegToRad(options.face_min_slope_deg));
  const double sin2_min = sin_min * sin_min;
  double sum_jj = 0.0;
  for (int j = -k; j <= k; ++j) sum_jj += static_cast<double>(j) * j;
  // Per column, slid down the rows: s1 = sum of d over the window, s2 = sum of j * d (j the row
  // offset from the centre), and how many rows of the window are invalid or jump from the row
  // above (a jump into the window's first row does not count). Invalid rows add 0 to the sums.
  thread_local std::vector<double> s1, s2;
  thread_local std::vector<int> bad;
  // Per row, prefix sums over the columns of s1 and s2, and the first and last column of each
  // run of clean columns whose window means step by at most kMaxRowJumpPx from one to the next
  // (one surface): each pixel pools the fits of up to face_columns_px columns of its run.
  thread_local std::vector<double> p1, p2;
  thread_local std::vector<int> run_first, run_last;
  s1.assign(w, 0.0);
  s2.assign(w, 0.0);
  bad.assign(w, 0);
  p1.assign(w + 1, 0.0);
  p2.assign(w + 1, 0.0);
  run_first.assign(w, 0);
  run_last.assign(w, 0);
  const double jump_sum = kMaxRowJumpPx * (2 * k + 1);  // the step limit on s1 = n * mean
  // Invalid disparities (NaN, <= 0) count 0 in the sums and 1 in `bad`; a jump from the row
  // above counts 1 in `bad` unless the row is the window's first.
  auto add_row = [&](int row, double weight_j, int sign, bool count_jump) {
    const float* d = disparity.row(row);
    const float* above = disparity.row(row > 0 ? row - 1 : row);
    for (int u = 0; u < w; ++u) {
      const bool ok = d[u] > 0.0f;
      const double x = ok ? static_cast<double>(d[u]) : 0.0;
      s1[u] += sign * x;
      s2[u] += sign * weight_j * x;
      bad[u] += sign * ((!ok) + (count_jump && std::abs(d[u] - above[u]) > kMaxRowJumpPx));
    }
  };
  for (int j = -k; j <= k; ++j) add_row(k + j, j, +1, j > -k);
  // Per pixel, with q = (dd/dv) / d from the fit and y = v - cv, the tangent along the column is
  // t = (-(u - cu) q, 1 - y q, -f q): its rise along up is up_y - q A(u) with
  // A(u) = (u - cu) up_x + y up_y + f up_z, and |t|^2 = q^2 ((u - cu)^2 + y^2 + f^2) - 2 y q + 1.
  const double n = 2 * k + 1;
  // Pixels rising steeper than kGrowSeedSlopeDeg are surely on a face: their window's mean
  // disparity (the face's, constant along the column) is kept to grow the face along the column.
  constexpr double kGrowSeedSlopeDeg = 70.0;
  const bool grow = options.face_grow_tolerance_px > 0;
  const double sin_seed = std::sin(DegToRad(kGrowSeedSlopeDeg)), sin2_seed = sin_seed * sin_seed;
  std::vector<std::pair<int, float>>& seeds = faces->seeds;
  auto joins = [&](int a, int b) { return bad[a] == 0 && bad[b] == 0 && std::abs(s1[a] - s1[b]) <= jump_sum; };
  for (int v = k;; ++v) {
    std::uint8_t* out = faces->marks.row(v);
    const double y = v - cv;
    const double a0 = -cu * up.x() + y * up.y() + f * up.z(), b0 = y * y + f * f;
    for (int u = 0; u < w; ++u) {
      p1[u + 1] = p1[u] + s1[u];
      p2[u + 1] = p2[u] + s2[u];
      run_first[u] = u > 0 && joins(u - 1, u) ? run_first[u - 1] : u;
    }
    for (int u = w - 1; u >= 0; --u) run_last[u] = u + 1 < w && joins(u, u + 1) ? run_last[u + 1] : u;
    for (int u = 0; u < w; ++u) {
      if (bad[u] != 0) continue;
      const int lo = std::max(u - r, run_first[u]), hi = std::min(u + r, run_last[u]) + 1;
      // The pooled slope over the mean disparity: q = mean(d') / mean(d) of those columns.
      const double q = (p2[hi] - p2[lo]) * n / (sum_jj * (p1[hi] - p1[lo]));
      const double du = u - cu;
      const double rise = up.y() - q * (a0 + u * up.x());
      const double norm2 = q * q * (du * du + b0) - 2.0 * y * q + 1.0;
      if (rise * rise > sin2_min * norm2) {
        out[u] = 1;
        if (grow && rise * rise > sin2_seed * norm2) {
          out[u] = 2;
          seeds.push_back({v * w + u, static_cast<float>(s1[u] / n)});
        }
      }
    }
    if (v + k + 1 >= h) break;
    // Slide the window one row down: row v - k leaves, row v + k + 1 enters; every remaining
    // row's offset j falls by one, so s2 loses the new s1 once.
    const float* leave = disparity.row(v - k);
    const float* leave_next = disparity.row(v - k + 1);
    const float* enter = disparity.row(v + k + 1);
    const float* enter_above = disparity.row(v + k);
    for (int u = 0; u < w; ++u) {
      const bool ok_out = leave[u] > 0.0f, ok_in = enter[u] > 0.0f;
      const double out_d = ok_out ? static_cast<double>(leave[u]) : 0.0;
      const double in_d = ok_in ? static_cast<double>(enter[u]) : 0.0;
      s1[u] += in_d - out_d;
      s2[u] += k * out_d + (k + 1) * in_d - s1[u];
      bad[u] += (!ok_in) + (std::abs(enter[u] - enter_above[u]) > kMaxRowJumpPx) - (!ok_out) -
                (std::abs(leave_next[u] - leave[u]) > kMaxRowJumpPx);
    }
  }
}

void ApplyDisparityFaces(const DisparityFaces& faces, const ImageF& disparity, const AnalysisOptions& options,
                         ImageU8* labels) {
  if (options.face_window_px == 0) return;
  SSTA_CHECK(faces.marks.width() == labels->width() && faces.marks.height() == labels->height() &&
                 disparity.width() == labels->width() && disparity.height() == labels->height(),
             "ApplyDisparityFaces: faces, disparity and labels differ in size");
  const int w = labels->width(), h = labels->height(), k = options.face_window_px / 2;
  // Traversable, semi-traversable and undecided pixels on a face become non-traversable; those
  // steep enough seed the growth, in raster order (the order of faces.seeds).
  thread_local std::vector<std::pair<int, float>> seeds;
  seeds.clear();
  std::size_t next_seed = 0;
  for (std::size_t i = 0; i < labels->size(); ++i) {
    const std::uint8_t mark = faces.marks[i];
    if (mark == 0) continue;
    std::uint8_t& c = (*labels)[i];
    const bool drivable = c == 1 || c == 2 || c == 4;
    if (drivable) c = static_cast<std::uint8_t>(TravClass::kNonTraversable);
    if (mark == 2) {
      if (drivable) seeds.push_back(faces.seeds[next_seed]);
      ++next_seed;
    }
  }
  // A face a few rows tall is flagged only where the window is centred on it (its rows near the
  // ground and the top straddle them): the rows within the window's reach whose disparity is
  // the face's, within face_grow_tolerance_px, join it.
  for (const auto& [index, face_d] : seeds) {
    const int v = index / w, u = index % w;
    for (int vv = std::max(0, v - k); vv <= std::min(h - 1, v + k); ++vv) {
      std::uint8_t& c = (*labels)(vv, u);
      if (c != 1 && c != 2 && c != 4) continue;
      const float d = disparity(vv, u);
      if (d > 0.0f && std::abs(d - face_d) <= options.face_grow_tolerance_px) {
        c = static_cast<std::uint8_t>(TravClass::kNonTraversable);
      }
    }
  }
}

void RefineByFragmentPlanes(const Image3f& cloud, const ImageI32& segment_ids, double focal_times_baseline,
                            const AnalysisOptions& options, AnalysisResult* result) {
  SSTA_CHECK(cloud.width() == segment_ids.width() && cloud.height() == segment_ids.height() &&
                 cloud.width() == result->labels.width() && cloud.height() == result->labels.height(),
             "RefineByFragmentPlanes: cloud, segment ids and labels differ in size");
  SSTA_CHECK(focal_times_baseline > 0, "RefineByFragmentPlanes: focal_times_baseline must be positive");
  if (!(options.fragment_tolerance_px > 0) || !result->quality.passed) return;
  constexpr double kMinPlaneDistanceM = 0.05;  // planes nearer the camera have no stable disparity
  const int num_segments = static_cast<int>(result->segments.size());
  std::vector<char> fragment(num_segments, 0), surface(num_segments, 0);
  for (const SegmentResult& seg : result->segments) {
    fragment[seg.id] = seg.small && seg.inliers > 0;
    surface[seg.id] = seg.inliers >= options.fragment_host_min_points && seg.has_plane &&
                      std::abs(seg.plane(3)) > kMinPlaneDistanceM;
  }
  // A host has a well-determined plane: at least fragment_host_min_points points, and more
  // than twice the fragment's.
  auto hosts = [&](int host, int frag) {
    return result->segments[host].inliers > 2 * result->segments[frag].inliers;
  };
  // The hosts each fragment touches (a handful at most; kept as small vectors).
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
  const int w = cloud.width(), h = cloud.height();
  for (int v = 0; v < h; ++v) {
    const std::int32_t* row = segment_ids.row(v);
    const std::int32_t* below = v + 1 < h ? segment_ids.row(v + 1) : nullptr;
    for (int u = 0; u < w; ++u) {
      if (u + 1 < w && row[u] != row[u + 1]) link(row[u], row[u + 1]);
      if (below && row[u] != below[u]) link(row[u], below[u]);
    }
  }
  // Points of each fragment within the tolerance of each touched plane.
  const double fb = focal_times_baseline;
  std::vector<int> points(num_segments, 0);
  std::vector<std::vector<int>> consistent(num_segments);
  for (int id = 0; id < num_segments; ++id) consistent[id].assign(touches[id].size(), 0);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const int id = segment_ids[i];
    if (id < 0 || id >= num_segments || touches[id].empty()) continue;
    const Eigen::Vector3d p = cloud[i].cast<double>();
    if (!(p.z() > 0)) continue;  // also NaN
    ++points[id];
    for (std::size_t k = 0; k < touches[id].size(); ++k) {
      const Eigen::Vector4d& plane = result->segments[touches[id][k]].plane;
      consistent[id][k] += std::abs(DisparityOffPlanePx(plane, p, fb)) <= options.fragment_tolerance_px;
    }
  }
  // Each fragment's host; a host may itself be a fragment of a larger host (it has more than
  // twice the points, so the chains end): a fragment takes the verdict at the end of its chain,
  // whatever the order of the segment ids.
  std::vector<int> host(num_segments, -1), share_pct(num_segments, 0);
  for (int id = 0; id < num_segments; ++id) {
    int best = -1, best_count = 0;
    for (std::size_t k = 0; k < touches[id].size(); ++k) {
      if (consistent[id][k] > best_count) {
        best_count = consistent[id][k];
        best = touches[id][k];
      }
    }
    if (best < 0 || best_count < options.fragment_consistent_share * points[id]) continue;
    host[id] = best;
    share_pct[id] = static_cast<int>(std::lround(100.0 * best_count / points[id]));
  }
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

void FillUndecidedByHeight(const Image3f& cloud, double focal_times_baseline, const VehicleOptions& vehicle,
                           const AnalysisOptions& options, AnalysisResult* result) {
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
      c = TravClass::kTraversable;
    }
    if (c == TravClass::kTraversable || c == TravClass::kSemiTraversable) labels[i] = static_cast<std::uint8_t>(c);
  }
}

void FillUndecidedByConsensus(const AnalysisOptions& options, ImageU8* labels) {
  const int r = options.undecided_fill_radius_px;
  if (r <= 0) return;
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
      if (decided > 0 && counts[best] >= options.undecided_fill_share * decided) {
        row[u] = static_cast<std::uint8_t>(best + 1);
      }
    }
  }
}

}  // namespace ssta
