#pragma once

// The paper's Superpixel Surface Traversability Analysis of one segmented frame (section III-E):
// AnalyzeSurfaces with its options and results. Which function implements which equation is
// listed at the top of src/analysis/surface_analyzer.cpp. The label refinements FrameAnalyzer
// runs after it are in label_refinements.h.

#include <string>
#include <vector>

#include <Eigen/Core>

#include "ssta/core/option_fields.h"
#include "ssta/core/vehicle_options.h"
#include "ssta/core/classes.h"
#include "ssta/core/enum_table.h"
#include "ssta/core/image.h"

namespace ssta {

/// What segments smaller than inliers_min get (YAML `analysis.small_segments`).
enum class SmallSegmentPolicy {
  kPaper,      ///< "paper": no verdict, undecided (the paper, eq. 4)
  /// "obstacles": a small segment whose centroid stands more than max_step_m off the ground
  /// plane, or that has at least min_plane_points points and is steeper than max_slope_deg, is
  /// non-traversable; the rest stay undecided. A centroid is robust even for a few points, a
  /// slope is not (the map leaves out the obstacles that a slope within the stereo noise alone
  /// makes: ObstacleBySlopeWithinNoise).
  kObstacles,
  /// "all": as obstacles, and a small segment with at least min_plane_points points gets its own
  /// slope/step class whatever it is.
  kAll,
};

/// Parses "paper", "obstacles", "all"; throws ssta::Error otherwise.
SmallSegmentPolicy ParseSmallSegmentPolicy(const std::string& name);
std::string SmallSegmentPolicyName(SmallSegmentPolicy policy);

/// What a segment's step is measured against (YAML `analysis.step_reference`).
enum class StepReference {
  /// "dominant_plane": the distance of the segment's centroid to the dominant ground plane
  /// (paper eq. 5). A hillside or the top of a long ramp reads as a tall step.
  kDominantPlane,
  /// "reachable": the step class is the smallest class over the ways to reach the segment from
  /// the dominant ground across segment boundaries, where crossing a boundary costs the median
  /// height jump between its adjacent 3D points (along up) and every segment passed on the way
  /// must be drivable by slope. Smooth ramps and hills are reached without a step; a box top,
  /// a curb or stereo noise floating in the air is not.
  kReachable,
  /// "reachable_large": eq. 5, except that a large segment (inliers_min points or more) that
  /// eq. 5 calls non-traversable takes its reachable class. A hillside or the ground beyond a
  /// rise is a large surface whose boundary jumps are measured on many pixel pairs; a small
  /// segment at range (a far box top merged with its front face, a fragment) meets its
  /// neighbours on a few noisy pairs that can read as no jump, and a step in the semi band
  /// (0.1-0.2 m by default) is within the noise of those jumps.
  kReachableLarge,
  /// "local": the rule of docs/interfaces.md, section 3: a pixel's step is the largest height
  /// jump within vehicle.step_radius_m of its point, on a height grid of the frame's points
  /// (RefineByLocalSteps); the segments get no step class of their own. Level ground is
  /// traversable at any height: a terrace's top, the floor below a drop-off.
  kLocal,
};
StepReference ParseStepReference(const std::string& name);
std::string StepReferenceName(StepReference reference);

/// The names of StepReference and SmallSegmentPolicy in config files: one table each for
/// parsing, naming and the config's choice.
const EnumTable<StepReference>& StepReferenceNames();
const EnumTable<SmallSegmentPolicy>& SmallSegmentPolicyNames();

/// What AnalyzeSurfaces reads: the paper's analysis (section III-E) and the rules it adds. Half
/// of the YAML section `analysis` (AnalysisOptions, frame_analysis.h); the label refinements
/// after it are the other half (LabelRefinementOptions, label_refinements.h).
struct SurfaceAnalysisOptions {
  // The paper's analysis (AnalyzeSurfaces).

  /// inliers_min = ratio * width * height (paper eq. 4): smaller segments get no verdict of
  /// their own in the paper.
  double inliers_min_ratio = 0.02;
  /// Quality check of the dominant ground plane: least share of the frame's depth pixels that
  /// must lie on it, and the largest RMS point-to-plane distance [m].
  double min_ground_share = 0.08;
  double max_ground_rms_m = 0.15;

  // AnalyzeSurfaces beyond the paper: steps by reachability, verdicts for small segments.

