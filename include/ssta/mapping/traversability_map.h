#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "ssta/mapping/map_options.h"
#include "ssta/mapping/map_types.h"

namespace ssta {

namespace internal {
struct TraversabilityMapAccess;  // private door for the exporters and tests (src/mapping)
}  // namespace internal

struct ColumnExplanation;  // include/ssta/mapping/column_explanation.h

/// Version of the map file layout this build writes; it reads this version and older ones.
inline constexpr int kMapFormatVersion = 2;

/// A persistent 3D traversability map: an octree of voxels in the world frame W (z up, metres)
/// holding occupancy, per-class evidence, mean slope and step, an observation count and the
/// last time each voxel was seen. Frames are fused with InsertFrame; planners ask CellAt,
/// TopSurfaceAt, QueryFootprint, QueryPath and Project. Backed by OctoMap (kept out of this
/// header); the file format is described in maps/README.md.
///
/// Semantics (the exact formulas; L1..L3 are the class log-odds of a voxel):
///  - class: for an occupied voxel with evidence, argmax_k (Lk + P [k = 1]) (ties go to the
///    worse class; P = options().class_prior_traversable_log_odds); kUndecided without;
///    kUnknown for free or unobserved voxels. Evidence: some Lk != 0 and at least options().
///    class_min_evidence_views clear views (|Lk| over class_hit_log_odds, times
///    class_obstacle_gain for k = 3): weaker votes are ground no view resolved, which the prior
///    alone would call open. Also kUndecided where L3 is the largest Lk, the prior makes class 1
///    the argmax, and the votes hold fewer than options().class_prior_min_evidence_views clear
///    views: the prior does not overrule weak votes for an obstacle. And kUndecided where
///    class 3 is the argmax but L3 holds fewer than options().class_obstacle_min_evidence_views
///    clear views: evidence stereo noise at the views' range can make blocks nothing.
///  - probability of class c: exp(Lc + P [c = 1]) / sum_k exp(Lk + P [k = 1]).
///  - cost: traversable 0.25 min(1, 1.5 (1 - confidence)), so 0 when certain and up to 0.25
///    when barely more probable than the others; non-traversable 1; semi-traversable
///    0.25 + 0.5 f with f = max(clamp01((slope - semi_slope) / (max_slope - semi_slope)),
///    clamp01((|step| - semi_step) / (max_step - semi_step))) from the slope and step and the
///    metadata's vehicle, so in [0.25, 0.75]; NaN for every other class.
///
/// Thread safety: const methods only read (OctoMap's search and traversal do not mutate the
/// tree), so any number of threads may query concurrently while no thread calls a non-const
/// method. InsertFrame, set_metadata and assignment need exclusive access: a planner that reads
/// while a map is being built guards it with a reader-writer lock (std::shared_mutex), or reads
/// a copy saved and loaded (Save / Load). A moved-from map may only be destroyed or assigned to.
///
/// A voxel's class is its fused per-class evidence (votes of the frames that saw it), not a
/// function of its stored mean slope and step: those are averages over the same frames, so a
/// voxel may hold class 3 with a mean slope under max_slope_deg (one frame's verdict against
/// another's, ties to the worse class). Planners take the class; slope and step explain it.
class TraversabilityMap {
 public:
  /// An empty map. Throws ssta::Error naming the key when `options` or `metadata.vehicle` is
  /// invalid.
  explicit TraversabilityMap(const MapOptions& options = MapOptions{}, MapMetadata metadata = {});
  ~TraversabilityMap();
  TraversabilityMap(TraversabilityMap&&) noexcept;
  TraversabilityMap& operator=(TraversabilityMap&&) noexcept;
  TraversabilityMap(const TraversabilityMap&) = delete;
  TraversabilityMap& operator=(const TraversabilityMap&) = delete;

  /// Fuses one frame of classified points (in W) seen from `sensor_origin_world` (in W).
  ///  1. Points are grouped by voxel; each voxel gets one update per frame. Its class is the
  ///     majority among the points' 1..3 verdicts (ties go to the worse class); its slope and
  ///     step the mean over those points (finite values only), its max step the largest |step|.
  ///     Points with class 0, 4 or any other id count for occupancy only.
  ///  2. One ray per hit voxel runs from the origin to the mean of its points; every voxel it
  ///     crosses (endpoint excluded) is free, once per frame, unless hit in this frame.
  ///     Voxels of points beyond max_range_m are not hit; their rays clear only up to the range.
  ///     A ray that ranged nothing (ClassifiedPoint::no_return) frees only the voxels the map
  ///     holds, up to the range or the first voxel at least free_space_no_return_stop_prob
  ///     occupied, whichever comes first.
  ///  3. Free voxels: occupancy miss, class log-odds decay towards 0. Hit voxels: occupancy hit;
  ///     with a verdict c: Lc += class_hit, the others += class_miss, all clamped; the means and
  ///     the observation count take the frame; last_seen_ns = timestamp_ns for every hit.
  /// A non-finite origin or one outside the map skips the frame (stats say why).
  InsertStats InsertFrame(const std::vector<ClassifiedPoint>& points,
                          const Eigen::Vector3d& sensor_origin_world, std::int64_t timestamp_ns);

