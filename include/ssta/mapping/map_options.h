#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "ssta/core/option_fields.h"
#include "ssta/core/vehicle_options.h"
#include "ssta/mapping/recording_fingerprint.h"

namespace ssta {

/// How a TraversabilityMap fuses frames. The defaults are OctoMap's sensor model for occupancy
/// and a matching one for the class evidence; they suit stereo at 0.1 m voxels.
///
/// Occupancy is one log-odds per voxel (OctoMap's); class evidence is three more log-odds per
/// voxel, one for each of traversable, semi-traversable and non-traversable (docs/interfaces.md,
/// section 3). These options travel with the map file, so a resumed map fuses exactly as the
/// run that created it.
struct MapOptions {
  double resolution_m = 0.10;  ///< voxel edge [m], in (0.005, 10]
  /// Free space is carved only up to this distance from the sensor [m]; points farther away
  /// are not inserted as hits, their rays clear space up to this range only.
  double max_range_m = 14.0;

  double occupancy_hit_prob = 0.7;         ///< P(occupied | endpoint in voxel), in (0.5, 1)
  double occupancy_miss_prob = 0.45;       ///< P(occupied | ray passes through), in (0, 0.5)
  double occupancy_clamp_min_prob = 0.1192;  ///< occupancy clamped below here, in (0, 0.5)
  double occupancy_clamp_max_prob = 0.971;   ///< occupancy clamped above here, in (0.5, 1)
  /// A voxel is occupied when P(occupied) >= this; strictly between the two clamps.
  double occupied_threshold_prob = 0.8;

