#pragma once

// Exports of a TraversabilityMap for other tools. Every file is written atomically (temporary
// file + rename); failures throw ssta::Error naming the file.

#include <cstdint>
#include <string>

#include <Eigen/Geometry>

#include "ssta/mapping/traversability_map.h"
#include "ssta/mapping/vehicle_attitude.h"

namespace ssta {

/// Header of the query CSV (docs/interfaces.md, section 5, with the confidence, the judge that
/// decided the class and the frames' means appended) and of the `csv` export.
inline constexpr char kQueryCsvHeader[] =
    "x,y,z,class,cost,probability,slope_deg,step_m,observations,confidence,decided_by,frame_mean_slope_deg,"
    "frame_mean_step_m";

/// One CSV row (no newline) for `cell` under kQueryCsvHeader: centre x, y, z [m] with 4
/// decimals (in exponent form from 1e9 m on), class id, cost and probability with 4 decimals,
/// slope [deg] with 2, step [m] with 3 (those that decided the class), observations, confidence
/// with 4 decimals, decided_by (ClassJudgeName: empty where no class was decided), the frames'
/// mean slope [deg] with 2 and mean step [m] with 3. Unknown values print as "nan".
std::string QueryCsvRow(const CellInfo& cell);

struct GridExportOptions {
  /// Pixel edge [m]; <= 0 takes the map's resolution.
  double resolution_m = 0.0;
  /// Region to export (x, y in W). Empty (the default): the occupied voxels' bounding box.
  /// The region is widened outwards to multiples of the resolution, so with the map's
  /// resolution every pixel is exactly one map column.
  Eigen::AlignedBox2d region;
  /// Holes: an unknown pixel with at least this many of its 8 neighbours classified takes their
  /// class (FillHoles). 5 (the default) fills the pixels that the rows of far pixels skip (at
  /// 10 m a pixel row spans ~0.3 m of ground), never the straight edge of the observed area
  /// (3 neighbours). 0: off; at most 8.
  int fill_min_neighbours = 5;
  /// Steps against the local ground: a level non-traversable pixel at the height of the
  /// traversable ground within this radius [m] is traversable (JudgeStepsByLocalGround; the
  /// level limit is the map's vehicle semi_slope_deg, the height tolerance one pixel edge).
  /// For maps of frames classed with steps against their dominant plane (eq. 5); the shipped
  /// frames measure local steps and the map judges each column from the surface around it,
  /// so it is off by default. 0: off.
  double local_ground_radius_m = 0.0;
  /// Cost layers per heading (HeadingCosts of the exported grid, judged against the map's
  /// vehicle): written by ExportGrid and ExportMcap when headings > 0; the other exports and
  /// the queries ignore it.
  HeadingCostOptions headings;
  /// A planner's confidence bar, applied last (ApplyConfidenceBar, ssta/mapping/confidence_bar.h):
  /// a traversable or semi-traversable pixel whose confidence is below it is undecided, so the
  /// navigation PGM shows it unknown. A pixel whose class an export step gave has no confidence
  /// and keeps it. 0 (the default): off; in [0, 1].
  double min_confidence = 0.0;
};

/// One pass over a projection: each non-traversable pixel (3) whose slope (the one that decided
/// its class) is below `level_slope_deg`, or NaN (the frames' votes decided), and whose height lies within `tolerance_m` of the median height of the
/// traversable pixels (1) within `radius_m` of it (at least 5 of them, read from the input, so a
/// changed pixel never counts for another) becomes traversable, with cost 0; its height, slope
/// and step stay as observed (ExportedSurface answers such a column with slope and step NaN). Why: a frame calls a surface a step by its height over that
/// frame's dominant ground plane (the paper's eq. 5), which does not pass through ground beyond
/// a rise, a hollow or a ditch; the map knows the ground around each cell. Obstacles and
/// steep cells are kept: an obstacle's top stands above the ground around it. Returns the
/// number of pixels changed. Throws ssta::Error unless radius_m > 0 and tolerance_m >= 0.
int JudgeStepsByLocalGround(GridProjection* grid, double radius_m, double tolerance_m, double level_slope_deg);

/// One pass over `classes` (ids of docs/interfaces.md, section 3): each unknown pixel (0) of which at
/// least `min_neighbours` (1..8) of the 8 neighbours hold a class 1..3 in the input takes the
/// most frequent of those classes, a tie going to the worse. Filled pixels do not count for
/// their neighbours, so a fill never grows from another; undecided pixels (4) stay and do not
/// count. Returns the number of pixels filled. Throws ssta::Error unless 1 <= min_neighbours <= 8.
int FillHoles(ImageU8* classes, int min_neighbours);

/// What the grid export changed in the projection (ExportGrid's `changes`).
struct GridExportChanges {
  int judged_by_local_ground = 0;  ///< non-traversable pixels made traversable (JudgeStepsByLocalGround)
  int holes_filled = 0;            ///< unknown pixels filled (FillHoles)
  int below_confidence_bar = 0;    ///< drivable pixels made undecided (GridExportOptions::min_confidence)
};

/// The grid that ExportGrid writes, without writing it: the map's projection of
/// options.region (the occupied voxels' bounding box when empty), widened outwards to multiples
/// of the resolution, with steps judged by the local ground and then holes filled as the options
/// say. Pixels lie on one lattice (multiples of the resolution) for any region, so a pixel
/// holds the same class and cost in the projection of any region that contains it with
/// local_ground_radius_m + 2 pixels around it. `changes`, when not null, gets how many pixels
/// each step changed. Throws ssta::Error as ExportGrid.
GridProjection ProjectAsExported(const TraversabilityMap& map, const GridExportOptions& options = GridExportOptions{},
                                 GridExportChanges* changes = nullptr);

/// Top surfaces as the exported grid shows them: TopSurfaceAt, with the class and cost of the
/// column's pixel in ProjectAsExported. A step judged by the local ground is traversable with
/// cost 0; a filled hole has its filled class, observed false, no height and cost NaN (the
/// export fills classes, not measurements). For planners that must agree with the exported
/// grid; TopSurfaceAt answers as observed. `region` (x, y in W [m]) is projected once, widened
/// by local_ground_radius_m + 2 pixels, which makes each of its pixels the whole export's
/// (pixels lie on one lattice of the resolution); a column outside it is projected on its own
/// when asked. options.region is ignored. Pass it as the surface of QueryFootprint and
/// QueryPath over the footprint's or path's bounding box. The map must outlive it.
class ExportedSurface {
 public:
  ExportedSurface(const TraversabilityMap& map, const Eigen::AlignedBox2d& region,
                  const GridExportOptions& options = GridExportOptions{});
  /// Throws ssta::Error unless x and y are finite.
  CellInfo operator()(double x, double y) const;

