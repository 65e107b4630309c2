#include "ssta/mapping/map_export.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <vector>

#include <octomap/ColorOcTree.h>

#include "mapping/map_impl.h"
#include "ssta/core/error.h"
#include "ssta/files/file_util.h"
#include "ssta/files/png_file.h"
#include "ssta/mapping/confidence_bar.h"

namespace ssta {
namespace {

/// The colour exports use: class colours, undecided grey (as ColourizeLabels).
Rgb8 ExportColour(TravClass c) {
  if (c == TravClass::kUndecided) return Rgb8{128, 128, 128};
  return ClassColour(c);
}

/// PGM value of a class for map_server (negate 0): occupied 0, free 254, unknown 205.
std::uint8_t NavValue(std::uint8_t cls) {
  switch (static_cast<TravClass>(cls)) {
    case TravClass::kNonTraversable: return 0;
    case TravClass::kTraversable:
    case TravClass::kSemiTraversable: return 254;
    default: return 205;
  }
}

std::string Format(const char* fmt, double v) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), fmt, v);
  return buffer;
}

/// Writes `text` produced by `fill` to `path` atomically, errors naming the file.
template <typename Fill>
void WriteStreamAtomically(const std::string& path, Fill&& fill) {
  WriteFileAtomically(path, [&](const std::string& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throw Error(path + ": cannot open for writing");
    fill(out);
    out.flush();
    if (!out) throw Error(path + ": write failed (disk full?)");
  });
}

/// Widens `box` outwards to multiples of `res` (so pixels coincide with map columns).
Eigen::AlignedBox2d SnapOutwards(const Eigen::AlignedBox2d& box, double res) {
  // The tolerance keeps bounds that are multiples of res up to rounding (-1.0000000000000002)
  // from growing by a whole pixel.
  const Eigen::Vector2d lo = ((box.min() / res).array() + 1e-6).floor() * res;
  const Eigen::Vector2d hi = ((box.max() / res).array() - 1e-6).ceil() * res;
  Eigen::AlignedBox2d snapped(lo, hi);
  for (int i = 0; i < 2; ++i) {
    if (snapped.max()[i] - snapped.min()[i] < 0.5 * res) snapped.max()[i] = snapped.min()[i] + res;
  }
  return snapped;
}

double ExportResolution(const TraversabilityMap& map, const GridExportOptions& options) {
  return options.resolution_m > 0.0 ? options.resolution_m : map.options().resolution_m;
}

/// options.region, or the occupied voxels' bounding box when it is empty; `what` names the map
/// in the error when it has no surface.
Eigen::AlignedBox2d RegionToProject(const TraversabilityMap& map, const GridExportOptions& options,
                                    const std::string& what) {
  if (!options.region.isEmpty()) return options.region;
  const Eigen::AlignedBox3d bounds = map.SurfaceBounds();
  if (bounds.isEmpty()) throw Error(what + " has no observed surface to export (give a region)");
  return Eigen::AlignedBox2d(bounds.min().head<2>(), bounds.max().head<2>());
}

// A pixel's judgement reads the pixels within the local-ground radius, its fill the judgements
// of its 8 neighbours: this many pixels around it make its class the whole export's.
int ReachPx(const GridExportOptions& options, double res) {
  return static_cast<int>(std::floor(std::max(options.local_ground_radius_m, 0.0) / res + 1e-9)) + 2;
}

}  // namespace

int FillHoles(ImageU8* classes, int min_neighbours) {
  if (min_neighbours < 1 || min_neighbours > 8) {
    throw Error("fill_min_neighbours: must be in 1..8 (0: no filling), got " + std::to_string(min_neighbours));
  }
  const ImageU8 in = *classes;
  const int w = in.width(), h = in.height();
  int filled = 0;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      if (in(v, u) != static_cast<std::uint8_t>(TravClass::kUnknown)) continue;
      std::array<int, 4> count{};  // by class id 1..3
      for (int dv = -1; dv <= 1; ++dv) {
        for (int du = -1; du <= 1; ++du) {
          const int nv = v + dv, nu = u + du;
          if ((dv == 0 && du == 0) || !in.Contains(nv, nu)) continue;
          const int c = in(nv, nu);
          if (c >= 1 && c <= 3) ++count[c];
        }
      }
      if (count[1] + count[2] + count[3] < min_neighbours) continue;
      int best = 3;  // ties go to the worse class
      for (int c = 2; c >= 1; --c) {
        if (count[c] > count[best]) best = c;
      }
      (*classes)(v, u) = static_cast<std::uint8_t>(best);
      ++filled;
    }
  }
  return filled;
}

