#pragma once

// The label refinements FrameAnalyzer runs after the paper's analysis (AnalyzeSurfaces,
// surface_analyzer.h), each turned on by its fields of LabelRefinementOptions. They change the
// labels, and some the verdicts of segments, where the paper's one plane per segment errs on
// stereo data:
//   1. per-pixel slopes          RefineByPixelSlope       src/analysis/pixel_slopes.cpp
//   2. ground consistency        RefineByGroundDisparity  src/analysis/label_refinements.cpp
//   3. fragments                 RefineByFragmentPlanes   src/analysis/label_refinements.cpp
//   3b. local steps              RefineByLocalSteps       src/analysis/local_steps.cpp
//   4. thin faces                RefineByDisparityFaces   src/analysis/disparity_faces.cpp
//   4b. faces by their height    JudgeFacesByHeight       src/analysis/disparity_faces.cpp
//   5. fill by consensus         FillUndecidedByConsensus src/analysis/label_refinements.cpp
//   6. fill by height            FillUndecidedByHeight    src/analysis/label_refinements.cpp
//   7. hidden drops              ApplyHiddenDrops         src/analysis/label_refinements.cpp
//   8. smeared step bands        ApplySmearedStepBand     src/analysis/local_steps.cpp
// Refinements 1 and 4 also come in two steps each (find, then apply) so that their costly part
// can run beside the steps before them.

#include <utility>
#include <vector>

#include <Eigen/Core>

#include "ssta/analysis/surface_analyzer.h"
#include "ssta/core/vehicle_options.h"
#include "ssta/core/image.h"

namespace ssta {

/// What the label refinements read: the other half of the YAML section `analysis`
/// (AnalysisOptions, frame_analysis.h), after the paper's analysis (SurfaceAnalysisOptions),
/// in the order FrameAnalyzer runs them, then the texture test FramePipeline applies after them.
struct LabelRefinementOptions {
  // Refinement 1, per-pixel slopes (RefineByPixelSlope).

  /// true: after the segment verdicts, a traversable or semi-traversable pixel whose own normal
  /// is in a worse slope class takes that class. On smooth terrain a hillside has no segment
  /// boundary, and one PCA slope for the whole segment averages its steep flank away. With
  /// step_reference local (a segment's verdict is then its slope's alone) a semi-traversable
  /// pixel whose own normal is gentler than semi_slope_deg also becomes traversable: the same
  /// average hides a hillside's gentle parts. false: the paper, one verdict per segment.
  bool pixel_slopes = true;
  /// Per-pixel slopes use the mean normal of a box of this side around the pixel, within its
  /// segment [px, odd]; 1: the pixel's own normal.
  int pixel_slope_window_px = 31;

  // Refinement 2, ground consistency (RefineByGroundDisparity); refinement 6 uses the tolerance.

  /// A point whose disparity lies within this of the dominant ground plane's disparity on the
  /// same pixel ray is on the ground within stereo noise [px]. Disparity noise does not grow
  /// with range, so the test holds as well at 10 m as at 2 m, where slopes of noisy far patches
  /// do not. 0: off.
  double ground_tolerance_px = 1.0;
  /// Least share of a small segment's points that must be ground-consistent for the segment to
  /// be taken as ground (traversable), (0, 1].
  double ground_consistent_share = 0.9;

  // Refinement 3, fragments on a neighbour's plane (RefineByFragmentPlanes).

  /// A small segment whose points lie within this of the plane of an adjacent large segment, in
  /// disparity along their pixel rays, is a piece of that surface that stereo noise broke off
  /// [px]. 0: off.
  double fragment_tolerance_px = 1.5;
  /// Least share of a small segment's points that must lie that close, (0, 1].
  double fragment_consistent_share = 0.9;
  /// Fewest points of a segment whose plane hosts fragments (it must also have more than twice
  /// the fragment's points); below inliers_min, a ramp seen from afar is itself a small segment.
  int fragment_host_min_points = 1000;

  // Refinement 4, thin vertical faces from the disparity (RefineByDisparityFaces).

