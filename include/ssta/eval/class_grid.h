#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "ssta/core/image.h"

namespace ssta {

/// A cell of a ClassGrid: image row (0 = largest y) and column (0 = smallest x).
struct GridCell {
  int row = 0;
  int col = 0;
};

/// A 2D world grid of class ids in the map_server convention (docs/interfaces.md, section 5, `export`
/// grid): column c spans x in [origin.x + c * res, origin.x + (c + 1) * res); image row 0 holds
/// the largest y, so row r spans y in [origin.y + (H - 1 - r) * res, origin.y + (H - r) * res).
/// `origin_m` is the world (x, y) of the lower-left corner of the lower-left pixel (the last
/// image row, first column), as map_server reads `origin` in its YAML. Cell bounds are
/// half-open; a point on a shared edge belongs to the cell with the larger index along x, or
/// the larger y along y.
struct ClassGrid {
  ImageU8 classes;                                      ///< class ids, row 0 = largest y
  double resolution_m = 0.0;                            ///< cell edge length [m], > 0
  Eigen::Vector2d origin_m = Eigen::Vector2d::Zero();  ///< lower-left corner, world x, y [m]
  std::string source;  ///< the file the classes came from; names it in error messages
  std::string seen;    ///< the YAML's `seen` key (truth grids of ssta synth); empty when absent

  /// The cell containing world point (x, y) [m], or nothing outside the grid.
  std::optional<GridCell> CellAt(const Eigen::Vector2d& p_world) const;
  /// World (x, y) [m] of the centre of `cell`; the cell need not lie inside the grid.
  Eigen::Vector2d CellCentre(const GridCell& cell) const;
  /// Class id at world point (x, y) [m]; 0 (unknown) outside the grid.
  std::uint8_t ClassAt(const Eigen::Vector2d& p_world) const;
};

/// Reads a class grid: 8-bit ids from `classes_png` and `resolution` and `origin` from the
/// map_server style `yaml_path` (its `image` key is not followed: the nav image it usually
/// names is not the class image). Other map_server keys (image, negate, occupied_thresh,
/// free_thresh, mode) are accepted and ignored. Throws ssta::Error naming the file and key
/// when a file is missing, `resolution` is not positive, `origin` is not [x, y] or
/// [x, y, yaw] with yaw 0 (rotated grids are not supported), or the image is not 8-bit grey.
ClassGrid ReadClassGrid(const std::string& yaml_path, const std::string& classes_png);

/// The ground-truth folder of a synthetic sequence: SEQ/gt, or SEQ/mav0/gt as EuRoC nests it;
/// a path to a folder named gt is taken as it is. Throws ssta::Error naming both places when
/// neither exists.
std::string FindGroundTruthDir(const std::string& sequence);

/// Reads SEQ/gt/grid_classes.png with SEQ/gt/grid.yaml (docs/interfaces.md, section 6). Throws
/// ssta::Error as ReadClassGrid.
ClassGrid ReadGroundTruthGrid(const std::string& sequence);

/// What a truth grid read by ReadGroundTruthGrid leaves unscored, as a warning to print: empty
/// when its `seen` key is synth::kTruthSeenBothCameras, else a sentence naming its YAML that says
/// it predates that seen mask (cells along class boundaries, beside every obstacle and lip, count
/// as unseen, so unsafe and falsely blocked figures on it leave most of those footprints out)
/// and to render the sequence again.
std::string StaleTruthGridWarning(const ClassGrid& truth);

}  // namespace ssta