int JudgeStepsByLocalGround(GridProjection* grid, double radius_m, double tolerance_m, double level_slope_deg) {
  if (!(radius_m > 0.0 && std::isfinite(radius_m))) {
    throw Error("local_ground_radius_m: must be positive and finite (0: off), got " + std::to_string(radius_m));
  }
  if (!(tolerance_m >= 0.0 && std::isfinite(tolerance_m))) {
    throw Error("local ground tolerance: must be zero or positive, got " + std::to_string(tolerance_m));
  }
  constexpr int kMinSupport = 5;
  constexpr auto kTrav = static_cast<std::uint8_t>(TravClass::kTraversable);
  constexpr auto kNon = static_cast<std::uint8_t>(TravClass::kNonTraversable);
  const ImageU8 in = grid->classes;
  const int w = in.width(), h = in.height();
  const double reach = radius_m / grid->resolution_m;  // in pixels
  const int r = static_cast<int>(std::floor(reach + 1e-9));
  const double r2 = reach * reach + 1e-9;
  std::vector<float> heights;
  int changed = 0;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      if (in(v, u) != kNon) continue;
      const float z = grid->height_m(v, u), slope = grid->slope_deg(v, u);
      if (!std::isfinite(z) || slope >= level_slope_deg) continue;  // NaN: the frames' votes decided
      heights.clear();
      for (int dv = -r; dv <= r; ++dv) {
        for (int du = -r; du <= r; ++du) {
          const int nv = v + dv, nu = u + du;
          if (du * du + dv * dv > r2 || !in.Contains(nv, nu) || in(nv, nu) != kTrav) continue;
          const float nz = grid->height_m(nv, nu);
          if (std::isfinite(nz)) heights.push_back(nz);
        }
      }
      if (static_cast<int>(heights.size()) < kMinSupport) continue;
      // The median (the upper one of an even count: heights are voxel centres, so either is one).
      const auto mid = heights.begin() + static_cast<std::ptrdiff_t>(heights.size() / 2);
      std::nth_element(heights.begin(), mid, heights.end());
      if (std::abs(z - *mid) > tolerance_m + 1e-6) continue;
      grid->classes(v, u) = kTrav;
      grid->cost(v, u) = 0.0f;
      if (grid->confidence.size() == in.size()) grid->confidence(v, u) = std::numeric_limits<float>::quiet_NaN();
      ++changed;
    }
  }
  return changed;
}

/// A coordinate [m] with 4 decimals; beyond 1e9 m (a point asked far outside any map, which
/// %.4f would print with hundreds of digits) in exponent form.
std::string Coordinate(double v) { return Format(std::abs(v) < 1e9 ? "%.4f" : "%.6e", v); }

std::string QueryCsvRow(const CellInfo& cell) {
  std::string row;
  row += Coordinate(cell.center.x()) + ',' + Coordinate(cell.center.y()) + ',' + Coordinate(cell.center.z()) + ',';
  row += std::to_string(static_cast<int>(cell.cls)) + ',';
  row += Format("%.4f", cell.cost) + ',' + Format("%.4f", cell.probability) + ',';
  row += Format("%.2f", cell.slope_deg) + ',' + Format("%.3f", cell.step_m) + ',';
  row += std::to_string(cell.observations) + ',' + Format("%.4f", cell.confidence) + ',';
  row += std::string(ClassJudgeName(cell.decided_by)) + ',';
  row += Format("%.2f", cell.frame_mean_slope_deg) + ',' + Format("%.3f", cell.frame_mean_step_m);
  return row;
}