  /// Writes the map (voxels, options, metadata) to `path` atomically: a temporary file beside
  /// it is written, flushed and renamed over `path`. Throws ssta::Error naming the file.
  void Save(const std::string& path) const;

  /// Reads a map written by Save. Throws ssta::Error naming the file when it is missing,
  /// truncated or corrupt, not an SSTA map (another OctoMap tree type), or of a newer format.
  static TraversabilityMap Load(const std::string& path);

  /// The voxel containing `p_world` [m]. Unobserved: observed false, class kUnknown, cost NaN,
  /// center still the voxel centre. Outside the addressable cube: also unobserved.
  CellInfo CellAt(const Eigen::Vector3d& p_world) const;

  /// The highest occupied voxel of the map column containing (x, y) [m] in W: the surface the
  /// robot drives on (an overhang above the ground counts as the top). When the column holds
  /// no occupied voxel: observed false, class kUnknown, cost NaN, center (column x, y, NaN).
  CellInfo TopSurfaceAt(double x, double y) const;
  /// The evidence behind TopSurfaceAt(x, y) and the rule that combined it
  /// (include/ssta/mapping/column_explanation.h); for `ssta explain` and people asking why.
  ColumnExplanation ExplainColumn(double x, double y) const;

  /// Where the footprint and path queries read each column's top surface: TopSurfaceAt by
  /// default, or another view of it such as ExportedSurface (ssta/mapping/map_export.h: the
  /// exported grid's classes and costs).
  using SurfaceSource = std::function<CellInfo(double x, double y)>;

  /// The top surfaces under a vehicle footprint (see FootprintResult), read from `surface`
  /// (empty: TopSurfaceAt). Every column the rectangle touches counts (its square overlaps the
  /// rectangle by more than 1e-9 m): an obstacle under any part of the footprint is under the
  /// robot. Throws ssta::Error for a
  /// non-finite x, y or yaw, a negative or non-finite size, a rectangle beyond the map's
  /// addressable area (+-32768 resolutions) or over more than 10^7 columns.
  FootprintResult QueryFootprint(const FootprintQuery& query, const SurfaceSource& surface = {}) const;

  /// Checks a path: samples every resolution/2 along `polyline_world` (x, y in W [m]); at each
  /// sample the top surfaces across `width_m` (perpendicular to the segment, one every
  /// resolution, at least the centre), read from `surface` (empty: TopSurfaceAt), give the
  /// sample's worst class and max cost. Where the path turns, extra samples at the vertex (same
  /// distance_m) turn the lateral line from one segment's direction to the next, so the outside
  /// of the turn is checked; a path of one point (or only repeated ones) checks the disc of
  /// radius width_m / 2 around it.
  /// Throws ssta::Error without a vertex, for a non-finite vertex, width_m < 0 or not finite,
  /// for more than 10^7 cells to read (samples x lateral cells) or 10^6 samples to return.
  PathResult QueryPath(const std::vector<Eigen::Vector2d>& polyline_world, double width_m,
                       const SurfaceSource& surface = {}) const;

  /// The top surface over `region` (x, y in W [m]) on a grid of `resolution_m` pixels: at the
  /// map's resolution or finer, TopSurfaceAt of each pixel centre; coarser, the worst class
  /// among the map columns whose centres the pixel holds (its cost, height, slope, step). The
  /// grid starts at region.min() and covers the region (ceil). Throws ssta::Error for an
  /// empty region, resolution <= 0, or more than 2^26 pixels (~1.4 GB).
  GridProjection Project(const Eigen::AlignedBox2d& region, double resolution_m) const;

  /// Every occupied voxel at map resolution (pruned blocks expanded), in OctoMap key order.
  std::vector<CellInfo> SurfaceCells() const;

  /// Bounding box of the occupied voxels' extents in W [m]; empty when there are none.
  Eigen::AlignedBox3d SurfaceBounds() const;

  /// Cost of a class with the given slope [deg], step [m] and confidence in [0, 1] (formula
  /// above).
  double Cost(TravClass cls, double slope_deg, double step_m, double confidence = 1.0) const;

  const MapOptions& options() const;
  const MapMetadata& metadata() const;
  /// Replaces the metadata (e.g. appends a sequence name). Throws ssta::Error on an invalid
  /// vehicle.
  void set_metadata(MapMetadata metadata);
  /// Where the sensor was: the origins of the inserted frames in W [m], in insertion order,
  /// one wherever the sensor moved at least one resolution from the last one kept. For
  /// pictures and reports (the picture export draws it); it survives Save/Load, and a file
  /// without it reads as an empty path.
  const std::vector<Eigen::Vector3d>& sensor_path() const;
  /// InsertFrame calls that inserted a frame, over the map's life (survives Save/Load).
  std::uint64_t frames_inserted() const;
  /// Timestamp of the last inserted frame [ns]; 0 before the first.
  std::int64_t last_timestamp_ns() const;
  /// For a loaded map, the ssta version that saved the file; for a new map, this build's.
  /// (Save always records this build's version.)
  const std::string& software_version() const;
  /// Number of octree nodes (inner and leaves); a size indicator.
  std::size_t NumNodes() const;

 private:
  struct Impl;
  explicit TraversabilityMap(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
  friend struct internal::TraversabilityMapAccess;
};

}  // namespace ssta
