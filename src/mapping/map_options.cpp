#include "ssta/mapping/map_options.h"

#include <cmath>

#include "ssta/core/error.h"

namespace ssta {
namespace {

/// The class evidence's fields, appended to `f` in the order MapOptions::Fields lists them.
void AddClassEvidenceFields(OptionFields<MapOptions>* f) {
  using O = MapOptions;
  f->push_back(Real<O>("class_hit_log_odds", &O::class_hit_log_odds, Above(0), "",
                       "added to the observed class's log-odds"));
  f->push_back(Real<O>("class_miss_log_odds", &O::class_miss_log_odds, {-HUGE_VAL, 0, true, false}, "",
                       "added to the two other classes' log-odds"));
  f->push_back(Real<O>("class_free_decay_log_odds", &O::class_free_decay_log_odds, AtLeast(0), "",
                       "a ray through a voxel moves its class log-odds this much towards 0"));
  f->push_back(Real<O>("class_obstacle_gain", &O::class_obstacle_gain, Closed(1, 10), "",
                       "a frame's non-traversable verdict adds this many times the hit (and miss) log-odds: "
                       "missing an obstacle costs more than a false alarm")
                   .AbsentMeans(1.0));
  f->push_back(Real<O>("class_worst_share", &O::class_worst_share, Closed(0, 1), "",
                       "a frame's verdict for a voxel is the worst class this share of its points reach, each "
                       "class counted with the worse ones: a voxel on the edge of an obstacle band is the "
                       "band's (0: the plurality of its points)")
                   .AbsentMeans(0.0));
  f->push_back(Real<O>("class_vote_noise_steps", &O::class_vote_noise_steps, Closed(0, 10), "",
                       "a frame's vote counts 1 / (1 + (sigma / (k vehicle.max_step_m))^2), sigma the height "
                       "noise of its points in the voxel, k this (0: every vote counts 1)")
                   .AbsentMeans(0.0));
  f->push_back(Real<O>("class_vote_smear_radii", &O::class_vote_smear_radii, Closed(0, 100), "",
                       "a frame's vote also counts 1 / (1 + (sigma_xy / (k vehicle.step_radius_m))^2), sigma_xy "
                       "the horizontal noise of its points in the voxel, k this (0: no such weighting)")
                   .AbsentMeans(0.0));
  f->push_back(Real<O>("class_prior_traversable_log_odds", &O::class_prior_traversable_log_odds, Closed(0, 10), "",
                       "added to the traversable log-odds when a column is judged: weak evidence leaves open "
                       "ground traversable with a lower confidence instead of blocking it")
                   .AbsentMeans(0.0));
  f->push_back(Real<O>("class_min_evidence_views", &O::class_min_evidence_views, Closed(0, 100), "views",
                       "a voxel's votes are a verdict only when some class's log-odds reaches this many "
                       "clear views from 0 (a clear view adds class_hit_log_odds, times class_obstacle_gain "
                       "for an obstacle): ground no view resolved is undecided, not traversable by the "
                       "prior alone (0: any vote is a verdict)")
                   .AbsentMeans(0.0));
  f->push_back(Real<O>("class_prior_min_evidence_views", &O::class_prior_min_evidence_views, Closed(0, 100),
                       "views",
                       "the open-ground prior may make a voxel whose votes lean to an obstacle traversable only "
                       "when they hold this many clear views; weaker, it is undecided, not open by the prior's "
                       "word (0: the prior always answers)")
                   .AbsentMeans(0.0));
  f->push_back(Real<O>("class_obstacle_min_evidence_views", &O::class_obstacle_min_evidence_views, Closed(0, 100),
                       "views",
                       "the frames alone call a voxel non-traversable only when its obstacle log-odds hold this "
                       "many clear views; weaker (what stereo noise at the views' range can make), it is "
                       "undecided, not blocked (0: any obstacle lead is a verdict)")
                   .AbsentMeans(0.0));
  f->push_back(Real<O>("class_surface_miss_prob", &O::class_surface_miss_prob, ClosedOpen(0, 1), "",
                       "chance that a fused surface finding open ground misses a hazard the frames saw (a "
                       "lip whose floor is hidden, a thin obstacle): its probabilities are mixed with this "
                       "much of a uniform one before they multiply the frames' (0: its word is final)")
                   .AbsentMeans(0.0));
  f->push_back(Flag<O>("class_smeared_surface_hazards", &O::class_smeared_surface_hazards,
                       "where the fused heights are too far to place a jump within the step radius, the "
                       "surface is judged again over the disc widened along the ray by their horizontal "
                       "sigma; a jump or slope above max there (2 sigmas) leaves a column that is not "
                       "otherwise non-traversable undecided (false: the frames' votes decide it)")
                   .AbsentMeans(false));
  f->push_back(Real<O>("class_clamp_min", &O::class_clamp_min, Open(-50, 0), "", "class log-odds lower clamp"));
  f->push_back(Real<O>("class_clamp_max", &O::class_clamp_max, Open(0, 50), "", "class log-odds upper clamp"));
}

}  // namespace

const OptionFields<MapOptions>& MapOptions::Fields() {
  using O = MapOptions;
  static const OptionFields<O> fields = [] {
    OptionFields<O> f;
    f.push_back(Real<O>("resolution_m", &O::resolution_m, OpenClosed(0.005, 10), "m", "voxel edge"));
    f.push_back(Real<O>("max_range_m", &O::max_range_m, OpenClosed(0, 1000), "m",
                        "farther points only clear free space up to this range"));
    f.push_back(Real<O>("occupancy_hit_prob", &O::occupancy_hit_prob, Open(0.5, 1), "",
                        "P(occupied) of a voxel a point falls in"));
    f.push_back(Real<O>("occupancy_miss_prob", &O::occupancy_miss_prob, Open(0, 0.5), "",
                        "P(occupied) of a voxel a ray passes through"));
    f.push_back(Real<O>("occupancy_clamp_min_prob", &O::occupancy_clamp_min_prob, Open(0, 0.5), "",
                        "occupancy log-odds are clamped to [min, max] probability"));
    f.push_back(Real<O>("occupancy_clamp_max_prob", &O::occupancy_clamp_max_prob, Open(0.5, 1), "", "upper clamp"));
    f.push_back(Real<O>("occupied_threshold_prob", &O::occupied_threshold_prob, Open(0, 1), "",
                        "a voxel is occupied at P >= this")
                    .Require([](const O& o) {
                      return o.occupied_threshold_prob > o.occupancy_clamp_min_prob &&
                             o.occupied_threshold_prob < o.occupancy_clamp_max_prob;
                    }, "must lie strictly between occupancy_clamp_min_prob and occupancy_clamp_max_prob"));
    AddClassEvidenceFields(&f);
    f.push_back(Real<O>("free_space_clearance_m", &O::free_space_clearance_m, Closed(0, 5), "m",
                        "rays stop clearing where they come this close (in height) to their end: "
                        "clearance / sin(elevation) short, at most 2 m (0: off)"));
    f.push_back(Integer<O>("free_space_ray_cell", &O::free_space_ray_cell, Closed(1, 8), "voxels",
                           "rays whose ends share a cell this many voxels wide are cast once, to their mean "
                           "(1: exact; 1, 2, 4 or 8)")
                    .Require([](const O& o) { return (o.free_space_ray_cell & (o.free_space_ray_cell - 1)) == 0; },
                             "must be 1, 2, 4 or 8 voxels")
                    .AbsentMeans(1.0));
    f.push_back(Real<O>("free_space_obstacle_shortening_per_m2", &O::free_space_obstacle_shortening_per_m2,
                        {-HUGE_VAL, 1, true, false}, "1/m",
                        "rays to obstacles stop k r^2 short of their end (r: range), the band of stereo's "
                        "depth noise, instead of the clearance's; negative: off")
                    .AbsentMeans(-1.0));
    f.push_back(Flag<O>("free_space_keeps_traversable", &O::free_space_keeps_traversable,
                        "rays leave voxels the map holds as traversable as they are (grazing rays beyond a "
                        "crest would erode seen ground); obstacles and undecided voxels still clear")
                    .AbsentMeans(false));
    f.push_back(Real<O>("free_space_no_return_stop_prob", &O::free_space_no_return_stop_prob, Open(0, 1), "",
                        "rays that ranged nothing (blank sky) stop clearing at the first voxel this likely "
                        "occupied: a surface the map is sure of, and what lies behind it, keep their evidence")
                    .Require([](const O& o) {
                      return o.free_space_no_return_stop_prob > o.occupancy_clamp_min_prob &&
                             o.free_space_no_return_stop_prob < o.occupancy_clamp_max_prob;
                    }, "must lie strictly between occupancy_clamp_min_prob and occupancy_clamp_max_prob")
                    .AbsentMeans(0.95));
    return f;
  }();
  return fields;
}

bool MapOptions::IsValid(std::string* error) const { return CheckOptions(*this, Fields(), error); }


const OptionFields<MappingOptions>& MappingOptions::Fields() {
  using O = MappingOptions;
  static const OptionFields<O> fields = [] {
    OptionFields<O> f;
    for (const OptionField<MapOptions>& field : MapOptions::Fields()) f.push_back(field.Within(&O::fusion));
    f.push_back(Integer<O>("pixel_stride", &O::pixel_stride, Closed(1, 64), "",
                           "insert every n-th pixel in u and v"));
    f.push_back(Real<O>("min_texture", &O::min_texture, ClosedOpen(0, 128), "grey levels",
                        "pixels above the horizon whose left-image standard deviation over the stereo block "
                        "is lower are not inserted (the sky's noise matches)"));
    f.push_back(OddOrOff<O>("subpixel_window_px", &O::subpixel_window_px, Closed(1, 31), "px",
                            "points at the disparity refined to sub-pixel precision over this window; the "
                            "classification keeps the matcher's. 0: off"));
    f.push_back(Flag<O>("hidden_drops", &O::hidden_drops,
                        "the lip of a drop-off whose foot a frame cannot see (a view over an edge that lands "
                        "lower by more than vehicle.max_step_m beyond noise, or on the far wall of a pit "
                        "that hides its floor) is non-traversable within vehicle.step_radius_m of the edge, "
                        "and so is the far rim of such a pit"));
    f.push_back(Integer<O>("no_return_stride_px", &O::no_return_stride_px, Closed(0, 64), "px",
                           "every n-th pixel above the horizon that the texture test left without a point "
                           "casts a ray that ranged nothing: the voxels the map holds along it are free space up "
                           "to the first one it is sure of (free_space_no_return_stop_prob) or the range, which "
                           "clears the matcher's noise carried into the sky; 0: off"));
    f.push_back(Flag<O>("auto_range", &O::auto_range,
                        "the range follows the rig: the depth at which its stereo depth noise reaches "
                        "range_depth_sigma_m replaces max_range_m"));
    f.push_back(Real<O>("range_depth_sigma_m", &O::range_depth_sigma_m, OpenClosed(0, 10), "m",
                        "the depth noise (1-sigma) at the auto range"));
    f.push_back(Integer<O>("checkpoint_every_frames", &O::checkpoint_every_frames, AtLeast(0), "frames",
                           "save the map every n frames while building (0: never)"));
    return f;
  }();
  return fields;
}

MapOptions MappingOptions::FusionFor(double focal_times_baseline, double disparity_sigma_px) const {
  MapOptions o = fusion;
  if (auto_range && focal_times_baseline > 0 && disparity_sigma_px > 0) {
    o.max_range_m = std::min(1000.0, std::sqrt(range_depth_sigma_m * focal_times_baseline / disparity_sigma_px));
  }
  return o;
}

bool MappingOptions::IsValid(std::string* error) const { return CheckOptions(*this, Fields(), error); }

}  // namespace ssta