  /// Added to the log-odds of the observed class when a frame's verdict for a voxel is that
  /// class; > 0.
  double class_hit_log_odds = 0.85;
  /// Added to the log-odds of each of the two other classes in that update; <= 0.
  double class_miss_log_odds = -0.4;
  /// When a ray passes through a voxel, each class log-odds moves this much towards 0 (no
  /// evidence), never past it; >= 0. Free space so forgets what moved away.
  double class_free_decay_log_odds = 0.1;
  /// A frame's non-traversable verdict for a voxel adds this many times class_hit_log_odds (and
  /// its misses this many times class_miss_log_odds to the other two): missing an obstacle costs
  /// a planner more than a false alarm, so one clear view of a lip or a rock's ring is not
  /// outvoted by a few views that did not resolve it; >= 1.
  double class_obstacle_gain = 2.0;
  /// A frame's verdict for a voxel is the worst class that this share of the voxel's class
  /// votes reach, counting each class with the worse ones: non-traversable when that many of
  /// its points are, else semi-traversable when that many are semi or worse, else traversable.
  /// A cell's class is the worst class of the ground in it (interfaces.md, section 3), so a
  /// voxel that straddles the edge of a lip band or a rock's ring is the band's, not the open
  /// ground's beside it; the share keeps a lone mislabelled point from deciding. 0: the
  /// plurality of the points, ties to the worse class; in [0, 1].
  double class_worst_share = 0.25;
  /// A frame's class vote for a voxel counts w = 1 / (1 + (sigma / (k max_step))^2), with sigma
  /// the stereo height noise of its points there and k this value (vehicle.max_step_m from the
  /// map's vehicle): a view that resolves a jump of max_step at k sigma counts fully, a far view
  /// whose noise is as large as the jump it should judge counts little. 0: every vote counts 1.
  double class_vote_noise_steps = 0.5;
  /// A frame's class vote for a voxel also counts 1 / (1 + (sigma_xy / (k step_radius))^2), with
  /// sigma_xy the stereo noise of its points' horizontal position there and k this value
  /// (vehicle.step_radius_m from the map's vehicle). Depth noise moves a far point along its
  /// ray, mostly sideways over the ground: an obstacle's far views land their votes in the
  /// columns behind and before it, and those would otherwise count as much as a near view's.
  /// 0: no such weighting; >= 0.
  double class_vote_smear_radii = 3.0;
  /// Added to the traversable class's log-odds when a column is judged: open ground is most of
  /// any terrain, so frames' evidence must beat this before a column is an obstacle. Weak,
  /// noisy evidence leaves the column traversable with a lower confidence (and a higher cost)
  /// instead of blocking it; >= 0.
  double class_prior_traversable_log_odds = 0.5;
  /// A voxel's votes are a verdict only when some class's log-odds has moved at least this
  /// many clear views from 0 (|L_k| >= this * class_hit_log_odds, times class_obstacle_gain
  /// for the non-traversable class). Each vote already counts by how well its view resolves
  /// the step radius (class_vote_noise_steps, class_vote_smear_radii): 0.25 is one view whose
  /// height noise is half max_step and whose sideways smear is three step radii, both at the
  /// edge of resolving the step. Weaker evidence is ground no view resolved: the voxel is then
  /// undecided (class 4) instead of traversable by the open-ground prior alone; the fused
  /// surface may still judge it. Off by default: on the tuning scenes 0.25 turns 2.5 % of the
  /// truly blocked footprints from unsafe to undecided (far slopes just over the limit), but a
  /// short drive on a low-resolution rig (320x240) answers 13 % fewer of its cells
  /// (docs/accuracy.md). 0: any nonzero vote is a verdict; >= 0.
  double class_min_evidence_views = 0.0;
  /// The open-ground prior may turn a voxel whose votes lean to an obstacle (class 3 the most
  /// probable without it) traversable only when those votes hold at least this many clear
  /// views (counted as for class_min_evidence_views); weaker, the voxel is undecided (class 4).
  /// Votes that weak come from views that do not resolve the step radius: they say little, and
  /// where the little they say is "obstacle", calling the ground open on the prior's word is
  /// the unsafe guess. 0.25 is one view at the edge of resolving the step (height noise half
  /// max_step, sideways smear three step radii). Votes that lean to open or semi-traversable
  /// ground are never withheld. On the tuning scenes it turns 1 % of the truly blocked
  /// footprints from unsafe to undecided, and with true disparity and true labels 3 %
  /// (docs/accuracy.md). 0: the prior always answers; >= 0.
  double class_prior_min_evidence_views = 0.25;
  /// The frames alone call a voxel non-traversable only when its obstacle log-odds L3 hold at
  /// least this many clear views (L3 >= this * class_hit_log_odds * class_obstacle_gain);
  /// weaker, the voxel is undecided (class 4), not an obstacle. Each vote counts by how well its
  /// view resolves the step radius (class_vote_noise_steps, class_vote_smear_radii), so 0.5 is
  /// two views at the edge of resolving it (0.25 each) or one view that resolves it: a single
  /// view that cannot, a far frame's smeared step say, does not block a voxel on its own word.
  /// A planner told "blocked" there would route around free ground; told "undecided" it knows
  /// the map has not seen the voxel well enough. Where the fused surface finds a hazard or
  /// vouches for open ground it judges with the frames whatever this value. On the tuning
  /// scenes 0.5 takes 269 free and 10 truly blocked footprints off non-traversable, and turns no
  /// blocked one drivable (docs/accuracy.md); 1 would also blank a rock ring one near view saw
  /// under eight noisy far views (0.7 clear views left). 0: any obstacle lead is a verdict;
  /// >= 0.
  double class_obstacle_min_evidence_views = 0.5;
  /// The chance that a fused surface which finds open ground misses a hazard the frames saw: a
  /// lip whose floor is hidden (the surface ends at the edge, where stereo smears the upper
  /// level a cell or two beyond it) or an obstacle thinner than a cell. Where the surface
  /// vouches for open ground, its class probabilities are mixed with this much of a uniform
  /// one before they multiply the frames'. Its word on open ground is then worth at most
  /// (1 - 2e/3) / (e/3) to one, so frames that saw an obstacle in nearly every view keep it,
  /// while a few noisy votes are still outweighed. 0: the surface's word is final; in [0, 1).
  double class_surface_miss_prob = 0.1;
  /// Where the fused heights are smeared sideways by more than half the step radius (far
  /// ground, SurfaceVerdict::smeared), judge the surface again over the disc widened along the
  /// ray from the nearest point of the sensor's path by their horizontal sigma
  /// (JudgeSmearedSurface). A jump or slope above max found there at 2 sigmas may lie within the
  /// step radius of the column or beyond it, which stereo at that range cannot tell: a column
  /// not otherwise non-traversable is undecided (JudgeRule::kSmearedHazard). On the tuning
  /// scenes this halves the unsafe footprints (22 % to 11 %) and blocks nothing more, for 6 %
  /// of the free footprints answered undecided instead of open, mostly beyond 10 m from the
  /// path (docs/accuracy.md). false: the frames' votes decide such columns.
  bool class_smeared_surface_hazards = true;
  double class_clamp_min = -2.0;  ///< class log-odds lower clamp; < 0
  double class_clamp_max = 3.5;   ///< class log-odds upper clamp; > 0
  /// A ray stops clearing free space where it comes within this height [m] of its endpoint,
  /// i.e. clearance / sin(elevation) before the end (at most 2 m). Why: a ray to far ground
  /// runs within one voxel of nearer ground for its last resolution/sin(elevation) metres and
  /// would clear the ground seen before. 0 disables it (OctoMap's usual carving); >= 0.
  double free_space_clearance_m = 0.1;
  /// Rays to an obstacle stop k r^2 short of their end instead (r: the ray's length, k this
  /// value in 1/m), when that is less than the clearance's shortening: rays to voxels whose
  /// points are mostly non-traversable and not below the frame's ground plane
  /// (ClassifiedPoint::height_m > -resolution/2, or unknown). They pass above the ground in front
  /// of the obstacle, where stereo's depth noise smears it towards the camera; cleared, those
  /// voxels take the smear away. The band k r^2 follows stereo's range error, r^2 dd / (f b):
  /// it keeps the obstacle's own voxels from the rays of its points smeared behind it. 0.008 is
  /// 0.4 px of disparity at f b = 50 px m (0.8 m at 10 m). Negative: off (the clearance applies).
  double free_space_obstacle_shortening_per_m2 = 0.008;
  /// Free-space rays whose ends fall in the same cell of this many voxels per edge (aligned to
  /// the voxel grid) are cast once, to the mean of their ends: an approximation that walks
  /// fewer rays. 1: one ray per hit voxel and per far voxel (exact, OctoMap's carving); 2, 4
  /// or 8. Each voxel a cell's ray frees lies within `free_space_ray_cell` voxels of a voxel
  /// one of the exact rays frees or hits.
  int free_space_ray_cell = 1;
  /// A ray's pass leaves a voxel the map holds as traversable ground (its traversable class
  /// log-odds positive and above the other two) as it is: no occupancy miss, no class decay.
  /// Why: rays to ground seen at a grazing angle (beyond a crest, with stereo's depth noise at
  /// range) run through the voxels of nearer ground and erode it frame by frame; on the hills
  /// scene that left a fifth of the seen ground without a class. Obstacles, undecided voxels
  /// and free space are still cleared; a traversable surface that goes away (a flat top moved)
  /// stays until frames vote it otherwise. false: every voxel a ray passes takes the miss.
  bool free_space_keeps_traversable = true;
  /// Rays that ranged nothing (ClassifiedPoint::no_return: blank sky) stop clearing at the first
  /// voxel whose P(occupied) is at least this, a surface the map is sure of; that voxel and what
  /// lies behind it keep their evidence. Such a pixel may be a blank wall as well as the sky:
  /// the stop keeps the wall, once other views have mapped it, and what they saw behind it.
  /// Matching noise that SGBM carried into the sky from a nearer edge lands at a different place
  /// in every frame, so it holds fewer hits and is cleared. 0.95 is four hits more than misses
  /// at the default occupancy_hit_prob (three are 0.93); on the tuning scenes, with
  /// class_obstacle_min_evidence_views at 0, it falsely blocks 8.9 % of the free footprints,
  /// 0.9 9.2 % and 0.8 9.5 %, for 8.0, 8.0 and 7.5 % unsafe (docs/accuracy.md). Strictly
  /// between occupancy_clamp_min_prob and occupancy_clamp_max_prob.
  double free_space_no_return_stop_prob = 0.95;

