#include "ssta/mount/refinement_options.h"

#include <cmath>

#include "ssta/core/error.h"

namespace ssta {
namespace {

const EnumTable<GroundReference>& GroundReferences() {
  static const EnumTable<GroundReference> table(
      "refinement.ground_reference",
      {{GroundReference::kPath, "path"}, {GroundReference::kBody, "body"}, {GroundReference::kGravity, "gravity"}});
  return table;
}

const EnumTable<RobustLoss>& RobustLosses() {
  static const EnumTable<RobustLoss> table("refinement.robust_loss",
                                           {{RobustLoss::kHuber, "huber"}, {RobustLoss::kCauchy, "cauchy"}});
  return table;
}

}  // namespace

GroundReference ParseGroundReference(const std::string& name) { return GroundReferences().Parse(name); }

std::string GroundReferenceName(GroundReference reference) { return GroundReferences().Name(reference); }

RobustLoss ParseRobustLoss(const std::string& name) { return RobustLosses().Parse(name); }

std::string RobustLossName(RobustLoss loss) { return RobustLosses().Name(loss); }

const OptionFields<RefinementOptions>& RefinementOptions::Fields() {
  using O = RefinementOptions;
  static const OptionFields<O> fields = [] {
    OptionFields<O> f;
    f.push_back(Integer<O>("points_per_frame", &O::points_per_frame, AtLeast(3), "points",
                           "ground points kept per frame after thinning"));
    f.push_back(Integer<O>("min_points_per_frame", &O::min_points_per_frame, AtLeast(3), "points",
                           "fewer: the frame is not used")
                    .Require([](const O& o) { return o.min_points_per_frame <= o.points_per_frame; },
                             "must be in [3, points_per_frame]"));
    f.push_back(Real<O>("max_range_m", &O::max_range_m, Above(0), "m", "farther ground points are not used"));
    f.push_back(Integer<O>("min_frames", &O::min_frames, AtLeast(1), "frames", "fewer usable frames: not determined"));
    f.push_back(Real<O>("point_sigma_m", &O::point_sigma_m, Above(0), "m",
                        "1-sigma of a ground point's height near the camera"));
    f.push_back(Real<O>("point_sigma_range_m", &O::point_sigma_range_m, Above(0), "m",
                        "beyond this range the point sigma grows with range"));
    f.push_back(Choice<O>("robust_loss", &O::robust_loss, RobustLosses(), "huber | cauchy"));
    f.push_back(Real<O>("loss_scale", &O::loss_scale, Above(0), "sigmas", "robust loss scale"));
    f.push_back(Choice<O>("ground_reference", &O::ground_reference, GroundReferences(),
                          "path: ground later driven over is parallel to the wheel plane standing on it (needs "
                          "poses; online and without poses: body) | body: the ground is parallel to the wheel "
                          "plane (z-up body) | gravity: the ground is level, its normal the IMU-corrected up"));
    f.push_back(Real<O>("path_half_length_m", &O::path_half_length_m, Above(0), "m",
                        "path: ground within this far ahead or behind a later pose's body is driven over"));
    f.push_back(Real<O>("path_half_width_m", &O::path_half_width_m, Above(0), "m",
                        "path: ... and within this far to its side"));
    f.push_back(Real<O>("wheelbase_m", &O::wheelbase_m, Closed(0, 10), "m",
                        "path: front to rear wheel contacts; where the way curves, the ground under a body "
                        "lies below the chord its wheels span by curvature * (wheelbase^2 / 4 - x^2) / 2 at x "
                        "ahead of its centre (0: the ground is the wheel plane along the way)"));
    f.push_back(Real<O>("track_m", &O::track_m, Closed(0, 10), "m",
                        "path: left to right wheel contacts; the same across the way, with the curvature "
                        "across from the shape of the frame's ground points; with wheelbase_m, also the twist "
                        "of a side slope that turns along the way, from the later bodies' roll (0: the ground "
                        "is the wheel plane across the way)"));
    f.push_back(Real<O>("terrain_tilt_sigma_deg", &O::terrain_tilt_sigma_deg, OpenClosed(0, 45), "deg",
                        "prior on each frame's ground tilt against the reference; limit on their scatter"));
    f.push_back(Real<O>("frame_loss_scale", &O::frame_loss_scale, Above(0), "sigmas",
                        "frames weighed by a Cauchy loss on their tilt, in sigmas of the tilts' scatter"));
    f.push_back(Real<O>("min_tilt_scatter_deg", &O::min_tilt_scatter_deg, OpenClosed(0, 45), "deg",
                        "floor on the measured scatter of the frames' tilts"));
    f.push_back(Real<O>("systematic_sigma_deg", &O::systematic_sigma_deg, Closed(0, 45), "deg",
                        "added in quadrature to the sigma of pitch and roll: errors every frame shares"));
    f.push_back(Real<O>("prior_sigma_deg", &O::prior_sigma_deg, OpenClosed(0, 45), "deg",
                        "prior on the mount correction (zero mean)"));
    f.push_back(Real<O>("max_sigma_ratio", &O::max_sigma_ratio, Open(0, 1), "",
                        "a solve is applied only when its posterior sigma is at most this times the prior's"));
    f.push_back(Real<O>("body_height_m", &O::body_height_m, {-HUGE_VAL, 10, true, false}, "m",
                        "body origin above the wheel plane; negative: unknown"));
    f.push_back(Real<O>("terrain_height_sigma_m", &O::terrain_height_sigma_m, Above(0), "m",
                        "1-sigma of each frame's ground height about body_height_m"));
    f.push_back(Flag<O>("estimate_height", &O::estimate_height, "also correct cam0's height (needs body_height_m)")
                    .Require([](const O& o) { return !o.estimate_height || o.body_height_m >= 0.0; },
                             "needs body_height_m (the camera height is otherwise unobservable)"));
    f.push_back(Real<O>("height_prior_sigma_m", &O::height_prior_sigma_m, Above(0), "m",
                        "prior on the height correction"));
    f.push_back(Integer<O>("max_iterations", &O::max_iterations, AtLeast(1), "", "solver iterations"));
    f.push_back(Flag<O>("unbiased_matching", &O::unbiased_matching,
                        "calibrate-mount matches with sgbm_mode hh4 where stereo.sgbm_mode is 3way or sgbm, and "
                        "refines the disparity over 7 px where stereo.subpixel_window_px is 0: the ground's "
                        "disparity unbiased, as a bias tilts it like a pitch error"));
    f.push_back(Flag<O>("online", &O::online,
                        "build-map refines the mount while it fuses (--refine sets it): a determined solve "
                        "replaces cam0's mount for the later frames"));
    f.push_back(Integer<O>("window_frames", &O::window_frames, AtLeast(1), "frames",
                           "online: sliding window of frames with a ground plane")
                    .Require([](const O& o) { return o.window_frames >= o.min_frames; }, "must be at least min_frames"));
    f.push_back(Integer<O>("solve_every_frames", &O::solve_every_frames, AtLeast(1), "frames",
                           "online: solve when the window first holds min_frames, then after every n-th "
                           "further frame with a ground plane"));
    return f;
  }();
  return fields;
}

bool RefinementOptions::IsValid(std::string* error) const { return CheckOptions(*this, Fields(), error); }

}  // namespace ssta
