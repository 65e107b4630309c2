#pragma once

// Exports of a TraversabilityMap for other tools. Every file is written atomically (temporary
// file + rename); failures throw ssta::Error naming the file.

#include <string>

#include <Eigen/Geometry>

#include "ssta/mapping/traversability_map.h"

namespace ssta {

/// Header of the query CSV (INTERFACES section 5) and of the `csv` export.
inline constexpr char kQueryCsvHeader[] = "x,y,z,class,cost,probability,slope_deg,step_m,observations";

/// One CSV row (no newline) for `cell` under kQueryCsvHeader: centre x, y, z [m] with 4
/// decimals, class id, cost and probability with 4 decimals, slope [deg] with 2, mean step [m]
/// with 3, observations. Unknown values print as "nan".
std::string QueryCsvRow(const CellInfo& cell);

struct GridExportOptions {
  /// Pixel edge [m]; <= 0 takes the map's resolution.
  double resolution_m = 0.0;
  /// Region to export (x, y in W). Empty (the default): the occupied voxels' bounding box.
  /// The region is widened outwards to multiples of the resolution, so with the map's
  /// resolution every pixel is exactly one map column.
  Eigen::AlignedBox2d region;
};

/// The `grid` export (INTERFACES section 5): PREFIX.png (class colours, undecided grey),
/// PREFIX_classes.png (8-bit class ids), PREFIX.pgm (non-traversable 0, traversable and semi
/// 254, unknown and undecided 205) and PREFIX.yaml (map_server: image, resolution, origin
/// [x, y, 0.0] of the lower-left pixel's lower-left corner, negate 0, occupied_thresh 0.65,
/// free_thresh 0.196, mode trinary). Row 0 of every image is the largest y. Returns the
/// projection that was written. Throws ssta::Error when the map has no surface and no region
/// is given.
GridProjection ExportGrid(const TraversabilityMap& map, const std::string& prefix,
                          const GridExportOptions& options = GridExportOptions{});

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