  /// Every field: its key, unit, range and meaning (reading, writing and IsValid come from it).
  static const OptionFields<MapOptions>& Fields();
  /// The first field out of its range, as "key: requirement" in `*error`.
  bool IsValid(std::string* error) const;
};

/// YAML section `map`: how frames are fused into a TraversabilityMap.
struct MappingOptions {
  MapOptions fusion;  ///< voxel size, range and the log-odds sensor model
  int pixel_stride = 1;         ///< insert every n-th pixel in u and v (the map thins per voxel)
  /// Pixels whose left-image grey-level standard deviation over the stereo block is below this
  /// are not inserted (sky and blank areas: matching noise); 0: off. Unlike stereo.min_texture
  /// it leaves the per-frame classification as it is. In [0, 128).
  double min_texture = 2.0;
  /// [px, odd] the map's points sit at the matcher's disparity refined to sub-pixel precision
  /// over this window (RefineDisparitySubpixel; 0: off). SGBM's disparities lean ~0.12 px short
  /// and lock to whole pixels: at 12 m that is ~0.35 m of range bias. The per-frame classes keep
  /// the matcher's disparity, on which they were measured; without effect when
  /// stereo.subpixel_window_px already refines it, or with a given (oracle) disparity.
  int subpixel_window_px = 7;
  /// The lips of drop-offs whose foot a frame cannot see are non-traversable in the map: up
  /// each image column, a view that passes over an edge and lands lower by more than
  /// vehicle.max_step_m beyond the noise of both heights marks the ground within
  /// vehicle.step_radius_m of the edge (src/analysis/hidden_drops.h).
  bool hidden_drops = true;
  /// [px] every n-th pixel (in u and v) above the horizon that the texture test left without a
  /// point (LabelRule::kTexture: blank sky, or a blank wall) casts a ray that ranged nothing
  /// (ClassifiedPoint::no_return), on a lattice whose phase changes from frame to frame. It
  /// clears the noise matches SGBM carries from a trunk or a skyline into the sky around it,
  /// which other frames inserted where the map's texture test kept them as a wall. Only voxels
  /// the map holds take the pass: the open sky is not filled with free voxels. 0: off.
  int no_return_stride_px = 4;
  int checkpoint_every_frames = 200;  ///< save the map every n frames while building (0: never)
  /// The map's range follows the rig: fusion.max_range_m becomes the depth at which the stereo
  /// depth noise reaches range_depth_sigma_m (FusionFor). false: fusion.max_range_m as given.
  bool auto_range = true;
  double range_depth_sigma_m = 2.0;  ///< [m] the depth noise (1-sigma) at the auto range

