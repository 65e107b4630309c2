#pragma once

// Value types that go in and out of a TraversabilityMap. World frame W throughout: right-handed,
// z up, metres (docs/interfaces.md, section 1). Angles in these structs are degrees only where the name
// says so (`slope_deg`); `yaw` is radians.

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ssta/core/classes.h"
#include "ssta/core/image.h"

namespace ssta {

/// One classified 3D point of a frame, as the per-frame classifier produces it.
struct ClassifiedPoint {
  Eigen::Vector3f world_p = Eigen::Vector3f::Zero();  ///< position in W [m]
  TravClass cls = TravClass::kUnknown;  ///< verdict; only 1..3 add class evidence
  /// A ray that ranged nothing (a pixel that saw blank sky): `world_p` is any point on it beyond
  /// the sensor. The voxels the map holds along it, up to max_range_m, take a pass as free
  /// space, up to the first one that is a surface the map is sure of
  /// (MapOptions::free_space_no_return_stop_prob); space the map has not observed stays
  /// unobserved, and the ray hits nothing. The other fields are not read.
  bool no_return = false;
  float slope_deg = 0.0f;  ///< surface slope at the point [deg]; non-finite: not averaged
  float step_m = 0.0f;     ///< step to the dominant ground plane [m]; non-finite: not averaged
  /// Signed height above the frame's dominant ground plane [m] (negative below); NaN when the
  /// frame has no ground plane that passed the quality check.
  float height_m = std::numeric_limits<float>::quiet_NaN();
  /// 1-sigma of the point's height [m] from the stereo depth noise (its depth error along its
  /// ray, seen vertically and through the surface's slope across the error's horizontal part);
  /// NaN: the point carries no height to fuse.
  float height_sigma_m = std::numeric_limits<float>::quiet_NaN();
  /// Horizontal 1-sigma of the point's position from the same depth error [m]; NaN with
  /// height_sigma_m.
  float horizontal_sigma_m = std::numeric_limits<float>::quiet_NaN();
  /// How much the point's class counts in its voxel's vote, in (0, 1]: 1 for a classified
  /// pixel; less for a lip that one view can only suspect (MapPointsOfFrame).
  float vote_weight = 1.0f;
};

/// What one InsertFrame call did.
struct InsertStats {
  std::size_t points_in = 0;           ///< points given
  std::size_t points_hit = 0;          ///< points within range that marked their voxel occupied
  std::size_t points_beyond_range = 0; ///< points beyond max_range_m (free space only)
  std::size_t rays_without_return = 0; ///< no_return points (free space up to a sure surface)
  std::size_t points_rejected = 0;     ///< non-finite or outside the map's addressable cube
  std::size_t voxels_hit = 0;          ///< distinct voxels updated as occupied
  std::size_t voxels_with_class = 0;   ///< of those, voxels that got a class verdict
  std::size_t voxels_freed = 0;        ///< distinct voxels updated as free
  bool inserted = true;                ///< false when the frame was skipped (see `reason`)
  std::string reason;                  ///< why the frame was skipped; empty otherwise
};

/// Which evidence decided a cell's class (CellInfo::decided_by).
enum class ClassJudge : std::uint8_t {
  kNone = 0,     ///< no class 1..3: unobserved, free space or undecided
  kFrames = 1,   ///< the frames' class votes in the voxel
  kSurface = 2,  ///< the fused surface around the column (its slope and step)
  kBoth = 3,     ///< the two together, agreeing on the class, or combined into it
  kExport = 4,   ///< an export step (a step judged by the local ground, a filled hole)
};

/// Lower-case name as printed in query CSV rows and Python's `decided_by`: "" (kNone),
/// "frames", "surface", "both", "export".
const char* ClassJudgeName(ClassJudge judge);

/// What the map knows about one voxel (or, for column queries, the top surface voxel).
/// Unknown numeric values are NaN.
struct CellInfo {
  /// The voxel has been seen (hit or passed through by a ray). For TopSurfaceAt: a surface
  /// (occupied voxel) was found in the column.
  bool observed = false;
  bool occupied = false;  ///< P(occupied) >= MapOptions::occupied_threshold_prob
  /// Voxel centre in W [m]. For an unobserved column from TopSurfaceAt, z is NaN.
  Eigen::Vector3d center = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  /// kUnknown: not observed, or free space. kUndecided: occupied but without class evidence
  /// (only undecided/unknown points hit it). Otherwise the class with the largest evidence.
  TravClass cls = TravClass::kUnknown;
  /// Planning cost in [0, 1] (see TraversabilityMap); NaN unless cls is 1..3.
  double cost = std::numeric_limits<double>::quiet_NaN();
  /// Probability of `cls` (softmax of the class log-odds); NaN unless cls is 1..3, and NaN
  /// where an export step, not the map's evidence, gave the class (ExportedSurface).
  double probability = std::numeric_limits<double>::quiet_NaN();
  /// How sure the map is of `cls`, in [0, 1]: for a column's top surface (TopSurfaceAt and the
  /// queries and exports built on it), the posterior probability of `cls` from the frames'
  /// class evidence and the fused surface around the column (its slope and step against the
  /// vehicle's limits, with their stereo uncertainty); for a voxel (CellAt), the frames'
  /// evidence alone (= probability). NaN unless cls is 1..3.
  double confidence = std::numeric_limits<double>::quiet_NaN();
  /// The fused height of the surface in the voxel (world z) [m]; the voxel centre's z when no
  /// height was fused; NaN unobserved.
  double surface_z_m = std::numeric_limits<double>::quiet_NaN();
  /// 1-sigma of surface_z_m [m]; NaN unobserved.
  double height_sigma_m = std::numeric_limits<double>::quiet_NaN();
  double occupancy = std::numeric_limits<double>::quiet_NaN();  ///< P(occupied); NaN unobserved
  /// Which evidence decided `cls`: for a voxel (CellAt) the frames; for a column's top surface
  /// (TopSurfaceAt) the frames, the fused surface around it, or both (see slope_deg).
  ClassJudge decided_by = ClassJudge::kNone;
  /// The slope that decided `cls` [deg]: the fused surface's (the local plane's slope) where
  /// decided_by is kSurface or kBoth; NaN where the frames' votes decided alone (kFrames: a
  /// frame classes its pixels by its own rules, so the frames' mean slope mixes the votes of
  /// every class; it is frame_mean_slope_deg) and where no class 1..3 was decided. The cost
  /// uses it.
  double slope_deg = std::numeric_limits<double>::quiet_NaN();
  /// The step that decided `cls` [m], as slope_deg: the fused surface's largest height jump
  /// within the vehicle's step radius (>= 0); NaN where the frames decided alone.
  double step_m = std::numeric_limits<double>::quiet_NaN();
  /// Mean over the frames that gave the voxel a class of their points' slope [deg]; NaN when
  /// none did.
  double frame_mean_slope_deg = std::numeric_limits<double>::quiet_NaN();
  /// Mean over those frames of their points' signed step to the ground [m]; NaN when none did.
  double frame_mean_step_m = std::numeric_limits<double>::quiet_NaN();
  double max_step_m = std::numeric_limits<double>::quiet_NaN(); ///< largest |step| a frame saw [m]
  std::uint32_t observations = 0;  ///< frames that gave this voxel a class verdict
  std::int64_t last_seen_ns = 0;   ///< timestamp of the last frame that hit it; 0 if never
};

/// A rectangular vehicle footprint on the ground, centred at (x, y) in W, its length along the
/// heading `yaw` [rad, from +x towards +y].
struct FootprintQuery {
  double x = 0.0;
  double y = 0.0;
  double yaw = 0.0;
  double length_m = 0.0;
  double width_m = 0.0;
};

/// The ground under a footprint: one top-surface cell per map column the rectangle touches
/// (the column under (x, y) when none does). An undecided top surface (class 4) counts as
/// observed: the map saw a surface there but cannot tell what it is, so a footprint over one
/// is not answered traversable or semi-traversable. Worst to best: non-traversable (3), then
/// undecided (4), semi-traversable (2), traversable (1).
struct FootprintResult {
  /// The worst class of the observed cells in that order (3 > 4 > 2 > 1); kUnknown if none.
  TravClass worst = TravClass::kUnknown;
  /// Mean cost over the observed cells that have one (class 1..3); NaN when there are none.
  double mean_cost = std::numeric_limits<double>::quiet_NaN();
  double max_cost = std::numeric_limits<double>::quiet_NaN();  ///< NaN when no cell has a cost
  /// The lowest CellInfo::confidence among the observed traversable and semi-traversable cells:
  /// how sure the map is that a drivable answer holds under the whole footprint (a planner that
  /// needs more treats the footprint as undecided). NaN when no such cell has a confidence.
  double drivable_confidence = std::numeric_limits<double>::quiet_NaN();
  double fraction_observed = 0.0;  ///< observed columns / columns, in [0, 1]
  int cells = 0;                   ///< columns under the footprint
  /// Of those, columns with an observed surface (or, read from a surface source such as
  /// ExportedSurface, with a class: a filled hole counts).
  int observed_cells = 0;
  /// Centre (x, y) [m] of the observed column of the `worst` class nearest the footprint's
  /// centre (where to ask `ExplainColumn` why); NaN when no column was observed.
  double worst_x_m = std::numeric_limits<double>::quiet_NaN();
  double worst_y_m = std::numeric_limits<double>::quiet_NaN();
  /// The vehicle's attitude on the plane fitted (least squares) to the fused surface heights
  /// (CellInfo::surface_z_m) of those columns, heading `yaw` (AttitudeOnGround,
  /// ssta/mapping/vehicle_attitude.h): pitch [deg], positive nose up; NaN when fewer than 3
  /// columns (not in a line) have a height.
  double pitch_deg = std::numeric_limits<double>::quiet_NaN();
  /// Roll [deg] on that plane, positive when the left side is higher; NaN likewise.
  double roll_deg = std::numeric_limits<double>::quiet_NaN();
  /// The attitude against the vehicle's max_pitch_deg, max_descent_deg and max_roll_deg:
  /// traversable below 0.8 of every limit, semi-traversable up to the limits, non-traversable
  /// beyond one; kUnknown without a plane. It comes on top of `worst` and does not change it.
  TravClass attitude = TravClass::kUnknown;
  int attitude_heights = 0;  ///< columns whose heights the plane was fitted to
};

/// One sample along a path: the worst top-surface cell across the path's width there.
struct PathSample {
  Eigen::Vector2d point = Eigen::Vector2d::Zero();  ///< on the polyline, in W [m]
  double distance_m = 0.0;                          ///< arc length from the first vertex [m]
  /// The worst class across the width, as FootprintResult::worst orders them (an undecided cell
  /// outranks semi-traversable and traversable ones); kUnknown if no cell was observed.
  TravClass cls = TravClass::kUnknown;
  double cost = std::numeric_limits<double>::quiet_NaN();  ///< max cost across the width
  double fraction_observed = 0.0;  ///< observed lateral cells (as FootprintResult) / lateral cells
  CellInfo cell;                   ///< the cell that set `cls` (the centre cell if none did)
  /// The lowest CellInfo::confidence among the traversable and semi-traversable cells across
  /// the width, as FootprintResult::drivable_confidence; NaN when no such cell has one.
  double drivable_confidence = std::numeric_limits<double>::quiet_NaN();
};

/// A polyline checked against the map.
struct PathResult {
  std::vector<PathSample> samples;  ///< every resolution/2 along the polyline, ends included
  TravClass worst = TravClass::kUnknown;  ///< worst sample class (as PathSample::cls); kUnknown if none
  /// Mean of the sample costs that are finite; NaN when none is.
  double mean_cost = std::numeric_limits<double>::quiet_NaN();
  double fraction_observed = 0.0;  ///< mean of the samples' fraction_observed
  double length_m = 0.0;           ///< polyline length [m]
  bool blocked = false;            ///< some sample is non-traversable
  /// The first non-traversable sample point (NaN when not blocked) and its arc length.
  Eigen::Vector2d first_non_traversable =
      Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
  double first_non_traversable_distance_m = std::numeric_limits<double>::quiet_NaN();
};

/// The top surface projected onto a 2D grid. Image convention: row 0 is the largest y, column
/// 0 the smallest x; pixel (v, u) covers x in [origin.x + u r, origin.x + (u + 1) r) and
/// y in [origin.y + (H - 1 - v) r, origin.y + (H - v) r), r = resolution_m.
struct GridProjection {
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();  ///< lower-left corner of pixel (H-1, 0) [m]
  double resolution_m = 0.0;                         ///< pixel edge [m]
  ImageU8 classes;    ///< class ids (0 where no surface was observed)
  ImageF cost;        ///< cost in [0, 1]; NaN where unknown
  ImageF height_m;    ///< z of the top surface voxel centre [m]; NaN where unobserved
  /// The slope that decided the pixel's class [deg] (CellInfo::slope_deg of its column); NaN
  /// where unobserved or no class 1..3 was decided.
  ImageF slope_deg;
  ImageF step_m;      ///< the step that decided the class [m] (CellInfo::step_m), NaN likewise
  /// The pixel's CellInfo::confidence in [0, 1]; NaN where there is no class 1..3 (and where an
  /// export step, not the map's evidence, set the class).
  ImageF confidence;
  /// The fused surface height of the pixel's column (CellInfo::surface_z_m, world z) [m]; NaN
  /// where unobserved. The heading costs fit their planes to it.
  ImageF surface_z_m;

  int width() const { return classes.width(); }
  int height() const { return classes.height(); }
  /// Centre of pixel (v, u) in W [m].
  Eigen::Vector2d PixelCenter(int v, int u) const {
    return {origin.x() + (u + 0.5) * resolution_m,
            origin.y() + (height() - 1 - v + 0.5) * resolution_m};
  }
};

}  // namespace ssta