  /// Rows of the disparity fitted along each image column [px, odd, >= 3]; 0: off.
  int face_window_px = 0;
  /// Neighbouring columns whose fits are pooled with a pixel's own [px, odd]: SGBM's noise
  /// varies from column to column while curbs and steps run across many; 1: each column alone.
  int face_columns_px = 17;
  /// A face is grown along the column from its surest pixels (steeper than 70 deg) over the
  /// rows within the window whose disparity is the face's within this [px]; 0: off.
  double face_grow_tolerance_px = 0.25;
  /// A pixel whose surface rises along its image column steeper than this is on a face [deg].
  double face_min_slope_deg = 35.0;
  /// A face is judged by its height, as a step is (JudgeFacesByHeight): the face test's pixels
  /// stay non-traversable only where their image column's run of non-traversable pixels spans
  /// vehicle.max_step_m along up; from semi_step_m they are semi-traversable; lower, they take
  /// back the class they had. false: every face is non-traversable.
  bool face_by_height = true;

  // Refinement 5, undecided pixels amid a consensus (FillUndecidedByConsensus).

  /// The half side of the square window around an undecided pixel [px]; 0: off.
  int undecided_fill_radius_px = 4;
  /// Least share of the window's decided pixels (classes 1..3) that must agree on one class.
  double undecided_fill_share = 0.9;

  // Refinement 6, undecided pixels by their own height (FillUndecidedByHeight).

  /// true: undecided pixels that no consensus fills each take the step class of their own
  /// point's height above the dominant ground plane where that is drivable (traversable, or
  /// semi-traversable above the plane); other points stay undecided.
  bool undecided_height_fill = true;

  // Refinement 7, the lips of drop-offs whose foot the frame cannot see (ApplyHiddenDrops).

  /// true: where a view passes over an edge and lands lower, or on the far wall of a pit that
  /// hides its floor (FindHiddenDrops, src/analysis/hidden_drops.h), the ground within
  /// vehicle.step_radius_m of the edge is non-traversable when the ray over the edge descends
  /// more steeply than vehicle.max_slope_deg (no wheel may take what it hides), else undecided
  /// (it may hide the drivable far side of a crest, which a nearer view shows).
  bool hidden_drops = true;

  // Refinement 8, the band of a jump where depth noise cannot place a point (ApplySmearedStepBand).

  /// true: a pixel still undecided because its point, beside a jump above max_step_m, lies
  /// farther from the camera than the step radius can be told apart (its depth error along the
  /// ray exceeds vehicle.step_radius_m) is non-traversable in the frame's labels: the frame
  /// knows the jump is there but not on which side of its band the point lies, and missing an
  /// obstacle costs more than a false alarm. The map fuses such a pixel as undecided either way
  /// (its rule, LabelRule::kSmearedStep, says why), for frames that see it from elsewhere decide.
  /// false: it stays undecided.
  bool smeared_step_blocks = true;

  // After the analysis (FramePipeline).