 private:
  CellInfo Answer(double x, double y, bool reproject_outside) const;

  const TraversabilityMap* map_;
  GridExportOptions options_;
  double resolution_m_ = 0.0;
  int border_px_ = 0;  // pixels at the grid's edges whose neighbourhood was cut
  GridProjection grid_;
};

/// One column as exported: ExportedSurface over the point (x, y) alone.
CellInfo TopSurfaceAsExported(const TraversabilityMap& map, double x, double y,
                              const GridExportOptions& options = GridExportOptions{});

/// The `grid` export (docs/interfaces.md, section 5): PREFIX.png (class colours, undecided grey),
/// PREFIX_classes.png (8-bit class ids), PREFIX.pgm (non-traversable 0, traversable and semi
/// 254, unknown and undecided 205) and PREFIX.yaml (map_server: image, resolution, origin
/// [x, y, 0.0] of the lower-left pixel's lower-left corner, negate 0, occupied_thresh 0.65,
/// free_thresh 0.196, mode trinary). Row 0 of every image is the largest y. Steps are judged
/// against the local ground as options.local_ground_radius_m says, then holes are filled as
/// options.fill_min_neighbours says (ProjectAsExported); the query API (TraversabilityMap::Project,
/// TopSurfaceAt) answers as observed, without either, and TopSurfaceAsExported with both.
/// Returns the projection that was written; `changes`, when not null, gets how many pixels each
/// step changed. Throws ssta::Error when the map has no surface and no region is given, when
/// fill_min_neighbours is not in 0..8 or local_ground_radius_m is negative or not finite (before
/// any file is written).
/// With options.headings.headings = N > 0 it also writes the cost per heading, one 8-bit PNG
/// per heading, HeadingCostPath(prefix, k, N) for k = 0..N-1: pixel round(254 cost), 255 where
/// the cost is unknown; PREFIX.yaml then lists them (heading_cost_images, in heading order) and
/// the footprint they were fitted under (heading_cost_footprint_m: [length, width]).
GridProjection ExportGrid(const TraversabilityMap& map, const std::string& prefix,
                          const GridExportOptions& options = GridExportOptions{},
                          GridExportChanges* changes = nullptr);

/// PREFIX_cost_heading_<yaw in degrees, HeadingName>.png: the `grid` export's image of heading k
/// of N.
std::string HeadingCostPath(const std::string& prefix, int k, int headings);

/// The value of a grid pixel in the `mcap` export's nav_msgs/OccupancyGrid, from its class id
/// and cost: non-traversable 100; traversable and semi-traversable round(100 cost) (0..75), or,
/// for a filled hole (no cost), the top of its class's cost range (25, 75); unknown and
/// undecided -1. So map_server's reading of the `grid` export's PGM (0 occupied, 254 free, 205
/// unknown) is this value thresholded: 100 occupied, -1 unknown, free otherwise.
std::int8_t OccupancyGridValue(std::uint8_t cls, float cost);

struct McapExportOptions {
  /// The grid of /map and /traversability, as the `grid` export makes it (ProjectAsExported).
  GridExportOptions grid;
  /// Chunks compressed with zstd; false: uncompressed.
  bool zstd = true;
  /// The frame the messages are given in (their header.frame_id). Must not be empty.
  std::string map_frame = "map";
  /// The world frame W the map's coordinates are in, the child of map_frame on /tf_static
  /// (identity transform). Empty: the map's metadata().world_frame, or "world" when unnamed.
  /// When it equals map_frame, /tf_static holds no transform.
  std::string world_frame;
};

/// What ExportMcap wrote.
struct McapExportSummary {
  int grid_width = 0, grid_height = 0;  ///< cells of /map and /traversability
  std::size_t voxels = 0;               ///< points of /traversability/voxels
  std::size_t path_poses = 0;           ///< poses of /sensor_path
  std::uint64_t bytes = 0;              ///< the file's size [bytes]
  std::uint32_t chunks = 0;             ///< MCAP chunks
  GridExportChanges changes;            ///< what the grid's export steps changed
};

/// The `mcap` export: a ROS 2 bag in one MCAP file (`ros2 bag play`, Foxglove, rviz2), written
/// with SSTA's MCAP writer (chunked, zstd or uncompressed, chunk and section CRCs, a summary
/// with statistics and chunk indexes), messages in CDR with their ros2msg schemas. One message
/// on each channel, all latched (offered QoS: reliable, transient local, keep last 1), stamped
/// with the map's last frame time:
///  - /map, nav_msgs/msg/OccupancyGrid: the `grid` export's grid (same region, resolution and
///    origin as its YAML), values OccupancyGridValue, row 0 the smallest y (ROS's convention).
///  - /traversability, grid_map_msgs/msg/GridMap: layers class (ids, NaN unknown), cost,
///    confidence, elevation (top surface voxel centre z [m]), slope [deg], step [m]; grid_map's
///    conventions: index (i, j) grows towards -x and -y from the cell at the largest x and y,
///    column-major Float32MultiArray (labels "column_index", "row_index"), pose the grid's centre.
///    With grid.headings.headings = N > 0, also layers cost_heading_<yaw in degrees> (HeadingName:
///    cost_heading_0, cost_heading_45, ...), HeadingCosts of the grid.
///  - /traversability/voxels, sensor_msgs/msg/PointCloud2: every occupied voxel's centre (x, y, z
///    float32), class (uint8), cost and confidence (float32), as SurfaceCells.
///  - /sensor_path, nav_msgs/msg/Path: sensor_path(), each pose facing the next.
///  - /tf_static, tf2_msgs/msg/TFMessage: map_frame -> world_frame, identity.
/// Written atomically. Throws ssta::Error as ExportGrid, for an empty map_frame, or naming the
/// file when it cannot be written.
McapExportSummary ExportMcap(const TraversabilityMap& map, const std::string& path,
                             const McapExportOptions& options = McapExportOptions{});

/// The `octovis` export: an OctoMap ColorOcTree file `path` (.ot) of the occupied voxels with
/// their occupancy, coloured by class (undecided grey 128), which octovis opens.
void ExportOctovis(const TraversabilityMap& map, const std::string& path);

/// ASCII PLY of the occupied voxel centres: x y z, red green blue (class colour), class, cost,
/// probability, slope_deg, step_m, observations.
void ExportPly(const TraversabilityMap& map, const std::string& path);

/// ASCII PCD (v0.7) of the same points and fields; colour is PCL's packed float `rgb`.
void ExportPcd(const TraversabilityMap& map, const std::string& path);

/// CSV of the occupied voxels, one row per voxel under kQueryCsvHeader.
void ExportCsv(const TraversabilityMap& map, const std::string& path);

}  // namespace ssta