GridProjection ProjectAsExported(const TraversabilityMap& map, const GridExportOptions& options,
                                 GridExportChanges* changes) {
  const double res = ExportResolution(map, options);
  const Eigen::AlignedBox2d region = RegionToProject(map, options, "the map");
  GridProjection grid = map.Project(SnapOutwards(region, res), res);
  GridExportChanges counts;
  if (options.local_ground_radius_m != 0.0) {  // checks > 0
    counts.judged_by_local_ground = JudgeStepsByLocalGround(&grid, options.local_ground_radius_m, res,
                                                            map.metadata().vehicle.semi_slope_deg);
  }
  if (options.fill_min_neighbours != 0) {
    counts.holes_filled = FillHoles(&grid.classes, options.fill_min_neighbours);  // checks 1..8
  }
  if (options.min_confidence != 0.0) counts.below_confidence_bar = ApplyConfidenceBar(&grid, options.min_confidence);
  if (changes != nullptr) *changes = counts;
  return grid;
}

ExportedSurface::ExportedSurface(const TraversabilityMap& map, const Eigen::AlignedBox2d& region,
                                 const GridExportOptions& options)
    : map_(&map), options_(options), resolution_m_(ExportResolution(map, options)) {
  if (region.isEmpty() || !region.min().allFinite() || !region.max().allFinite()) {
    throw Error("ExportedSurface: the region must be finite and not empty");
  }
  border_px_ = ReachPx(options, resolution_m_);
  // Two pixels more than needed, so that rounding never leaves a pixel of `region` in the border.
  const Eigen::Vector2d margin = Eigen::Vector2d::Constant((border_px_ + 2) * resolution_m_);
  GridExportOptions local = options;
  local.region = Eigen::AlignedBox2d(region.min() - margin, region.max() + margin);
  grid_ = ProjectAsExported(map, local);
}

CellInfo ExportedSurface::operator()(double x, double y) const { return Answer(x, y, true); }

CellInfo ExportedSurface::Answer(double x, double y, bool reproject_outside) const {
  if (!std::isfinite(x) || !std::isfinite(y)) throw Error("exported surface query: x and y must be finite");
  CellInfo cell = map_->TopSurfaceAt(x, y);
  // At the map's resolution a pixel is one map column: read the pixel of the column's centre,
  // which no rounding moves across a pixel edge.
  const Eigen::Vector2d at =
      resolution_m_ == map_->options().resolution_m ? Eigen::Vector2d(cell.center.head<2>()) : Eigen::Vector2d(x, y);
  const int u = static_cast<int>(std::floor((at.x() - grid_.origin.x()) / resolution_m_));
  const int v = grid_.height() - 1 - static_cast<int>(std::floor((at.y() - grid_.origin.y()) / resolution_m_));
  if (reproject_outside &&
      (u < border_px_ || v < border_px_ || u >= grid_.width() - border_px_ || v >= grid_.height() - border_px_)) {
    const Eigen::Vector2d p(x, y);
    return ExportedSurface(*map_, Eigen::AlignedBox2d(p, p), options_).Answer(x, y, false);
  }
  if (!grid_.classes.Contains(v, u)) return cell;  // not reached: the column lies in its own projection
  const auto exported = static_cast<TravClass>(grid_.classes(v, u));
  // A class the export decided (a step judged by the local ground, a filled hole) has no
  // probability or confidence under the map's evidence, which was for the other class.
  // Nor a slope and step that decided it.
  if (!cell.observed || exported != cell.cls) {
    cell.probability = cell.confidence = std::numeric_limits<double>::quiet_NaN();
    if (exported != cell.cls) {
      const int c = static_cast<int>(exported);
      cell.decided_by = c >= 1 && c <= 3 ? ClassJudge::kExport : ClassJudge::kNone;
      cell.slope_deg = cell.step_m = std::numeric_limits<double>::quiet_NaN();
    }
  }
  cell.cls = exported;
  cell.cost = grid_.cost(v, u);
  return cell;
}

CellInfo TopSurfaceAsExported(const TraversabilityMap& map, double x, double y, const GridExportOptions& options) {
  if (!std::isfinite(x) || !std::isfinite(y)) throw Error("TopSurfaceAsExported: x and y must be finite");
  return ExportedSurface(map, Eigen::AlignedBox2d(Eigen::Vector2d(x, y), Eigen::Vector2d(x, y)), options)(x, y);
}

