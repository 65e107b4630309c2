#pragma once

// What changed between two maps of one site (`ssta diff-maps A.ot B.ot --out D`): each map
// column's class in both maps, sorted into real changes (a new obstacle, a cleared one, harder or
// easier ground), changes of coverage (newly seen, no longer seen) and changes that are only
// uncertain (docs/fleet.md).

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ssta/core/image.h"
#include "ssta/mapping/map_types.h"
#include "ssta/mapping/traversability_map.h"

namespace ssta {

/// How a map column changed from map A to map B (the ids of DiffMaps' `change` image). Class
/// ids as docs/interfaces.md, section 3: a column "has a class" when it holds 1..3.
enum class CellChange : std::uint8_t {
  kNone = 0,          ///< neither map has a class there
  kUnchanged = 1,     ///< the same class in both
  kNewObstacle = 2,   ///< traversable or semi-traversable in A, non-traversable in B
  kCleared = 3,       ///< non-traversable in A, traversable or semi-traversable in B
  kHarder = 4,        ///< traversable in A, semi-traversable in B
  kEasier = 5,        ///< semi-traversable in A, traversable in B
  kNewlySeen = 6,     ///< unobserved in A (class 0), a class in B
  kNoLongerSeen = 7,  ///< a class in A, unobserved in B
  /// The class differs but the change may be noise: one map is not sure of its class
  /// (confidence below MapDiffOptions::min_confidence), one saw a surface it could not judge
  /// (undecided, class 4), a change between semi-traversable and a neighbouring class whose
  /// slope and step moved less than the noise (MapDiffOptions::slope_noise_deg, step_noise_m),
  /// or a boundary between two classes that moved (MapDiffOptions::boundary_shift_columns).
  kUncertain = 8,
};
inline constexpr int kCellChangeCount = 9;

/// Lower-case name, as diff.csv's `change` column writes it: "", "unchanged", "new_obstacle",
/// "cleared", "harder", "easier", "newly_seen", "no_longer_seen", "uncertain".
const char* CellChangeName(CellChange change);

/// The changes a user acts on: new obstacle, cleared, harder, easier (not coverage, not
/// uncertain).
bool IsRealChange(CellChange change);

struct MapDiffOptions {
  /// A class change counts only where both maps hold their class with at least this confidence
  /// (CellInfo::confidence, the posterior probability of the class); below it in either map the
  /// column is uncertain. In [0, 1]. 0.6: a class the map holds at 60 % or more beats the two
  /// others together by 1.5 to 1.
  double min_confidence = 0.6;
  /// A change between semi-traversable and a neighbouring class (traversable or
  /// non-traversable) counts only where the slope that decided the classes moved by more than
  /// this [deg] or the step by more than step_noise_m: such a change follows a threshold
  /// (semi_slope_deg, max_step_m, ...), and a column near it flips with the stereo noise.
  /// > 0. The defaults: 90 % of the columns whose class stayed the same between two drives of
  /// the rendered yard (320 x 240) moved less (docs/fleet.md).
  double slope_noise_deg = 20.0;
  double step_noise_m = 0.10;  ///< [m], > 0; as slope_noise_deg
  /// A real change (new obstacle, cleared, harder, easier) where map A holds B's class and map
  /// B holds A's class within this many columns of it is uncertain: the boundary between the
  /// two classes only moved, as the rim of an obstacle does with stereo's smear from one drive
  /// to the next. 0: off; 0..10.
  int boundary_shift_columns = 1;
  /// The first field out of its range, as "key: requirement" in `*error`.
  bool IsValid(std::string* error) const;
};

/// One column whose class changed (diff.csv's row).
struct CellDiff {
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();  ///< column centre in W [m]
  std::uint8_t class_a = 0, class_b = 0;         ///< class ids in A and B (0..4)
  /// CellInfo::confidence in A and B; NaN where the map has no class 1..3.
  double confidence_a = 0.0, confidence_b = 0.0;
  CellChange change = CellChange::kNone;
};

/// What DiffMaps found.
struct MapDiffSummary {
  /// Columns of each CellChange (index: its id).
  std::array<std::size_t, kCellChangeCount> counts{};
  std::size_t compared = 0;  ///< columns with a class in both maps
  /// Columns of the real changes (IsRealChange).
  std::size_t RealChanges() const;
  /// One line per change type with its count, and the columns compared.
  std::string BriefReport() const;
};

/// Two maps on one lattice of columns and how each column changed.
struct MapDiff {
  GridProjection a, b;  ///< the top surfaces of A and B over one region, at the maps' resolution
  ImageU8 change;       ///< CellChange id per pixel, the projections' size (row 0 the largest y)
  std::vector<CellDiff> cells;  ///< the columns whose class changed (change not kNone or kUnchanged), row by row
  MapDiffSummary summary;
  std::vector<Eigen::Vector3d> path_a, path_b;  ///< the maps' sensor paths (for the picture)
};

/// The change of one column from its class and confidence in A and B, and the slope [deg] and
/// step [m] that decided each class (NaN where unknown), under `options` (CellChange; all but
/// the boundary-shift rule, which needs the columns around).
CellChange ClassifyChange(std::uint8_t class_a, double confidence_a, double slope_a_deg, double step_a_m,
                          std::uint8_t class_b, double confidence_b, double slope_b_deg, double step_b_m,
                          const MapDiffOptions& options = MapDiffOptions{});

/// The change of every pixel of two projections of one lattice (same origin, resolution and
/// size; throws ssta::Error otherwise) by ClassifyChange, then the boundary-shift rule
/// (MapDiffOptions::boundary_shift_columns). Paths are left empty.
MapDiff DiffProjections(const GridProjection& a, const GridProjection& b, const MapDiffOptions& options = MapDiffOptions{});

/// Compares map `b` (read from `b_file`) with map `a` (from `a_file`), the earlier drive:
/// both are projected (TraversabilityMap::Project, the top surface as observed: no hole filling)
/// at their resolution over the union of their surfaces (and a metre around their sensor
/// paths), on the lattice of the map columns, and
/// each column classified by ClassifyChange. Throws ssta::Error naming both files and both
/// values when the maps differ in resolution or world frame (RequireSameWorldGrid) or in
/// vehicle (the classes are that vehicle's: a change of vehicle is not a change of the site),
/// when neither map has a surface, or for invalid options.
MapDiff DiffMaps(const TraversabilityMap& a, const std::string& a_file, const TraversabilityMap& b,
                 const std::string& b_file, const MapDiffOptions& options = MapDiffOptions{});

/// Header of diff.csv.
inline constexpr char kMapDiffCsvHeader[] = "x,y,class_a,class_b,confidence_a,confidence_b,change";

/// Colours of the diff picture (RGB).
namespace change_colours {
inline constexpr Rgb8 kUnchanged{205, 205, 205};          ///< unchanged ground (traversable, semi)
inline constexpr Rgb8 kUnchangedObstacle{130, 130, 130};  ///< unchanged non-traversable
inline constexpr Rgb8 kNewObstacle{214, 40, 40};
inline constexpr Rgb8 kCleared{40, 170, 60};
inline constexpr Rgb8 kHarder{240, 140, 30};
inline constexpr Rgb8 kEasier{150, 215, 110};
inline constexpr Rgb8 kNewlySeen{50, 100, 225};
inline constexpr Rgb8 kNoLongerSeen{185, 170, 225};
inline constexpr Rgb8 kUncertain{240, 210, 40};
}  // namespace change_colours

/// The diff as CSV text: kMapDiffCsvHeader, then one row per MapDiff::cells entry (x, y [m] with
/// 4 decimals, the class ids, the confidences with 4 decimals or "nan", the change's name), each
/// line ending in a newline. The picture beside it is ssta/pictures/map_diff_picture.h.
std::string MapDiffCsv(const MapDiff& diff);

}  // namespace ssta