  /// The fusion options for a rig of `focal_times_baseline` [px m] whose matcher's disparity
  /// noise is `disparity_sigma_px`: with auto_range, max_range_m = sqrt(range_depth_sigma_m *
  /// f b / sigma_d), the depth where Z^2 sigma_d / (f b) reaches range_depth_sigma_m (20 m for
  /// f b = 50 px m and 0.25 px), at most 1000 m.
  MapOptions FusionFor(double focal_times_baseline, double disparity_sigma_px) const;
  /// Every field: its key, unit, range and meaning (reading, writing and IsValid come from it).
  static const OptionFields<MappingOptions>& Fields();
  /// The first field out of its range, as "key: requirement" in `*error`.
  bool IsValid(std::string* error) const;
};

/// What a map remembers about how it was made. It is written into the map file with the voxels.
/// cam0's mount as an online refinement (`ssta build-map --refine`) left it, with the mount from
/// sensor.yaml it corrects: a resumed build with the same sensor.yaml starts from `refined`.
struct RefinedMount {
  Eigen::Isometry3d configured = Eigen::Isometry3d::Identity();  ///< body_T_cam0 of sensor.yaml
  Eigen::Isometry3d refined = Eigen::Isometry3d::Identity();     ///< body_T_cam0 in use at the end
};

/// One map file that went into a merge (MergeMaps): where its evidence came from.
struct MapSource {
  std::string file;      ///< the file as the merge was given it
  std::string checksum;  ///< "fnv1a64:<16 hex digits>", the hash in the file's end marker
  std::vector<std::string> sequences;  ///< the sequences fused into it, in order
  std::uint64_t frames_inserted = 0;   ///< frames fused into it
  std::string software_version;        ///< the ssta version that wrote it
};

struct MapMetadata {
  VehicleOptions vehicle;           ///< the vehicle whose limits gave the classes (and costs)
  std::string calibration_summary;  ///< free text or YAML describing the stereo calibration
  std::vector<std::string> sequences;  ///< names of the sequences fused, in fusion order
  /// Set by a build with online mount refinement once a solve was applied; nullopt otherwise.
  std::optional<RefinedMount> refined_mount;
  /// Name of the world frame W the poses were given in (`build-map --world-frame`); empty:
  /// unnamed. Maps merge only when they name the same frame: their voxels must share W.
  std::string world_frame;
  /// What a reader of the map must know about its evidence, "SEQUENCE: sentence" each (a
  /// sequence read from a truncated bag with --allow-truncated), in the order they arose.
  std::vector<std::string> notes;
  /// A merged map: the built (not merged) maps whose evidence it holds, in merge order (a
  /// merge of merged maps lists their sources). Empty for a map that was not merged.
  std::vector<MapSource> merged_from;
  /// The fingerprints of the recordings whose frames the map holds (build-map records each
  /// fused frame; a merge lists its inputs'), in fusion order. A sequence without one (a map
  /// written before fingerprints) is unknown: no overlap can be found with it.
  std::vector<RecordingFingerprint> recordings;
};

}  // namespace ssta
