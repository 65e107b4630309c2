#pragma once

#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "ssta/core/option_fields.h"
#include "ssta/analysis/vehicle_options.h"
#include "ssta/core/classes.h"
#include "ssta/core/image.h"

namespace ssta {

/// What segments smaller than inliers_min get (YAML `analysis.small_segments`).
enum class SmallSegmentPolicy {
  kPaper,      ///< "paper": no verdict, undecided (the paper, eq. 4)
  /// "obstacles": a small segment whose centroid stands more than max_step_m off the ground
  /// plane, or that has at least min_plane_points points and is steeper than max_slope_deg, is
  /// non-traversable; the rest stay undecided. A centroid is robust even for a few points, a
  /// slope is not.
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
};
StepReference ParseStepReference(const std::string& name);
std::string StepReferenceName(StepReference reference);

/// YAML section `analysis`: the SSTA stage after segmentation (paper section III-E).
struct AnalysisOptions {
  /// true: after the segment verdicts, a traversable or semi-traversable pixel whose own normal
  /// is in a worse slope class takes that class (RefineByPixelSlope). On smooth terrain a
  /// hillside has no segment boundary, and one PCA slope for the whole segment averages its
  /// steep flank away. false: the paper, one verdict per segment.
  bool pixel_slopes = true;
  /// Per-pixel slopes use the mean normal of a box of this side around the pixel, within its
  /// segment [px, odd]; 1: the pixel's own normal.
  int pixel_slope_window_px = 31;
  /// How steps are measured; see StepReference.
  StepReference step_reference = StepReference::kReachableLarge;
  /// inliers_min = ratio * width * height (paper eq. 4): smaller segments get no verdict of
  /// their own in the paper.
  double inliers_min_ratio = 0.02;
  /// What small segments get; see SmallSegmentPolicy.
  SmallSegmentPolicy small_segments = SmallSegmentPolicy::kAll;
  /// Fewest points for the slope of a small segment to count [points].
  int min_plane_points = 30;
  /// Quality check of the dominant ground plane: least share of the frame's depth pixels that
  /// must lie on it, and the largest RMS point-to-plane distance [m].
  double min_ground_share = 0.08;
  double max_ground_rms_m = 0.08;
  /// Ground consistency in disparity space (RefineByGroundDisparity) [px]: a point whose
  /// disparity lies within this of the dominant ground plane's disparity on the same pixel ray
  /// is on the ground within stereo noise. Disparity noise does not grow with range, so the test
  /// holds as well at 10 m as at 2 m, where slopes of noisy far patches do not. 0: off.
  double ground_tolerance_px = 1.0;
  /// Least share of a small segment's points that must be ground-consistent for the segment to
  /// be taken as ground (traversable), (0, 1].
  double ground_consistent_share = 0.9;
  /// Fragments on a neighbour's plane (RefineByFragmentPlanes) [px]: a small segment whose
  /// points lie within this of the plane of an adjacent large segment, in disparity along their
  /// pixel rays, is a piece of that surface that stereo noise broke off. 0: off.
  double fragment_tolerance_px = 1.5;
  /// Least share of a small segment's points that must lie that close, (0, 1].
  double fragment_consistent_share = 0.9;
  /// Fewest points of a segment whose plane hosts fragments (it must also have more than twice
  /// the fragment's points); below inliers_min, a ramp seen from afar is itself a small segment.
  int fragment_host_min_points = 1000;
  /// Undecided pixels amid a consensus (FillUndecidedByConsensus): the half side of the square
  /// window around an undecided pixel [px]; 0: off.
  int undecided_fill_radius_px = 4;
  /// Least share of the window's decided pixels (classes 1..3) that must agree on one class.
  double undecided_fill_share = 0.9;
  /// Undecided pixels that no consensus fills (FillUndecidedByHeight): true, each takes the step
  /// class of its own point's height above the dominant ground plane where that is drivable
  /// (traversable, or semi-traversable above the plane); other points stay undecided.
  bool undecided_height_fill = true;
  /// Pixels whose left-image standard deviation over the stereo block is below this [grey
  /// levels] are labelled unknown (0) once the analysis is done (FramePipeline): the sky, blank
  /// walls, where the matcher's disparity is a guess. The analysis still uses their points.
  /// 0: off.
  double label_min_texture = 0.0;
  /// Thin vertical faces from the disparity (RefineByDisparityFaces): rows of the disparity
  /// fitted along each image column [px, odd, >= 3]; 0: off.
  int face_window_px = 11;
  /// Neighbouring columns whose fits are pooled with a pixel's own [px, odd]: SGBM's noise
  /// varies from column to column while curbs and steps run across many; 1: each column alone.
  int face_columns_px = 17;
  /// A face is grown along the column from its surest pixels (steeper than 70 deg) over the
  /// rows within the window whose disparity is the face's within this [px]; 0: off.
  double face_grow_tolerance_px = 0.25;
  /// A pixel whose surface rises along its image column steeper than this is on a face [deg].
  double face_min_slope_deg = 35.0;

