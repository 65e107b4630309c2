// The paper's Superpixel Surface Traversability Analysis (section III-E) of one segmented frame,
// AnalyzeSurfaces, step by step in the paper's order:
//   eq. 1   4-connected segmentation by normals: not here, Segmenter (src/geometry/segmenter.cpp)
//   PCA     mean, covariance and PCA plane per segment: SegmentMoments, PlaneAccumulator::Fit,
//           FitSegment
//   eq. 2   gravity in the camera frame: the input up_camera (GravityProvider in src/sensors/,
//           rotated into the rectified frame by FramePipeline)
//   eq. 3   slope of a segment's normal against up, and its slope class: FitSegment
//   eq. 4   inliers_min: AnalyzeSurfaces; FitSegment marks the segments below it small
//   ground  dominant ground plane: FindGroundPlane; point-cloud quality check: CheckQuality
//   eq. 5   step, the distance of a segment's centroid to the ground plane: MeasureStep
//   class   the worse of a segment's slope and step classes: DecideVerdict; per pixel: PixelLabels
// Beyond the paper, AnalyzeSurfaces also measures steps by reachability (StepReference,
// reachable_steps.cpp) and gives small segments verdicts (SmallSegmentPolicy, DecideVerdict).
// The label refinements that follow it are declared in label_refinements.h.

#include "ssta/analysis/surface_analyzer.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include <Eigen/Eigenvalues>

#include "analysis/reachable_steps.h"
#include "analysis/reason_format.h"
#include "ssta/analysis/label_rule.h"
#include "ssta/core/error.h"
#include "ssta/core/units.h"

namespace ssta {

const EnumTable<StepReference>& StepReferenceNames() {
  static const EnumTable<StepReference> table("step_reference", {{StepReference::kDominantPlane, "dominant_plane"},
                                                                 {StepReference::kReachable, "reachable"},
                                                                 {StepReference::kReachableLarge, "reachable_large"},
                                                                 {StepReference::kLocal, "local"}});
  return table;
}

const EnumTable<SmallSegmentPolicy>& SmallSegmentPolicyNames() {
  static const EnumTable<SmallSegmentPolicy> table("small_segments", {{SmallSegmentPolicy::kPaper, "paper"},
                                                                      {SmallSegmentPolicy::kObstacles, "obstacles"},
                                                                      {SmallSegmentPolicy::kAll, "all"}});
  return table;
}

StepReference ParseStepReference(const std::string& name) { return StepReferenceNames().Parse(name); }

std::string StepReferenceName(StepReference reference) { return StepReferenceNames().Name(reference); }

SmallSegmentPolicy ParseSmallSegmentPolicy(const std::string& name) { return SmallSegmentPolicyNames().Parse(name); }

std::string SmallSegmentPolicyName(SmallSegmentPolicy policy) { return SmallSegmentPolicyNames().Name(policy); }

Eigen::Vector3d PlaneAccumulator::Mean() const {
  SSTA_CHECK(count_ >= 1, "the mean of no points");
  return sum_ / count_;
}

Eigen::Matrix3d PlaneAccumulator::Covariance() const {
  SSTA_CHECK(count_ >= 1, "a covariance needs at least 1 point");
  const Eigen::Vector3d mean = sum_ / count_;
  Eigen::Matrix3d sum_sq;
  sum_sq << xx_, xy_, xz_, xy_, yy_, yz_, xz_, yz_, zz_;
  const Eigen::Matrix3d cov = sum_sq / count_ - mean * mean.transpose();
  return 0.5 * (cov + cov.transpose());
}

PlaneFit PlaneAccumulator::Fit() const {
  SSTA_CHECK(count_ >= 3, "a plane fit needs at least 3 points");
  PlaneFit fit;
  fit.count = count_;
  fit.centroid = sum_ / count_;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(Covariance());
  fit.normal = solver.eigenvectors().col(0).normalized();  // eigenvalues ascending
  fit.rms_m = std::sqrt(std::max(0.0, solver.eigenvalues()(0)));
  return fit;
}

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

/// Each segment's point moments, from one pass over the pixels, and the frame's depth pixels.
struct FrameMoments {
  std::vector<PlaneAccumulator> segments;  ///< per segment id
  int depth_pixels = 0;                    ///< pixels with a valid point
};

FrameMoments SegmentMoments(const Image3f& cloud, const ImageI32& segment_ids, int num_segments) {
  FrameMoments moments;
  moments.segments.resize(num_segments);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3f& p = cloud[i];
    if (!IsFinite(p)) continue;
    ++moments.depth_pixels;
    const int id = segment_ids[i];
    if (id >= 0) {
      SSTA_CHECK(id < num_segments, "segment id out of range");
      moments.segments[id].Add(p.cast<double>());
    }
  }
  return moments;
}

