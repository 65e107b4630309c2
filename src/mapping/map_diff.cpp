// DiffMaps: two maps of one site projected on one lattice of columns, each column's change
// sorted into real changes, coverage and uncertainty. The picture is drawn in src/pictures/map_picture.cpp.

#include "ssta/mapping/map_diff.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "ssta/core/error.h"
#include "ssta/mapping/map_merge.h"

namespace ssta {
namespace {

bool HasClass(std::uint8_t cls) { return cls >= 1 && cls <= 3; }

constexpr std::uint8_t kSemi = static_cast<std::uint8_t>(TravClass::kSemiTraversable);
constexpr std::uint8_t kNon = static_cast<std::uint8_t>(TravClass::kNonTraversable);
constexpr std::uint8_t kUndecidedId = static_cast<std::uint8_t>(TravClass::kUndecided);

/// The region both maps' surfaces cover, with a metre around their sensor paths (as the map
/// picture), widened outwards to multiples of `resolution_m` so that its pixels are the map
/// columns. Empty when neither map has a surface.
Eigen::AlignedBox2d ColumnRegion(const TraversabilityMap& a, const TraversabilityMap& b, double resolution_m) {
  Eigen::AlignedBox2d region;
  for (const TraversabilityMap* map : {&a, &b}) {
    const Eigen::AlignedBox3d bounds = map->SurfaceBounds();
    if (bounds.isEmpty()) continue;
    region.extend(bounds.min().head<2>());
    region.extend(bounds.max().head<2>());
  }
  if (region.isEmpty()) return region;
  for (const TraversabilityMap* map : {&a, &b}) {
    for (const Eigen::Vector3d& p : map->sensor_path()) {
      region.extend(p.head<2>() - Eigen::Vector2d::Ones());
      region.extend(p.head<2>() + Eigen::Vector2d::Ones());
    }
  }
  const Eigen::Vector2d lo = (region.min() / resolution_m).array().floor() * resolution_m;
  Eigen::Vector2d hi = (region.max() / resolution_m).array().ceil() * resolution_m;
  // A region of one column's width still holds that column.
  for (int k = 0; k < 2; ++k) hi[k] = std::max(hi[k], lo[k] + resolution_m);
  return Eigen::AlignedBox2d(lo, hi);
}

std::string Decimals(double value, int decimals) {
  if (!std::isfinite(value)) return "nan";
  char buffer[48];
  std::snprintf(buffer, sizeof(buffer), "%.*f", decimals, value);
  return buffer;
}

}  // namespace

const char* CellChangeName(CellChange change) {
  static const char* const kNames[kCellChangeCount] = {
      "", "unchanged", "new_obstacle", "cleared", "harder", "easier", "newly_seen", "no_longer_seen", "uncertain"};
  const auto id = static_cast<std::size_t>(change);
  return id < kCellChangeCount ? kNames[id] : "";
}

bool IsRealChange(CellChange change) {
  return change == CellChange::kNewObstacle || change == CellChange::kCleared || change == CellChange::kHarder ||
         change == CellChange::kEasier;
}

bool MapDiffOptions::IsValid(std::string* error) const {
  const auto fail = [&](const std::string& message) {
    if (error != nullptr) *error = message;
    return false;
  };
  if (!(min_confidence >= 0.0 && min_confidence <= 1.0)) return fail("min_confidence: must be in [0, 1]");
  if (!(slope_noise_deg > 0.0 && std::isfinite(slope_noise_deg))) return fail("slope_noise_deg: must be > 0");
  if (!(step_noise_m > 0.0 && std::isfinite(step_noise_m))) return fail("step_noise_m: must be > 0");
  if (boundary_shift_columns < 0 || boundary_shift_columns > 10) return fail("boundary_shift_columns: must be in 0..10");
  return true;
}

CellChange ClassifyChange(std::uint8_t class_a, double confidence_a, double slope_a_deg, double step_a_m,
                          std::uint8_t class_b, double confidence_b, double slope_b_deg, double step_b_m,
                          const MapDiffOptions& options) {
  const bool a_has = HasClass(class_a), b_has = HasClass(class_b);
  if (!a_has && !b_has) return CellChange::kNone;
  if (!a_has) return class_a == kUndecidedId ? CellChange::kUncertain : CellChange::kNewlySeen;
  if (!b_has) return class_b == kUndecidedId ? CellChange::kUncertain : CellChange::kNoLongerSeen;
  if (class_a == class_b) return CellChange::kUnchanged;
  // NaN confidences fail the comparison: no confidence is no certainty.
  if (!(confidence_a >= options.min_confidence && confidence_b >= options.min_confidence)) {
    return CellChange::kUncertain;
  }
  const bool next_to_semi = (class_a == kSemi || class_b == kSemi);  // 1 <-> 2 or 2 <-> 3
  if (next_to_semi) {
    const bool slope_moved = std::abs(slope_b_deg - slope_a_deg) > options.slope_noise_deg;
    const bool step_moved = std::abs(step_b_m - step_a_m) > options.step_noise_m;
    if (!slope_moved && !step_moved) return CellChange::kUncertain;
  }
  if (class_b == kNon) return CellChange::kNewObstacle;
  if (class_a == kNon) return CellChange::kCleared;
  return class_b == kSemi ? CellChange::kHarder : CellChange::kEasier;
}

std::size_t MapDiffSummary::RealChanges() const {
  std::size_t n = 0;
  for (int id = 0; id < kCellChangeCount; ++id) n += IsRealChange(static_cast<CellChange>(id)) ? counts[id] : 0;
  return n;
}

std::string MapDiffSummary::BriefReport() const {
  std::ostringstream r;
  r << "columns with a class in both maps: " << compared << "\n";
  for (int id = 1; id < kCellChangeCount; ++id) {
    r << "  " << CellChangeName(static_cast<CellChange>(id)) << ": " << counts[id] << "\n";
  }
  r << "real changes (new_obstacle, cleared, harder, easier): " << RealChanges() << "\n";
  return r.str();
}

namespace {

/// `grid` holds `cls` in a column within `reach` columns of (v, u) (the square around it).
bool ClassNear(const GridProjection& grid, int v, int u, std::uint8_t cls, int reach) {
  for (int dv = -reach; dv <= reach; ++dv) {
    for (int du = -reach; du <= reach; ++du) {
      const int vv = v + dv, uu = u + du;
      if (vv < 0 || uu < 0 || vv >= grid.height() || uu >= grid.width()) continue;
      if (grid.classes(vv, uu) == cls) return true;
    }
  }
  return false;
}

}  // namespace

MapDiff DiffProjections(const GridProjection& a, const GridProjection& b, const MapDiffOptions& options) {
  std::string error;
  if (!options.IsValid(&error)) throw Error("diff options: " + error);
  const bool same_lattice = a.width() == b.width() && a.height() == b.height() &&
                            std::abs(a.resolution_m - b.resolution_m) <= 1e-9 * a.resolution_m &&
                            (a.origin - b.origin).cwiseAbs().maxCoeff() <= 1e-6 * a.resolution_m;
  if (!same_lattice) throw Error("diff: the two projections do not share one lattice (origin, resolution, size)");
  MapDiff diff;
  diff.a = a;
  diff.b = b;
  diff.change = ImageU8(a.width(), a.height(), 0);
  for (int v = 0; v < a.height(); ++v) {
    for (int u = 0; u < a.width(); ++u) {
      const std::uint8_t ca = a.classes(v, u), cb = b.classes(v, u);
      CellChange change = ClassifyChange(ca, a.confidence(v, u), a.slope_deg(v, u), a.step_m(v, u), cb,
                                         b.confidence(v, u), b.slope_deg(v, u), b.step_m(v, u), options);
      // A boundary between two classes that moved by a column or two: each map holds the
      // other's class right beside the column.
      if (IsRealChange(change) && options.boundary_shift_columns > 0 &&
          ClassNear(a, v, u, cb, options.boundary_shift_columns) &&
          ClassNear(b, v, u, ca, options.boundary_shift_columns)) {
        change = CellChange::kUncertain;
      }
      diff.change(v, u) = static_cast<std::uint8_t>(change);
      ++diff.summary.counts[static_cast<std::size_t>(change)];
      if (HasClass(ca) && HasClass(cb)) ++diff.summary.compared;
      if (change == CellChange::kNone || change == CellChange::kUnchanged) continue;
      CellDiff cell;
      cell.xy = a.PixelCenter(v, u);
      cell.class_a = ca;
      cell.class_b = cb;
      cell.confidence_a = HasClass(ca) ? a.confidence(v, u) : std::nan("");
      cell.confidence_b = HasClass(cb) ? b.confidence(v, u) : std::nan("");
      cell.change = change;
      diff.cells.push_back(cell);
    }
  }
  return diff;
}

MapDiff DiffMaps(const TraversabilityMap& a, const std::string& a_file, const TraversabilityMap& b,
                 const std::string& b_file, const MapDiffOptions& options) {
  std::string error;
  if (!options.IsValid(&error)) throw Error("diff options: " + error);
  const std::string advice = "maps compare only when they share resolution, world frame and vehicle";
  RequireSameWorldGrid(a, a_file, b, b_file, advice);
  RequireSameVehicle(a.metadata().vehicle, a_file + ": built for", b.metadata().vehicle, b_file + ": built for", "",
                     advice);
  const double res = a.options().resolution_m;
  const Eigen::AlignedBox2d region = ColumnRegion(a, b, res);
  if (region.isEmpty()) throw Error(a_file + " and " + b_file + ": neither map has a surface to compare");
  MapDiff diff = DiffProjections(a.Project(region, res), b.Project(region, res), options);
  diff.path_a = a.sensor_path();
  diff.path_b = b.sensor_path();
  return diff;
}

std::string MapDiffCsv(const MapDiff& diff) {
  std::string csv = std::string(kMapDiffCsvHeader) + "\n";
  for (const CellDiff& c : diff.cells) {
    csv += Decimals(c.xy.x(), 4) + "," + Decimals(c.xy.y(), 4) + "," + std::to_string(c.class_a) + "," +
           std::to_string(c.class_b) + "," + Decimals(c.confidence_a, 4) + "," + Decimals(c.confidence_b, 4) + "," +
           CellChangeName(c.change) + "\n";
  }
  return csv;
}

}  // namespace ssta
