// AnalysisOptions (frame_analysis.h): the fields of the YAML section `analysis`, apart from the
// analysis itself so that the config readers (and the fuzzers) link them alone.

#include "ssta/analysis/frame_analysis.h"

namespace ssta {

namespace {

using O = AnalysisOptions;

/// The paper's analysis: segments, their planes, the step reference and the quality check.
void AddSurfaceFields(OptionFields<O>& f) {
  f.push_back(Real<O>("inliers_min_ratio", &O::inliers_min_ratio, ClosedOpen(0, 1), "",
                      "inliers_min = ratio * width * height (eq. 4): smaller segments are small"));
  f.push_back(Flag<O>("pixel_slopes", &O::pixel_slopes,
                      "a traversable or semi pixel whose own normal is steeper takes that slope class "
                      "(smooth hillsides have no segment boundary), and with step_reference local a semi "
                      "pixel whose normal is gentler becomes traversable; false: the paper"));
  f.push_back(Integer<O>("pixel_slope_window_px", &O::pixel_slope_window_px, Closed(1, 255), "px",
                         "that normal is the mean over a box this wide within the pixel's segment; 1: its own")
                  .Require([](const O& o) { return o.pixel_slope_window_px % 2 == 1; }, "must be odd"));
  f.push_back(Choice<O, StepReference>("step_reference", &O::step_reference, StepReferenceNames(),
                        "dominant_plane: centroid distance to the ground plane (eq. 5) | reachable: class "
                        "of the best way from the ground across segment boundaries | reachable_large: "
                        "eq. 5, but a large segment that eq. 5 calls non-traversable takes its reachable class | "
                        "local: the largest height jump within step_radius_m of each point (the class rule "
                        "of docs/interfaces.md, section 3)"));
  f.push_back(Choice<O, SmallSegmentPolicy>("small_segments", &O::small_segments, SmallSegmentPolicyNames(),
                        "what segments below inliers_min get: paper (undecided) | obstacles (non-traversable "
                        "when off the ground by more than max_step_m or steeper than max_slope_deg) | all "
                        "(obstacles, and any with min_plane_points points gets its class)"));
  f.push_back(Integer<O>("min_plane_points", &O::min_plane_points, AtLeast(3), "points",
                         "fewest points for the slope of a small segment to count"));
  f.push_back(Real<O>("min_ground_share", &O::min_ground_share, Closed(0, 1), "",
                      "quality check: least share of the depth pixels on the ground plane"));
  f.push_back(Real<O>("max_ground_rms_m", &O::max_ground_rms_m, Above(0), "m",
                      "quality check: largest RMS of the ground plane fit"));
}

/// The label refinements after it (label_refinements.h), in the order they run.
void AddRefinementFields(OptionFields<O>& f) {
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
                         "within this radius hold (one the local steps left undecided beside a jump, only "
                         "non-traversable); 0: off"));
  f.push_back(Real<O>("undecided_fill_share", &O::undecided_fill_share, OpenClosed(0.5, 1), "",
                      "share of the window's decided pixels that must agree"));
  f.push_back(Flag<O>("undecided_height_fill", &O::undecided_height_fill,
                      "an undecided pixel left then takes the step class of its own height above the "
                      "ground plane where that is drivable"));
  f.push_back(Flag<O>("hidden_drops", &O::hidden_drops,
                      "the ground within vehicle.step_radius_m of a drop-off's lip whose foot the frame "
                      "cannot see: non-traversable where the ray over the edge descends more steeply than "
                      "vehicle.max_slope_deg, else undecided (the far side of a crest may be drivable; "
                      "map.hidden_drops weighs it)"));
  f.push_back(Flag<O>("smeared_step_blocks", &O::smeared_step_blocks,
                      "a point beside a jump above vehicle.max_step_m whose depth error along its ray "
                      "exceeds vehicle.step_radius_m (the frame cannot tell which side of the jump's band "
                      "it lies on) is non-traversable in the frame's labels; false: undecided. The map "
                      "fuses it as undecided either way"));
  f.push_back(Real<O>("label_min_texture", &O::label_min_texture, ClosedOpen(0, 128), "grey levels",
                      "pixels above the horizon whose left-image standard deviation over the stereo block "
                      "is lower are labelled unknown: the sky, where matching finds noise (below the "
                      "horizon a blank surface is a surface); 0: off"));
  f.push_back(Real<O>("texture_noise_multiple", &O::texture_noise_multiple, Closed(0, 10), "",
                      "the texture tests (label_min_texture, map.min_texture) ask for at least this many "
                      "times the image's sensor noise, estimated from the image itself, where that is more "
                      "than their grey levels: a noisy camera's sky has no texture to match; 0: off"));
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
  f.push_back(Flag<O>("face_by_height", &O::face_by_height,
                      "a face is judged as a step is, by the height its image column's run of "
                      "non-traversable pixels spans: non-traversable from vehicle.max_step_m, semi from "
                      "semi_step_m, lower no hazard (SGBM's plateaus on near ground read as faces a few cm "
                      "tall)"));
}

}  // namespace

const OptionFields<AnalysisOptions>& AnalysisOptions::Fields() {
  static const OptionFields<O> fields = [] {
    OptionFields<O> f;
    AddSurfaceFields(f);
    AddRefinementFields(f);
    return f;
  }();
  return fields;
}

bool AnalysisOptions::IsValid(std::string* error) const { return CheckOptions(*this, Fields(), error); }

}  // namespace ssta