/// The slope sigma that the depth noise alone gives a plane fitted to `moments`' points
/// (SegmentResult::slope_sigma_deg) with unit normal `normal` pointing up's side [deg].
/// `cov`: the points' covariance (PlaneAccumulator::Covariance).
double SlopeSigmaDeg(const PlaneAccumulator& moments, const Eigen::Matrix3d& cov, const PlaneFit& fit,
                     const Eigen::Vector3d& normal, const Eigen::Vector3d& up_camera, const DepthNoise& noise) {
  if (noise.per_m2 <= 0.0) return 0.0;
  // Off the plane: k Z d, Z the points' RMS depth, d the plane's distance from the camera.
  const double off_plane = noise.per_m2 * std::sqrt(moments.MeanSquaredZ()) * std::abs(normal.dot(fit.centroid));
  const double windows = std::max(1.0, moments.count() / static_cast<double>(noise.window_px * noise.window_px));
  // The fall line: up's direction within the plane; on a level plane, the plane's narrower axis.
  Eigen::Vector3d fall = up_camera - up_camera.dot(normal) * normal;
  double spread = 0.0;  // the points' variance along the fall line [m^2]
  if (fall.norm() > 1e-3) {
    fall.normalize();
    spread = fall.dot(cov * fall);
  } else {
    spread = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvalues()(1);
  }
  if (spread <= 0.0) return 90.0;
  return std::min(90.0, RadToDeg(off_plane / std::sqrt(windows * spread)));
}

/// Segment `id` from its moments: small below inliers_min (eq. 4); with 3 points or more its
/// PCA plane, the normal oriented to the up side, its slope against up with the slope class
/// (eq. 3) and the slope's noise (SlopeSigmaDeg). The step is NaN until MeasureStep.
SegmentResult FitSegment(int id, const PlaneAccumulator& moments, int inliers_min, const Eigen::Vector3d& up_camera,
                         const VehicleOptions& vehicle, const DepthNoise& noise) {
  SegmentResult s;
  s.id = id;
  s.inliers = moments.count();
  s.small = s.inliers < inliers_min;
  s.step_m = std::numeric_limits<double>::quiet_NaN();
  if (s.inliers == 0) return s;
  s.centroid = moments.Mean();
  if (s.inliers < 3) {
    s.reason = "too few points for a plane";
    return s;
  }
  const PlaneFit fit = moments.Fit();
  s.has_plane = true;
  s.centroid = fit.centroid;
  s.normal = fit.normal.dot(up_camera) < 0 ? -fit.normal : fit.normal;
  s.plane << s.normal, -s.normal.dot(s.centroid);
  s.rms_m = fit.rms_m;
  s.slope_deg = RadToDeg(std::acos(std::clamp(s.normal.dot(up_camera), -1.0, 1.0)));
  s.slope_class = vehicle.ClassifySlope(s.slope_deg);
  const Eigen::Matrix3d cov = moments.Covariance();
  s.slope_sigma_deg = SlopeSigmaDeg(moments, cov, fit, s.normal, up_camera, noise);
  s.rise_m = std::sqrt(12.0 * std::max(0.0, up_camera.dot(cov * up_camera)));
  // Steeper than max_slope_deg within kSlopeNoiseSigmas of the slope's noise, and rising less
  // than a step: the noise explains the slope.
  constexpr double kSlopeNoiseSigmas = 2.0;
  s.slope_within_noise = s.slope_class == TravClass::kNonTraversable &&
                         s.slope_deg - kSlopeNoiseSigmas * s.slope_sigma_deg <= vehicle.max_slope_deg &&
                         s.rise_m <= vehicle.max_step_m;
  return s;
}