  /// Pixels whose left-image standard deviation over the stereo block is below this [grey
  /// levels] are labelled unknown (0) once the analysis is done: the sky, blank walls, where the
  /// matcher's disparity is a guess. The analysis still uses their points. 0: off.
  double label_min_texture = 2.0;
  /// The texture tests (label_min_texture here, map.min_texture) ask for at least this many
  /// times the image's own sensor noise (ImageNoiseSigma) when that is more than their grey
  /// levels: a block whose grey levels vary no more than noise would has no texture to match,
  /// and a noisy camera's sky otherwise passes a fixed threshold and matches at random depths.
  /// A pure-noise block's standard deviation is the noise's, within a spread of sigma /
  /// sqrt(2 (n - 1)) (0.08 sigma over a 9 x 9 block), so 1.5 keeps it out. 0: off.
  double texture_noise_multiple = 1.5;
};

/// Per-pixel slope refinement (LabelRefinementOptions::pixel_slopes): each pixel labelled
/// traversable or semi-traversable in `labels` takes the worse of its label and the slope class
/// of its own normal against `up_camera`. `normals` has the labels' size (NaN: left as is).
/// With window_px > 1 each pixel's normal is first averaged over a window_px box restricted to
/// its own segment (`segment_ids`, required then): per-pixel normals of stereo points carry a few
/// degrees of noise, and where the true slope is near a threshold the classes flicker.
/// `gentler_too`: as ApplyPixelSlopeClasses's.
void RefineByPixelSlope(const Image3f& normals, const Eigen::Vector3d& up_camera, const VehicleOptions& vehicle,
                        ImageU8* labels, const ImageI32* segment_ids = nullptr, int window_px = 1,
                        bool gentler_too = false);

/// RefineByPixelSlope in two steps, so that the costly one can run beside AnalyzeSurfaces:
/// PixelSlopeClasses reads the normals and segment ids only and writes, per pixel, the slope
/// class of its (window-averaged) normal (0: no normal, 1..3); ApplyPixelSlopeClasses then
/// gives each traversable or semi-traversable label the worse of it and its slope's class.
/// The two in turn give exactly RefineByPixelSlope's labels. With `gentler_too`, a
/// semi-traversable label whose slope is traversable also becomes traversable: for labels that
/// come from segments' slopes alone (SurfaceAnalysisOptions::step_reference local), where a
/// segment's one plane averages a hillside whose slope crosses semi_slope_deg within it.
void PixelSlopeClasses(const Image3f& normals, const Eigen::Vector3d& up_camera, const VehicleOptions& vehicle,
                       const ImageI32* segment_ids, int window_px, ImageU8* slope_classes);
void ApplyPixelSlopeClasses(const ImageU8& slope_classes, ImageU8* labels, bool gentler_too = false);

/// Ground consistency of small segments (LabelRefinementOptions::ground_tolerance_px > 0; needs a
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
                             const LabelRefinementOptions& options, AnalysisResult* result);

/// Fragments (LabelRefinementOptions::fragment_tolerance_px > 0; needs a frame that passed the quality
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
                            const LabelRefinementOptions& options, AnalysisResult* result);

/// Thin vertical faces (LabelRefinementOptions::face_window_px > 0): a traversable, semi-traversable or
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
                            const LabelRefinementOptions& options, ImageU8* labels);

/// Faces by their height (LabelRefinementOptions::face_by_height). `before`: the labels just
/// before the face test; `labels`: after it. Each image column's run of consecutive
/// non-traversable pixels that holds a pixel the test made so (non-traversable in `labels`, not
/// in `before`) spans a height: its points' highest minus lowest along `up_camera`. The run
/// counts the pixels other rules made non-traversable too: a face continues the obstacle they
/// found above or below it. A run of at least vehicle.max_step_m stays non-traversable; below
/// that, the test's pixels take back their classes from `before`, but traversable and undecided
/// ones become semi-traversable where the run reaches semi_step_m. Under the class rule of
/// docs/interfaces.md, section 3, a face lower than the semi step is no hazard; the matcher's
/// fronto-parallel plateaus on near ground (SGBM's smoothness prefers them) are such faces, a
/// few centimetres tall.
void JudgeFacesByHeight(const Image3f& cloud, const Eigen::Vector3d& up_camera, const VehicleOptions& vehicle,
                        const ImageU8& before, ImageU8* labels);

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
                        const LabelRefinementOptions& options, DisparityFaces* faces);
void ApplyDisparityFaces(const DisparityFaces& faces, const ImageF& disparity, const LabelRefinementOptions& options,
                         ImageU8* labels);

/// Undecided pixels amid a consensus (LabelRefinementOptions::undecided_fill_radius_px > 0): an
/// undecided pixel (4) takes the class (1..3) that at least undecided_fill_share of the decided
/// pixels in the (2 r + 1)^2 window around it hold. Tiny segments along obstacle outlines and
/// in far ground get no verdict of their own (too few points for a plane); where everything
/// around them agrees, that verdict is theirs too; where the window is split (an obstacle's
/// edge against the ground), they stay undecided. One pass on the labels as they were.
/// `step_classes` (optional, LocalStepClasses' output, the labels' size): a pixel it holds
/// undecided (4), a point smeared over the step radius beside a jump above max_step_m, takes
/// only non-traversable. The local step rule left it undecided because the noise allows the
/// obstacle's band as well as open ground; ground around it agreeing is no evidence either way.
void FillUndecidedByConsensus(const LabelRefinementOptions& options, ImageU8* labels,
                              const ImageU8* step_classes = nullptr);