std::string HeadingCostPath(const std::string& prefix, int k, int headings) {
  return prefix + "_cost_heading_" + HeadingName(k, headings) + ".png";
}

GridProjection ExportGrid(const TraversabilityMap& map, const std::string& prefix,
                          const GridExportOptions& options, GridExportChanges* changes) {
  GridExportOptions resolved = options;
  resolved.region = RegionToProject(map, options, prefix + ".pgm: the map");
  std::string error;
  if (!options.headings.IsValid(&error)) throw Error(prefix + ".yaml: heading costs: " + error);
  const GridProjection grid = ProjectAsExported(map, resolved, changes);
  const int headings = options.headings.headings;
  const std::vector<ImageF> heading_costs =
      headings > 0 ? HeadingCosts(grid, map.metadata().vehicle, options.headings) : std::vector<ImageF>{};

  ImageU8 nav(grid.width(), grid.height());
  for (std::size_t i = 0; i < nav.size(); ++i) nav[i] = NavValue(grid.classes[i]);

  WritePng(ColourizeLabels(grid.classes), prefix + ".png");
  WritePng(grid.classes, prefix + "_classes.png");
  const std::string pgm = prefix + ".pgm";
  WriteStreamAtomically(pgm, [&](std::ostream& out) {
    out << "P5\n# SSTA navigation grid: 0 non-traversable, 254 traversable, 205 unknown\n"
        << nav.width() << ' ' << nav.height() << "\n255\n";
    out.write(reinterpret_cast<const char*>(nav.data()), static_cast<std::streamsize>(nav.size()));
  });
  const std::string image_name = std::filesystem::path(pgm).filename().string();
  std::ostringstream yaml;
  yaml << "# map_server map of an SSTA traversability map; origin is the lower-left corner of\n"
       << "# the lower-left pixel, row 0 of the image is the largest y.\n"
       << "image: " << image_name << '\n'
       << "resolution: " << Format("%.9g", grid.resolution_m) << '\n'
       << "origin: [" << Format("%.9g", grid.origin.x()) << ", " << Format("%.9g", grid.origin.y())
       << ", 0.0]\n"
       << "negate: 0\n"
       << "occupied_thresh: 0.65\n"
       << "free_thresh: 0.196\n"
       << "mode: trinary\n";
  if (headings > 0) {
    yaml << "# Cost per heading (yaw in degrees from +x towards +y in the file name), 8-bit: round(254 cost),\n"
         << "# 255 unknown; the vehicle's attitude on the ground under the footprint raises the class cost.\n"
         << "heading_cost_images: [";
    for (int k = 0; k < headings; ++k) {
      const std::string path = HeadingCostPath(prefix, k, headings);
      ImageU8 png(grid.width(), grid.height(), 255);
      const ImageF& cost = heading_costs[static_cast<std::size_t>(k)];
      for (std::size_t i = 0; i < png.size(); ++i) {
        if (std::isfinite(cost[i])) png[i] = static_cast<std::uint8_t>(std::lround(std::clamp(cost[i], 0.0f, 1.0f) * 254.0f));
      }
      WritePng(png, path);
      yaml << (k ? ", " : "") << std::filesystem::path(path).filename().string();
    }
    yaml << "]\nheading_cost_footprint_m: [" << Format("%.9g", options.headings.footprint_length_m) << ", "
         << Format("%.9g", options.headings.footprint_width_m) << "]\n";
  }
  WriteTextAtomically(prefix + ".yaml", yaml.str());
  return grid;
}

void ExportOctovis(const TraversabilityMap& map, const std::string& path) {
  const internal::TravOcTree& tree = internal::TraversabilityMapAccess::Tree(map);
  octomap::ColorOcTree colour(tree.getResolution());
  colour.setOccupancyThres(map.options().occupied_threshold_prob);
  colour.setClampingThresMin(map.options().occupancy_clamp_min_prob);
  colour.setClampingThresMax(map.options().occupancy_clamp_max_prob);
  for (const CellInfo& cell : map.SurfaceCells()) {
    octomap::OcTreeKey key;
    if (!colour.coordToKeyChecked(cell.center.x(), cell.center.y(), cell.center.z(), key)) continue;
    const Rgb8 rgb = ExportColour(cell.cls);
    colour.setNodeValue(key, static_cast<float>(octomap::logodds(cell.occupancy)), true);
    colour.setNodeColor(key, rgb.r, rgb.g, rgb.b);
  }
  // ColorOcTree::updateInnerOccupancy reads the root without checking it (OctoMap 1.9): a map
  // without surface voxels has none.
  if (colour.getRoot() != nullptr) colour.updateInnerOccupancy();
  WriteFileAtomically(path, [&](const std::string& tmp) {
    if (!colour.write(tmp)) throw Error(path + ": cannot write the ColorOcTree file");
  });
}