/// The dominant ground plane: the largest traversable, large-enough segment below the camera;
/// without one, the largest semi-traversable one (a vehicle climbing a slope sees no level
/// ground, and the slope it stands on is still the ground its frames are judged against).
GroundPlane FindGroundPlane(const std::vector<SegmentResult>& segments, const FrameMoments& moments,
                            const DepthNoise& noise) {
  const int depth_pixels = moments.depth_pixels;
  GroundPlane ground;
  for (const TravClass wanted : {TravClass::kTraversable, TravClass::kSemiTraversable}) {
    for (const SegmentResult& s : segments) {
      if (!s.has_plane || s.small || s.slope_class != wanted) continue;
      const double camera_height = s.plane(3);  // signed distance of the camera origin
      if (camera_height <= 0) continue;         // the plane is above the camera
      if (!ground.found || s.inliers > segments[ground.segment_id].inliers) {
        ground.found = true;
        ground.segment_id = s.id;
      }
    }
    if (ground.found) break;
  }
  if (!ground.found) return ground;
  const SegmentResult& g = segments[ground.segment_id];
  ground.surface_class = g.slope_class;
  ground.plane = g.plane;
  ground.camera_height_m = g.plane(3);
  ground.rms_m = g.rms_m;
  // Across a plane h below the camera, a point at depth Z errs by k Z^2 |n . p| / Z = k Z h.
  ground.noise_rms_m =
      noise.per_m2 * ground.camera_height_m * std::sqrt(moments.segments[ground.segment_id].MeanSquaredZ());
  ground.share = depth_pixels > 0 ? static_cast<double>(g.inliers) / depth_pixels : 0.0;
  return ground;
}

/// The scatter of the ground segment's points about the smooth quadratic surface that fits them
/// best, in the plane's own frame (heights above the plane as a quadratic of the two in-plane
/// coordinates), as a robust standard deviation: 1.4826 times the median absolute residual.
/// Unlike the plane's RMS, it leaves out the gentle bend of rolling ground (a plane through a
/// hillside's curve misses it by decimetres) and the few mismatched points that a plane's RMS
/// squares, and keeps what the quality check is for: the scatter of the ground's points.
double QuadraticRms(const Image3f& cloud, const ImageI32& segment_ids, const GroundPlane& ground) {
  const Eigen::Vector3d n = ground.plane.head<3>();
  const Eigen::Vector3d a = n.unitOrthogonal(), b = n.cross(a);
  using Vector6 = Eigen::Matrix<double, 6, 1>;
  Eigen::Matrix<double, 6, 6> normal = Eigen::Matrix<double, 6, 6>::Zero();
  Vector6 rhs = Vector6::Zero();
  int count = 0;
  // Every third pixel in raster order: the statistics need a few thousand points, not all (and
  // a stride of 3 does not alias with a pattern of rows and columns, as one of 2 x 2 would).
  std::vector<std::size_t> pixels;
  for (std::size_t i = 0; i < cloud.size(); i += 3) {
    if (segment_ids[i] == ground.segment_id) pixels.push_back(i);
  }
  for (const std::size_t i : pixels) {
    const Eigen::Vector3d p = cloud[i].cast<double>();
    const double x = a.dot(p), y = b.dot(p), h = n.dot(p) + ground.plane(3);
    Vector6 row;
    row << 1.0, x, y, x * x, x * y, y * y;
    normal.selfadjointView<Eigen::Lower>().rankUpdate(row);
    rhs += h * row;
    ++count;
  }
  if (count < 12) return ground.rms_m;
  const Eigen::Matrix<double, 6, 6> full = normal.selfadjointView<Eigen::Lower>();
  const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> solver(full);
  if (solver.info() != Eigen::Success) return ground.rms_m;
  const Vector6 coefficients = solver.solve(rhs);
  if (!coefficients.allFinite()) return ground.rms_m;
  std::vector<float> residuals;
  residuals.reserve(static_cast<std::size_t>(count));
  for (const std::size_t i : pixels) {
    const Eigen::Vector3d p = cloud[i].cast<double>();
    const double x = a.dot(p), y = b.dot(p), h = n.dot(p) + ground.plane(3);
    Vector6 row;
    row << 1.0, x, y, x * x, x * y, y * y;
    residuals.push_back(static_cast<float>(std::abs(h - coefficients.dot(row))));
  }
  auto middle = residuals.begin() + static_cast<std::ptrdiff_t>(residuals.size() / 2);
  std::nth_element(residuals.begin(), middle, residuals.end());
  return 1.4826 * *middle;
}

