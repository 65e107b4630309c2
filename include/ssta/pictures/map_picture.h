#pragma once

// A picture of a map for people: the exported grid in class colours over a hillshade of the
// surface heights, with the vehicle's path, metric axes, a scale bar and a legend
// (`ssta export --format picture`, `ssta build-map --picture`).

#include <string>

#include <Eigen/Core>

#include "ssta/core/image.h"
#include "ssta/mapping/map_export.h"
#include "ssta/mapping/traversability_map.h"

namespace ssta {

struct MapPictureOptions {
  /// The grid drawn: ProjectAsExported with these options (region, resolution, holes, local
  /// ground), so the picture shows what `export --format grid` writes. When the resolution is
  /// left at 0 and the region spans more than max_cells map columns, the picture's cells are
  /// coarsened (each the worst class of the columns it holds) to fit.
  GridExportOptions grid;
  /// Shade each cell by its surface's relief (light from the north-west, 45 deg up), so
  /// slopes, ridges and ditches read at a glance. Off: flat class colours.
  bool hillshade = true;
  /// Cells along the longer side at most (see grid); 100..20000.
  int max_cells = 1500;
  /// Side of one cell on screen [px]: the largest integer that keeps the map within
  /// max_map_px along its longer side (at least 1).
  int max_map_px = 1200;
  /// First line of the title; empty: "SSTA map".
  std::string title;
};

/// A rendered picture and where the map lies in it.
struct MapPicture {
  ImageRgb image;
  GridProjection grid;   ///< the cells drawn (class, height, ...)
  int cell_px = 1;       ///< pixels per cell edge
  Eigen::Vector2i map_top_left_px = Eigen::Vector2i::Zero();  ///< (u, v) of the grid's top-left corner

  /// The picture pixel (u, v) where the point (x, y) in W [m] is drawn (it may lie outside).
  Eigen::Vector2i PixelOf(const Eigen::Vector2d& xy_world) const;
};

/// Colours of the picture (RGB). Class colours are softer than ClassColour's pure primaries
/// but keep their hues (green traversable, blue semi, red non-traversable).
namespace picture_colours {
inline constexpr Rgb8 kTraversable{88, 178, 92};
inline constexpr Rgb8 kSemiTraversable{66, 120, 220};
inline constexpr Rgb8 kNonTraversable{214, 52, 44};
inline constexpr Rgb8 kUndecided{150, 150, 150};
inline constexpr Rgb8 kUnknown{222, 218, 206};      ///< inside the grid, never observed (hatched)
inline constexpr Rgb8 kUnknownHatch{196, 190, 176};
inline constexpr Rgb8 kBackground{255, 255, 255};   ///< outside the grid
inline constexpr Rgb8 kPath{20, 20, 20};
inline constexpr Rgb8 kPathHalo{255, 255, 255};
}  // namespace picture_colours

/// Renders `map` as a picture: the grid of options.grid with row 0 at the largest y (x to the
/// right, y up, as the grid export), unknown cells hatched so they differ from the white
/// background, the sensor path (TraversabilityMap::sensor_path) as a dark line with a circle
/// at its start and a square at its end, ticks in metres on two sides, a scale bar and a
/// legend. Throws ssta::Error as ProjectAsExported (an empty map needs options.grid.region),
/// and for max_cells or max_map_px out of range.
MapPicture RenderMapPicture(const TraversabilityMap& map, const MapPictureOptions& options = MapPictureOptions{});

/// RenderMapPicture written to `path` (PNG) atomically; errors name the file.
MapPicture ExportPicture(const TraversabilityMap& map, const std::string& path,
                         const MapPictureOptions& options = MapPictureOptions{});

}  // namespace ssta