/// Undecided pixels by their own height (LabelRefinementOptions::undecided_height_fill; needs a frame
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
                           const LabelRefinementOptions& options, AnalysisResult* result);

/// The lips of drop-offs whose foot the frame cannot see (LabelRefinementOptions::hidden_drops):
/// `lip` is FindHiddenDrops' mask of the frame (0: no lip; else 255 min(1, tan(ray) /
/// tan(max_slope)), the ray over the edge). A lip pixel labelled traversable, semi-traversable or
/// undecided becomes non-traversable at 255 and undecided below, where the frame cannot tell a
/// drop from a crest's far side; unknown and non-traversable pixels keep their labels.
void ApplyHiddenDrops(const ImageU8& lip, ImageU8* labels);

/// Local steps (SurfaceAnalysisOptions::step_reference "local"): the step of the rule of
/// docs/interfaces.md, section 3, measured on the frame's own points below the camera (above it
/// lies nothing the wheels meet, and the sky's false matches lie there). The points go into a grid
/// of horizontal cells (half the step radius wide, in the frame levelled by `up_camera`), each
/// with its mean height, the vertical noise of its points (`noise`: k Z |up . p| for a point at
/// depth Z) and the local gradient of its mean normal (level for a face steeper than
/// max_slope_deg, which is judged by the jump it spans). A cell's step is the largest height
/// difference, beyond that gradient and one sigma of noise on either side, between the cells
/// within vehicle.step_radius_m of it. Each pixel labelled 1-3 takes the worse of its label and
/// its cell's step class; an undecided pixel within the radius of a jump above max_step_m
/// becomes non-traversable. A point whose depth error along its ray (k Z |p|) exceeds the step
/// radius cannot tell which side of a jump it lies on: beside a jump above max_step_m (its cell's
/// step) a traversable or semi-traversable label becomes undecided, for missing an obstacle costs
/// more than a false alarm and the noise allows either; elsewhere its label stays as it was. Points
/// smeared over twice the radius stay out of the grid. All images share the cloud's size.
void RefineByLocalSteps(const Image3f& cloud, const Image3f& normals, const Eigen::Vector3d& up_camera,
                        const VehicleOptions& vehicle, const DepthNoise& noise, ImageU8* labels);

/// RefineByLocalSteps in two steps, so that the costly one can run beside the refinements before
/// it: LocalStepClasses reads the cloud and normals only and writes, per pixel, the step class of
/// its point (0: none, its point is missing or smeared over twice the radius; 4, undecided: smeared
/// over the radius beside a jump above max_step_m); ApplyLocalStepClasses then changes
/// the labels. The two in turn give exactly RefineByLocalSteps' labels.
/// `supported` (optional, the cloud's size): points where it is 0 stay out of the grid and get
/// no step class. Points above the camera's level stay out of the grid's heights too (tree
/// crowns and eaves over the ground are nothing the wheels meet), but for those that lie more
/// than max_step_m below the plane through the camera parallel to the frame's ground, placed
/// within the step radius: up a slope the ground ahead and what stands on it rise above the
/// camera's level. `ground_up` is that ground's upward unit normal in the camera frame; null
/// (or up_camera) keeps the camera's level alone. The margin stands for the error of a fitted
/// plane's normal: a degree of it is 0.2 m at 12 m.
void LocalStepClasses(const Image3f& cloud, const Image3f& normals, const Eigen::Vector3d& up_camera,
                      const VehicleOptions& vehicle, const DepthNoise& noise, ImageU8* step_classes,
                      const ImageU8* supported = nullptr, const Eigen::Vector3d* ground_up = nullptr);
void ApplyLocalStepClasses(const ImageU8& step_classes, ImageU8* labels);

/// The band of a jump that depth noise keeps the frame from placing
/// (LabelRefinementOptions::smeared_step_blocks): each pixel labelled undecided (4) whose step
/// class in `step_classes` (LocalStepClasses' output, the labels' size) is undecided, a point
/// smeared over the step radius beside a jump above max_step_m, becomes non-traversable; every
/// other label stays as it is.
void ApplySmearedStepBand(const ImageU8& step_classes, ImageU8* labels);

}  // namespace ssta