  /// How steps are measured; see StepReference.
  StepReference step_reference = StepReference::kLocal;
  /// What small segments get; see SmallSegmentPolicy.
  SmallSegmentPolicy small_segments = SmallSegmentPolicy::kAll;
  /// Fewest points for the slope of a small segment to count [points].
  int min_plane_points = 30;
};


/// One superpixel surface: its PCA plane and verdict.
struct SegmentResult {
  int id = -1;           ///< segment id in the segmentation label image
  int inliers = 0;       ///< pixels with a valid point
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();  ///< mean point, camera frame [m] (inliers >= 1)
  /// Unit normal (smallest PCA eigenvector), oriented to the up side (n . up >= 0).
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  Eigen::Vector4d plane = Eigen::Vector4d::Zero();  ///< A, B, C, D with (A,B,C) = normal
  double rms_m = 0.0;       ///< RMS point-to-plane distance [m]
  double slope_deg = 0.0;   ///< angle between the normal and up [deg]
  /// 1-sigma of slope_deg that the stereo depth noise alone gives (DepthNoise) [deg]: a point
  /// errs along its ray by k Z^2, which moves it off the plane by k Z d (d: the plane's
  /// distance from the camera), shared over a matching window; over N points spread with a
  /// variance L along the plane's fall line that tilts the plane by k Z d / sqrt(N_windows L).
  /// 0 without a noise model.
  double slope_sigma_deg = 0.0;
  /// The height its points span: sqrt(12) x their standard deviation along up (the span of
  /// points spread evenly over a face) [m].
  double rise_m = 0.0;
  /// Steeper than max_slope_deg, but by less than two slope_sigma_deg, and rising less than
  /// max_step_m: the stereo noise alone could tilt level ground this steep, and the segment
  /// stands up as no step. Its slope class stands (see ObstacleBySlopeWithinNoise).
  bool slope_within_noise = false;
  /// Step [m]: |distance| of the centroid to the ground plane (eq. 5); with step_reference
  /// "reachable" (or "reachable_large", where it applies), the mean height jump of the
  /// crossing that reached it (eq. 5 if unreached).
  /// NaN without a ground plane.
  double step_m = 0.0;
  bool has_plane = false;   ///< at least 3 points: centroid, PCA plane and slope are set
  bool small = false;       ///< fewer inliers than inliers_min
  bool ground = false;      ///< this is the dominant ground plane
  TravClass slope_class = TravClass::kUndecided;
  TravClass step_class = TravClass::kUndecided;
  TravClass verdict = TravClass::kUndecided;  ///< the class its pixels get
  std::string reason;       ///< why this verdict, for people
};

/// Whether `s` is a small segment whose only hazard is a slope that the stereo noise explains
/// (slope_within_noise, no non-traversable step): its pixels keep its class in the frame's
/// labels, and the map does not count their obstacle votes (ClassifiedPointsInWorld).
inline bool ObstacleBySlopeWithinNoise(const SegmentResult& s) {
  return s.small && s.slope_within_noise && s.step_class != TravClass::kNonTraversable;
}

/// The dominant ground plane (paper III-E): the largest traversable segment whose normal points
/// up and which lies below the camera; without one, the largest such semi-traversable segment.
struct GroundPlane {
  bool found = false;
  int segment_id = -1;
  Eigen::Vector4d plane = Eigen::Vector4d::Zero();  ///< n . p + D = 0, n pointing up
  double camera_height_m = 0.0;  ///< camera origin above the plane [m]
  /// The ground segment's slope class: traversable, or semi-traversable where no traversable
  /// segment is large enough (the vehicle on a slope it may climb, none of it level).
  TravClass surface_class = TravClass::kTraversable;
  double rms_m = 0.0;            ///< RMS of its inliers to the plane [m]
  /// RMS distance to the plane that the stereo depth noise alone gives its inliers [m]: a point
  /// at depth Z errs by k Z^2 along its ray (DepthNoise), k Z h across a plane h below the
  /// camera. 0 without a noise model.
  double noise_rms_m = 0.0;
  /// Robust scatter (1.4826 x the median absolute residual) of its inliers about the best
  /// quadratic surface: the bend of rolling ground and a few mismatches left out [m]; the
  /// plane's RMS where no such fit is possible.
  double smooth_rms_m = 0.0;
  double share = 0.0;            ///< its inliers / the frame's depth pixels
};

/// The stereo depth noise of a frame's points: a point at depth Z has a depth sigma of
/// per_m2 * Z^2, per_m2 = disparity sigma / (f b) [1/m]. 0: no noise model.
struct DepthNoise {
  double per_m2 = 0.0;
  /// [px] Side of the window over which neighbouring pixels share their error: a matcher
  /// compares windows of this side, so the pixels of one window err alike.
  int window_px = 1;
  double SigmaAt(double depth_m) const { return per_m2 * depth_m * depth_m; }
};

/// Verdict of the point-cloud quality check on the ground plane.
struct QualityCheck {
  bool passed = false;
  std::string reason;  ///< empty when passed
  /// Whether the frame's segments and pixels get verdicts: the check passed, or, under the
  /// local step rule (StepReference::kLocal), it failed only on the plane's share of the depth
  /// pixels (min_ground_share). Such a plane is plausible and smooth but holds little of the
  /// view, as on rolling ground where no one plane fits much of it; the local rule measures
  /// slopes and steps against gravity, not against the plane. Otherwise every pixel with depth
  /// is undecided (LabelRule::kQualityCheck).
  bool judged = false;
};

struct AnalysisResult {
  std::vector<SegmentResult> segments;  ///< one per segment id, in id order
  GroundPlane ground;
  QualityCheck quality;
  int inliers_min = 0;       ///< the eq. 4 threshold used [px]
  int min_plane_points = 0;  ///< SurfaceAnalysisOptions::min_plane_points used
  int depth_pixels = 0;      ///< pixels with a valid 3D point
  /// Class per pixel (image size): 0 without depth, 4 undecided, else the segment's verdict.
  ImageU8 labels;
  /// The LabelRule (label_rule.h) that set each pixel's class, as a uint8 (image size):
  /// AnalyzeSurfaces writes no_depth, quality_check, no_segment, segment or small_segment; each
  /// later step writes its rule where it changes a label.
  ImageU8 rules;
  /// The lips of drop-offs whose foot the frame cannot see (FrameAnalyzer with
  /// analysis.hidden_drops: FindHiddenDrops' weights, image size; else empty), and the range
  /// they were searched within [m]. The map takes them as they are when its own range is that.
  ImageU8 lips;
  double lips_range_m = 0.0;
};

/// Superpixel Surface Traversability Analysis of one frame.
///
/// `cloud`: organized points in the (rectified) camera frame, NaN invalid. `segment_ids`: per
/// pixel segment id in [0, num_segments) or -1, same size as the cloud. `up_camera`: unit
/// vector opposite to gravity (eq. 2's g_c), in the same camera frame. Per segment: mean and
/// covariance, PCA normal, slope vs up (eq. 3), inliers_min (eq. 4), dominant ground plane,
/// quality check, step (eq. 5); a segment's class is the worse of its slope and step classes.
/// When the quality check fails, every depth pixel is undecided and the reason is reported.
/// The check judges the ground plane's roughness beyond the depth `noise` expected at its range.
/// Thread-safe (pure function).
AnalysisResult AnalyzeSurfaces(const Image3f& cloud, const ImageI32& segment_ids, int num_segments,
                               const Eigen::Vector3d& up_camera, const VehicleOptions& vehicle,
                               const SurfaceAnalysisOptions& options, const DepthNoise& noise = {});

/// The ground's roughness beyond its smooth bend and the stereo noise: sqrt(r^2 - noise_rms^2)
/// with r the smaller of rms_m and smooth_rms_m, 0 when the noise explains all of it [m].
double GroundRoughness(const GroundPlane& ground);

/// A plane fitted by PCA to a set of points: centroid, unit normal (smallest eigenvector),
/// RMS distance. Exposed for tests and for the map.
struct PlaneFit {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  double rms_m = 0.0;
  int count = 0;
};

/// Accumulates first and second moments of points (double precision) and fits a plane.
class PlaneAccumulator {
 public:
  /// Inline: AnalyzeSurfaces adds every point of a frame (an out-of-line call per point cost
  /// ~1 ms per VGA frame). Only the six distinct products of p p^T are summed.
  void Add(const Eigen::Vector3d& p) {
    ++count_;
    sum_ += p;
    xx_ += p.x() * p.x();
    xy_ += p.x() * p.y();
    xz_ += p.x() * p.z();
    yy_ += p.y() * p.y();
    yz_ += p.y() * p.z();
    zz_ += p.z() * p.z();
  }
  int count() const { return count_; }
  /// Mean squared z (the depth of camera-frame points). Precondition: count() >= 1.
  double MeanSquaredZ() const { return zz_ / count_; }
  /// Mean point. Precondition: count() >= 1.
  Eigen::Vector3d Mean() const;
  /// The points' covariance (divided by the count) [m^2]. Precondition: count() >= 1.
  Eigen::Matrix3d Covariance() const;
  /// Precondition: count() >= 3.
  PlaneFit Fit() const;

 private:
  int count_ = 0;
  Eigen::Vector3d sum_ = Eigen::Vector3d::Zero();
  double xx_ = 0, xy_ = 0, xz_ = 0, yy_ = 0, yz_ = 0, zz_ = 0;  ///< sums of p p^T
};

}  // namespace ssta