/// The point-cloud quality check on the dominant ground plane: a plausible camera height above
/// it, a small roughness beyond the stereo noise expected at its range (the RMS with the noise's
/// share taken out in quadrature), and a large enough share of the depth pixels. Whether the
/// frame is judged all the same: QualityCheck::judged.
QualityCheck CheckQuality(const GroundPlane& ground, const VehicleOptions& vehicle, const SurfaceAnalysisOptions& options) {
  QualityCheck quality;
  if (!ground.found) {
    quality.reason = "no dominant ground plane (no large traversable or semi-traversable segment below the camera)";
  } else if (ground.camera_height_m < vehicle.min_camera_height_m ||
             ground.camera_height_m > vehicle.max_camera_height_m) {
    quality.reason = FormatNumber("implausible camera height", ground.camera_height_m, 2, " m") +
                     FormatNumber(" above the ground plane (vehicle expects", vehicle.min_camera_height_m, 2, "") +
                     FormatNumber(" to", vehicle.max_camera_height_m, 2, " m)");
  } else if (GroundRoughness(ground) > options.max_ground_rms_m) {
    quality.reason = FormatNumber("ground plane too rough: RMS", ground.rms_m, 3, " m") +
                     FormatNumber(" (about a smooth surface", std::min(ground.rms_m, ground.smooth_rms_m), 3, " m)") +
                     FormatNumber(", of which stereo noise", ground.noise_rms_m, 3, " m") +
                     FormatNumber(": roughness", GroundRoughness(ground), 3, " m") +
                     FormatNumber(" > max_ground_rms_m", options.max_ground_rms_m, 3, "");
  } else if (ground.share < options.min_ground_share) {
    quality.reason = FormatNumber("ground plane too small: share", ground.share, 3, "") +
                     FormatNumber(" < min_ground_share", options.min_ground_share, 3, "");
    // Only the plane's share failed: the local rule does not measure against it.
    quality.judged = options.step_reference == StepReference::kLocal;
  } else {
    quality.passed = true;
    quality.judged = true;
  }
  return quality;
}

/// The step of a segment and its class: the distance of its centroid to the ground plane
/// (eq. 5) or, where step_reference asks for it and `reach` is set, its reachable class.
void MeasureStep(const GroundPlane& ground, const internal::ReachableSteps& reach, const VehicleOptions& vehicle,
                 StepReference step_reference, SegmentResult* segment) {
  SegmentResult& s = *segment;
  s.ground = s.id == ground.segment_id;
  s.step_m = s.ground ? 0.0 : std::abs(ground.plane.head<3>().dot(s.centroid) + ground.plane(3));
  if (step_reference == StepReference::kLocal) {  // the pixels' own steps come later (RefineByLocalSteps)
    s.step_class = TravClass::kTraversable;
    return;
  }
  s.step_class = vehicle.ClassifyStep(s.step_m);
  const bool by_reach = !reach.step_class.empty() && (step_reference == StepReference::kReachable ||
                                                      (!s.small && s.step_class == TravClass::kNonTraversable));
  if (by_reach) {
    s.step_class = reach.step_class[s.id];
    // Reached: the jump of the crossing that reached it; unreached: eq. 5's distance.
    if (std::isfinite(reach.jump_m[s.id])) s.step_m = reach.jump_m[s.id];
  }
}

/// A segment's verdict and its reason: the worse of its slope and step classes; a small segment
/// as small_segments says.
void DecideVerdict(int inliers_min, const SurfaceAnalysisOptions& options, SegmentResult* segment) {
  SegmentResult& s = *segment;
  if (!s.has_plane) {
    // One or two points: no slope, but their height above the ground still tells an obstacle.
    const bool obstacle =
        options.small_segments != SmallSegmentPolicy::kPaper && s.step_class == TravClass::kNonTraversable;
    s.verdict = obstacle ? TravClass::kNonTraversable : TravClass::kUndecided;
    if (obstacle) s.reason = "small segment, obstacle: step " + std::to_string(s.step_m) + " m";
    return;
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
    s.reason = "small segment (" + std::to_string(s.inliers) + " < " + std::to_string(inliers_min) + " px)";
  }
  if (s.verdict == TravClass::kNonTraversable && ObstacleBySlopeWithinNoise(s)) {
    s.reason += FormatNumber("; the stereo noise explains its slope (sigma", s.slope_sigma_deg, 1,
                             " deg) and it rises no step: the map does not count it");
  }
}