  /// Every field: its key, unit, range and meaning (reading, writing and IsValid come from it).
  static const OptionFields<AnalysisOptions>& Fields();
  /// The first field out of its range, as "key: requirement" in `*error`.
  bool IsValid(std::string* error) const;
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

/// The dominant ground plane (paper III-E): the largest traversable segment whose normal points
/// up and which lies below the camera.
struct GroundPlane {
  bool found = false;
  int segment_id = -1;
  Eigen::Vector4d plane = Eigen::Vector4d::Zero();  ///< n . p + D = 0, n pointing up
  double camera_height_m = 0.0;  ///< camera origin above the plane [m]
  double rms_m = 0.0;            ///< RMS of its inliers to the plane [m]
  double share = 0.0;            ///< its inliers / the frame's depth pixels
};

/// Verdict of the point-cloud quality check on the ground plane.
struct QualityCheck {
  bool passed = false;
  std::string reason;  ///< empty when passed
};

struct AnalysisResult {
  std::vector<SegmentResult> segments;  ///< one per segment id, in id order
  GroundPlane ground;
  QualityCheck quality;
  int inliers_min = 0;       ///< the eq. 4 threshold used [px]
  int min_plane_points = 0;  ///< AnalysisOptions::min_plane_points used
  int depth_pixels = 0;      ///< pixels with a valid 3D point
  /// Class per pixel (image size): 0 without depth, 4 undecided, else the segment's verdict.
  ImageU8 labels;
};

/// Superpixel Surface Traversability Analysis of one frame.
///
/// `cloud`: organized points in the (rectified) camera frame, NaN invalid. `segment_ids`: per
/// pixel segment id in [0, num_segments) or -1, same size as the cloud. `up_camera`: unit
/// vector opposite to gravity, in the same camera frame. Per segment: mean and covariance,
/// PCA normal, slope vs up (eq. 3), dominant ground plane, quality check, step (eq. 5); a
/// segment's class is the worse of its slope and step classes. When the quality check fails,
/// every depth pixel is undecided and the reason is reported. Thread-safe (pure function).
AnalysisResult AnalyzeSurfaces(const Image3f& cloud, const ImageI32& segment_ids, int num_segments,
                               const Eigen::Vector3d& up_camera, const VehicleOptions& vehicle,
                               const AnalysisOptions& options);

/// Per-pixel slope refinement (AnalysisOptions::pixel_slopes): each pixel labelled
/// traversable or semi-traversable in `labels` takes the worse of its label and the slope class
/// of its own normal against `up_camera`. `normals` has the labels' size (NaN: left as is).
/// With window_px > 1 each pixel's normal is first averaged over a window_px box restricted to
/// its own segment (`segment_ids`, required then): per-pixel normals of stereo points carry a few
/// degrees of noise, and where the true slope is near a threshold the classes flicker.
void RefineByPixelSlope(const Image3f& normals, const Eigen::Vector3d& up_camera, const VehicleOptions& vehicle,
                        ImageU8* labels, const ImageI32* segment_ids = nullptr, int window_px = 1);

/// RefineByPixelSlope in two steps, so that the costly one can run beside AnalyzeSurfaces:
/// PixelSlopeClasses reads the normals and segment ids only and writes, per pixel, the class its
/// (window-averaged) slope would force on a traversable or semi-traversable label (0: none,
/// 2: semi-traversable, 3: non-traversable); ApplyPixelSlopeClasses then changes the labels.
/// The two in turn give exactly RefineByPixelSlope's labels.
void PixelSlopeClasses(const Image3f& normals, const Eigen::Vector3d& up_camera, const VehicleOptions& vehicle,
                       const ImageI32* segment_ids, int window_px, ImageU8* slope_classes);
void ApplyPixelSlopeClasses(const ImageU8& slope_classes, ImageU8* labels);

/// Ground consistency of small segments (AnalysisOptions::ground_tolerance_px > 0; needs a
/// dominant ground plane that passed the quality check, else does nothing). A point is
/// ground-consistent when |d - d_ground| <= ground_tolerance_px, with d = focal_times_baseline / Z
/// its disparity and d_ground the disparity of the ground plane along the same pixel ray. A small
/// segment (below inliers_min) that is not traversable and has at least ground_consistent_share
/// of its points consistent becomes traversable: far from the camera, stereo noise breaks the
/// ground into small fragments whose own planes tilt at random, while their disparities stay on
/// the ground's. Large segments keep their verdicts: their planes are well determined.
/// Updates result->labels and the verdicts and reasons of the segments it changes.
/// `focal_times_baseline`: f * b of the rectified pair [px * m].
void RefineByGroundDisparity(const Image3f& cloud, const ImageI32& segment_ids, double focal_times_baseline,
                             const AnalysisOptions& options, AnalysisResult* result);

/// Undecided pixels amid a consensus (AnalysisOptions::undecided_fill_radius_px > 0): an
/// undecided pixel (4) takes the class (1..3) that at least undecided_fill_share of the decided
/// pixels in the (2 r + 1)^2 window around it hold. Tiny segments along obstacle outlines and
/// in far ground get no verdict of their own (too few points for a plane); where everything
/// around them agrees, that verdict is theirs too; where the window is split (an obstacle's
/// edge against the ground), they stay undecided. One pass on the labels as they were.
void FillUndecidedByConsensus(const AnalysisOptions& options, ImageU8* labels);

/// Undecided pixels by their own height (AnalysisOptions::undecided_height_fill; needs a frame
/// that passed the quality check, else does nothing). Pixels without a normal (the smoothing
/// window broke on a depth edge) and segments of a few points get no verdict, and where an
/// obstacle's edge meets the ground no consensus fills them: the 3-5 rows on top of a curb, the
/// strip between a face and the ground. Each undecided pixel (4) with a point p takes
/// traversable when p lies within ground_tolerance_px of the dominant plane in disparity (the
/// test of RefineByGroundDisparity), else the step class of its height |n . p + D| when that is
/// traversable, or semi-traversable above the plane. Other points stay undecided: a lone point is
/// not called an obstacle, since next to a depth edge the matcher smears the farther surface's
/// disparity into the nearer one (at a drop-off's brink such points lie far below the plane);
/// and below the plane, what the camera sees of a shallow hole is mostly its far wall (a face),
/// where above it the top of a curb or a step faces the camera as much as its front does.
/// Updates result->labels. `focal_times_baseline`: f * b of the rectified pair [px * m].
void FillUndecidedByHeight(const Image3f& cloud, double focal_times_baseline, const VehicleOptions& vehicle,
                           const AnalysisOptions& options, AnalysisResult* result);

/// Thin vertical faces (AnalysisOptions::face_window_px > 0): a traversable, semi-traversable or
/// undecided pixel whose surface climbs along its image column steeper than face_min_slope_deg
/// becomes non-traversable. The disparity is fitted by a line over face_window_px rows around the
/// pixel (a window with an invalid pixel or a jump over 0.5 px between rows is skipped); with d
/// and d' = dd/dv from the fit, the surface's tangent along the column is
/// (0, 1, 0) - (u - cu, v - cv, f) * d' / d (X = ray * b / d, differentiated), and its angle to
/// the plane normal to `up_camera` is the slope tested. On level ground d' is b/h px per row
/// (h: camera height) at every range; on a face towards the camera d is constant. Faces a few
/// pixels tall (the front of a curb or a step) vanish in the normals' smoothing windows, which
/// are 31 px wide; eleven rows of disparity keep them. Each pixel takes the mean d' over the mean
/// d of the clean windows (no invalid pixel, no jump) of the face_columns_px columns around it:
/// pooling columns cuts the noise of d' that hides faces of 5 cm. A face shorter than the window
/// is flagged only where the window is centred on it; from each pixel steeper than 70 deg, the
/// rows within the window whose disparity equals the face's (within face_grow_tolerance_px,
/// the window's mean) join it.
/// `disparity` [px] and `labels` share the cropped rectified image's size; `f`, `cu`, `cv` are its
/// focal length and principal point [px].
void RefineByDisparityFaces(const ImageF& disparity, double f, double cu, double cv, const Eigen::Vector3d& up_camera,
                            const AnalysisOptions& options, ImageU8* labels);

/// RefineByDisparityFaces in two steps, so that the costly one can run beside the label steps
/// before it: FindDisparityFaces reads the disparity only and marks, per pixel, what the test
/// would make of a traversable, semi-traversable or undecided pixel there; ApplyDisparityFaces
/// then changes the labels as RefineByDisparityFaces does. Find then Apply on the same labels
/// gives exactly RefineByDisparityFaces' result.
struct DisparityFaces {
  ImageU8 marks;  ///< 0: no face; 1: on a face; 2: on a face and steep enough to grow it
  std::vector<std::pair<int, float>> seeds;  ///< pixels marked 2 (raster order): index, face disparity
};
void FindDisparityFaces(const ImageF& disparity, double f, double cu, double cv, const Eigen::Vector3d& up_camera,
                        const AnalysisOptions& options, DisparityFaces* faces);
void ApplyDisparityFaces(const DisparityFaces& faces, const ImageF& disparity, const AnalysisOptions& options,
                         ImageU8* labels);

/// Fragments (AnalysisOptions::fragment_tolerance_px > 0; needs a frame that passed the quality
/// check, else does nothing). Far from the camera, stereo noise breaks a ramp or the ground into
/// small segments whose own planes tilt at random and whose centroids may stand off the dominant
/// plane: as obstacles (small_segments: all) they paint ramps and far ground non-traversable.
/// A small segment takes the verdict of the host it touches (4-connected) whose plane holds the
/// most of its points within fragment_tolerance_px in disparity (|fb (n . p + D) / (Z D)|, the
/// test of RefineByGroundDisparity on that plane), if that is at least fragment_consistent_share
/// of them. A host is a segment with a plane not through the camera, at least
/// fragment_host_min_points points and more than twice the fragment's. A host that is itself a
/// fragment of a larger host passes that one's verdict on: a fragment takes the verdict at the
/// end of its chain of hosts, whatever the order of the segment ids.
/// Updates result->labels (pixels with depth) and the verdicts and reasons of the segments it
/// changes. `focal_times_baseline`: f * b of the rectified pair [px * m].
void RefineByFragmentPlanes(const Image3f& cloud, const ImageI32& segment_ids, double focal_times_baseline,
                            const AnalysisOptions& options, AnalysisResult* result);

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
  /// Mean point. Precondition: count() >= 1.
  Eigen::Vector3d Mean() const;
  /// Precondition: count() >= 3.
  PlaneFit Fit() const;

 private:
  int count_ = 0;
  Eigen::Vector3d sum_ = Eigen::Vector3d::Zero();
  double xx_ = 0, xy_ = 0, xz_ = 0, yy_ = 0, yz_ = 0, zz_ = 0;  ///< sums of p p^T
};

}  // namespace ssta