namespace {

/// Calls `row(cell, colour)` for every surface voxel.
template <typename Row>
void ForEachSurfaceCell(const TraversabilityMap& map, Row&& row) {
  for (const CellInfo& cell : map.SurfaceCells()) row(cell, ExportColour(cell.cls));
}

/// A voxel's numbers; its slope and step are the frames' means (a voxel's class is their vote).
std::string Numbers(const CellInfo& cell) {
  return std::to_string(static_cast<int>(cell.cls)) + ' ' + Format("%.6g", cell.cost) + ' ' +
         Format("%.6g", cell.probability) + ' ' + Format("%.6g", cell.frame_mean_slope_deg) + ' ' +
         Format("%.6g", cell.frame_mean_step_m) + ' ' + std::to_string(cell.observations);
}

std::string Xyz(const CellInfo& cell) {
  return Format("%.9g", cell.center.x()) + ' ' + Format("%.9g", cell.center.y()) + ' ' +
         Format("%.9g", cell.center.z());
}

}  // namespace

void ExportPly(const TraversabilityMap& map, const std::string& path) {
  const std::size_t n = map.SurfaceCells().size();
  WriteStreamAtomically(path, [&](std::ostream& out) {
    out << "ply\nformat ascii 1.0\ncomment SSTA traversability map voxels (centres, world frame, m)\n"
        << "element vertex " << n << '\n'
        << "property float x\nproperty float y\nproperty float z\n"
        << "property uchar red\nproperty uchar green\nproperty uchar blue\n"
        << "property uchar class\nproperty float cost\nproperty float probability\n"
        << "property float slope_deg\nproperty float step_m\nproperty uint observations\n"
        << "end_header\n";
    ForEachSurfaceCell(map, [&](const CellInfo& cell, const Rgb8& c) {
      out << Xyz(cell) << ' ' << int(c.r) << ' ' << int(c.g) << ' ' << int(c.b) << ' '
          << Numbers(cell) << '\n';
    });
  });
}

void ExportPcd(const TraversabilityMap& map, const std::string& path) {
  const std::size_t n = map.SurfaceCells().size();
  WriteStreamAtomically(path, [&](std::ostream& out) {
    out << "# .PCD v0.7 - SSTA traversability map voxels (centres, world frame, m)\n"
        << "VERSION 0.7\n"
        << "FIELDS x y z rgb class cost probability slope_deg step_m observations\n"
        << "SIZE 4 4 4 4 1 4 4 4 4 4\n"
        << "TYPE F F F F U F F F F U\n"
        << "COUNT 1 1 1 1 1 1 1 1 1 1\n"
        << "WIDTH " << n << "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\n"
        << "POINTS " << n << "\nDATA ascii\n";
    ForEachSurfaceCell(map, [&](const CellInfo& cell, const Rgb8& c) {
      const std::uint32_t packed = (std::uint32_t(c.r) << 16) | (std::uint32_t(c.g) << 8) | c.b;
      float rgb;
      std::memcpy(&rgb, &packed, sizeof(rgb));
      out << Xyz(cell) << ' ' << Format("%.9g", rgb) << ' ' << Numbers(cell) << '\n';
    });
  });
}

void ExportCsv(const TraversabilityMap& map, const std::string& path) {
  WriteStreamAtomically(path, [&](std::ostream& out) {
    out << kQueryCsvHeader << '\n';
    ForEachSurfaceCell(map, [&](const CellInfo& cell, const Rgb8&) { out << QueryCsvRow(cell) << '\n'; });
  });
}

}  // namespace ssta