/// Class per pixel: unknown without a point, undecided without a segment, else its segment's
/// verdict; and the rule behind each (LabelRule).
void PixelLabels(const Image3f& cloud, const ImageI32& segment_ids, const std::vector<SegmentResult>& segments,
                 bool judged, AnalysisResult* result) {
  ImageU8& labels = result->labels;
  ImageU8& rules = result->rules;
  labels = ImageU8(cloud.width(), cloud.height(), static_cast<std::uint8_t>(TravClass::kUnknown));
  rules = ImageU8(cloud.width(), cloud.height(), static_cast<std::uint8_t>(LabelRule::kNoDepth));
  const auto segment_rule = static_cast<std::uint8_t>(judged ? LabelRule::kSegment : LabelRule::kQualityCheck);
  const auto small_rule =
      static_cast<std::uint8_t>(judged ? LabelRule::kSmallSegment : LabelRule::kQualityCheck);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!IsFinite(cloud[i])) continue;
    const int id = segment_ids[i];
    const TravClass c = id >= 0 ? segments[id].verdict : TravClass::kUndecided;
    labels[i] = static_cast<std::uint8_t>(c);
    rules[i] = id < 0 ? static_cast<std::uint8_t>(LabelRule::kNoSegment) : segments[id].small ? small_rule : segment_rule;
  }
}

}  // namespace

double GroundRoughness(const GroundPlane& ground) {
  const double rms = std::min(ground.rms_m, ground.smooth_rms_m);
  return std::sqrt(std::max(0.0, rms * rms - ground.noise_rms_m * ground.noise_rms_m));
}

AnalysisResult AnalyzeSurfaces(const Image3f& cloud, const ImageI32& segment_ids, int num_segments,
                               const Eigen::Vector3d& up_camera, const VehicleOptions& vehicle,
                               const SurfaceAnalysisOptions& options, const DepthNoise& noise) {
  SSTA_CHECK(cloud.width() == segment_ids.width() && cloud.height() == segment_ids.height(),
             "cloud and segment ids differ in size");
  SSTA_CHECK(std::abs(up_camera.norm() - 1.0) < 1e-6, "up_camera must be a unit vector");
  SSTA_CHECK(num_segments >= 0, "negative segment count");

  AnalysisResult result;
  result.inliers_min = static_cast<int>(
      std::ceil(options.inliers_min_ratio * cloud.width() * cloud.height()));
  result.min_plane_points = options.min_plane_points;

  const FrameMoments moments = SegmentMoments(cloud, segment_ids, num_segments);
  result.depth_pixels = moments.depth_pixels;
  result.segments.reserve(num_segments);
  for (int id = 0; id < num_segments; ++id) {
    result.segments.push_back(FitSegment(id, moments.segments[id], result.inliers_min, up_camera, vehicle, noise));
  }

  result.ground = FindGroundPlane(result.segments, moments, noise);
  // The smooth surface's scatter only matters when the plane's does not pass on its own.
  result.ground.smooth_rms_m = result.ground.rms_m;
  if (result.ground.found && GroundRoughness(result.ground) > options.max_ground_rms_m) {
    result.ground.smooth_rms_m = QuadraticRms(cloud, segment_ids, result.ground);
  }
  result.quality = CheckQuality(result.ground, vehicle, options);

  internal::ReachableSteps reach;
  if (result.quality.passed && options.step_reference != StepReference::kDominantPlane) {
    reach = internal::ReachableStepClasses(cloud, segment_ids, result.segments, result.ground.segment_id, up_camera,
                                           vehicle);
  }
  for (SegmentResult& s : result.segments) {
    if (s.inliers == 0) continue;
    if (!result.quality.judged) {
      s.verdict = TravClass::kUndecided;
      s.reason = "frame failed the quality check";
      continue;
    }
    MeasureStep(result.ground, reach, vehicle, options.step_reference, &s);
    DecideVerdict(result.inliers_min, options, &s);
  }

  PixelLabels(cloud, segment_ids, result.segments, result.quality.judged, &result);
  return result;
}

}  // namespace ssta
