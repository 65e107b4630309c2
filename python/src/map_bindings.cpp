// ssta.Map: a TraversabilityMap read from a file, queried with NumPy arrays. Every query runs
// its loop in C++ with the GIL released, so several Python threads query one map at once (the
// map's const methods are safe to call concurrently: traversability_map.h).

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <pybind11/stl.h>

#include "bindings.h"
#include "query_row.h"
#include "ssta/mapping/map_diff.h"
#include "ssta/mapping/confidence_bar.h"
#include "ssta/mapping/map_export.h"
#include "ssta/mapping/traversability_map.h"
#if !SSTA_PYTHON_MAP_ONLY
#include "ssta/pictures/map_diff_picture.h"
#endif

namespace ssta::python {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// One row of Map.footprints: the columns of `ssta query --footprint`.
struct FootprintRow {
  std::uint8_t worst;
  double mean_cost, max_cost, fraction_observed;
  std::int32_t cells, observed_cells;
  double pitch_deg, roll_deg;
  std::uint8_t attitude;
  std::int32_t attitude_heights;
  double drivable_confidence;
  bool within_limits;
};

// One sample of Map.path: the columns of `ssta query --path`.
struct PathRow {
  double distance_m, x, y;
  std::uint8_t cls;
  double cost, fraction_observed, drivable_confidence;
};

// A loaded map and the file it came from.
struct MapHandle {
  TraversabilityMap map;
  std::string path;
};

// The planner's confidence bar of query, footprints and path (`--min-confidence`), checked.
void CheckMinConfidence(double min_confidence) {
  if (!(min_confidence >= 0.0 && min_confidence <= 1.0)) {
    throw py::value_error("min_confidence: must be a probability in [0, 1], got " + std::to_string(min_confidence));
  }
}

// The grid export's two steps, for the queries' as_exported (`--fill-holes`, `--local-ground`).
GridExportOptions ExportSteps(int fill_holes, double local_ground_radius_m) {
  if (fill_holes < 0 || fill_holes > 8) {
    throw py::value_error("fill_holes: must be in 0..8 (0: off), got " + std::to_string(fill_holes));
  }
  GridExportOptions options;
  options.fill_min_neighbours = fill_holes;
  options.local_ground_radius_m = NonNegativeArg(local_ground_radius_m, "local_ground_radius_m");
  return options;
}

// Rethrows a query's ssta::Error naming the argument and row instead of the library's query
// ("footprint query: ..." -> "poses[3]: ..."), as the command line names its option.
template <class Query>
auto NamingTheArgument(const std::string& argument, const std::string& library_prefix, Query&& query) {
  try {
    return query();
  } catch (const Error& e) {
    std::string message = e.what();
    if (message.rfind(library_prefix, 0) == 0) message.erase(0, library_prefix.size());
    throw Error(argument + ": " + message);
  }
}

// The exported surface over `box` when it spans at most 4e6 map columns, else one that projects
// each asked column on its own (as `ssta query --as-exported`): each answer is the same from any
// projection that holds its column (ExportedSurface).
std::unique_ptr<ExportedSurface> ExportedOver(const TraversabilityMap& map, Eigen::AlignedBox2d box,
                                              const GridExportOptions& options) {
  const double res = map.options().resolution_m;
  if (box.sizes().x() / res * (box.sizes().y() / res) > 4e6) box = Eigen::AlignedBox2d(box.min(), box.min());
  return std::make_unique<ExportedSurface>(map, box, options);
}

// The NumPy dtype of QueryRow: its fields under the names of `ssta query`'s columns, decided_by
// as a string ('<U7'), which PYBIND11_NUMPY_DTYPE cannot describe.
py::dtype QueryRowDtype() {
  static_assert(sizeof(char32_t) == 4, "decided_by is UTF-32");
  py::list names, formats, offsets;
  auto field = [&](const char* name, const std::string& format, std::size_t offset) {
    names.append(name);
    formats.append(format);
    offsets.append(offset);
  };
  field("x", "<f8", offsetof(QueryRow, x));
  field("y", "<f8", offsetof(QueryRow, y));
  field("z", "<f8", offsetof(QueryRow, z));
  field("class", "u1", offsetof(QueryRow, cls));
  field("cost", "<f8", offsetof(QueryRow, cost));
  field("probability", "<f8", offsetof(QueryRow, probability));
  field("slope_deg", "<f8", offsetof(QueryRow, slope_deg));
  field("step_m", "<f8", offsetof(QueryRow, step_m));
  field("observations", "<u4", offsetof(QueryRow, observations));
  field("confidence", "<f8", offsetof(QueryRow, confidence));
  field("decided_by", "<U" + std::to_string(kDecidedByChars), offsetof(QueryRow, decided_by));
  field("frame_mean_slope_deg", "<f8", offsetof(QueryRow, frame_mean_slope_deg));
  field("frame_mean_step_m", "<f8", offsetof(QueryRow, frame_mean_step_m));
  field("height_m", "<f8", offsetof(QueryRow, height_m));
  field("observed", "?", offsetof(QueryRow, observed));
  py::dict spec;
  spec["names"] = names;
  spec["formats"] = formats;
  spec["offsets"] = offsets;
  spec["itemsize"] = sizeof(QueryRow);
  return py::dtype::from_args(spec);
}

py::array Query(const MapHandle& handle, const py::object& points_arg, bool as_exported, int fill_holes,
                double local_ground_radius_m, double min_confidence) {
  const GridExportOptions steps = ExportSteps(fill_holes, local_ground_radius_m);
  CheckMinConfidence(min_confidence);
  const auto points = MatrixArg(points_arg, "points", 2, 3);
  const py::ssize_t n = points.shape(0), cols = points.shape(1);
  py::array out(QueryRowDtype(), std::vector<py::ssize_t>{n});
  const double* p = points.data();
  QueryRow* rows = static_cast<QueryRow*>(out.mutable_data());
  {
    py::gil_scoped_release release;
    RequireFinite(p, n, cols, "points");
    if (as_exported && cols == 3) {
      throw py::value_error("points: as_exported answers (x, y) points (the exported grid is 2D), got (N, 3)");
    }
    const TraversabilityMap& map = handle.map;
    std::unique_ptr<ExportedSurface> exported;
    if (as_exported) {
      Eigen::AlignedBox2d box;
      for (py::ssize_t i = 0; i < n; ++i) box.extend(Eigen::Vector2d(p[i * 2], p[i * 2 + 1]));
      exported = ExportedOver(map, box, steps);
    }
    for (py::ssize_t i = 0; i < n; ++i) {
      const double* q = p + i * cols;
      const CellInfo cell = AtConfidenceBar(cols == 3   ? map.CellAt({q[0], q[1], q[2]})
                                            : exported ? (*exported)(q[0], q[1])
                                                       : map.TopSurfaceAt(q[0], q[1]),
                                            min_confidence);
      // An unobserved cell answers at the point asked, z NaN for (x, y) (`ssta query`).
      const Eigen::Vector3d at = cell.observed ? cell.center : Eigen::Vector3d(q[0], q[1], cols == 3 ? q[2] : kNaN);
      rows[i] = MakeQueryRow(cell, at);
    }
  }
  return out;
}

py::array Footprints(const MapHandle& handle, const py::object& poses_arg, double length_m, double width_m,
                     bool as_exported, int fill_holes, double local_ground_radius_m, double min_confidence) {
  const GridExportOptions steps = ExportSteps(fill_holes, local_ground_radius_m);
  CheckMinConfidence(min_confidence);
  NonNegativeArg(length_m, "length_m");
  NonNegativeArg(width_m, "width_m");
  const auto poses = MatrixArg(poses_arg, "poses", 3, 3);
  const py::ssize_t n = poses.shape(0);
  py::array_t<FootprintRow> out(n);
  const double* p = poses.data();
  FootprintRow* rows = out.mutable_data();
  {
    py::gil_scoped_release release;
    RequireFinite(p, n, 3, "poses");
    const TraversabilityMap& map = handle.map;
    // The rectangle lies within r of its centre: the exported surface covers every one.
    const double r = 0.5 * std::hypot(length_m, width_m);
    std::unique_ptr<ExportedSurface> exported;
    if (as_exported) {
      Eigen::AlignedBox2d box;
      for (py::ssize_t i = 0; i < n; ++i) {
        box.extend(Eigen::Vector2d(p[i * 3] - r, p[i * 3 + 1] - r));
        box.extend(Eigen::Vector2d(p[i * 3] + r, p[i * 3 + 1] + r));
      }
      exported = ExportedOver(map, box, steps);
    }
    const TraversabilityMap::SurfaceSource surface = WithConfidenceBarOver(map, exported.get(), min_confidence);
    for (py::ssize_t i = 0; i < n; ++i) {
      const FootprintQuery query{p[i * 3], p[i * 3 + 1], p[i * 3 + 2], length_m, width_m};
      const FootprintResult f = NamingTheArgument("poses[" + std::to_string(i) + "]", "footprint query: ",
                                                  [&] { return map.QueryFootprint(query, surface); });
      rows[i] = FootprintRow{static_cast<std::uint8_t>(f.worst), f.mean_cost, f.max_cost, f.fraction_observed,
                             f.cells, f.observed_cells, f.pitch_deg, f.roll_deg, static_cast<std::uint8_t>(f.attitude),
                             f.attitude_heights, f.drivable_confidence,
                             f.attitude == TravClass::kTraversable || f.attitude == TravClass::kSemiTraversable};
    }
  }
  return std::move(out);
}

py::dict Path(const MapHandle& handle, const py::object& vertices_arg, double width_m, bool as_exported,
              int fill_holes, double local_ground_radius_m, double min_confidence) {
  const GridExportOptions steps = ExportSteps(fill_holes, local_ground_radius_m);
  CheckMinConfidence(min_confidence);
  NonNegativeArg(width_m, "width_m");
  const auto vertices = MatrixArg(vertices_arg, "vertices", 2, 2);
  const py::ssize_t n = vertices.shape(0);
  const double* v = vertices.data();
  PathResult result;
  {
    py::gil_scoped_release release;
    RequireFinite(v, n, 2, "vertices");
    std::vector<Eigen::Vector2d> polyline;
    Eigen::AlignedBox2d box;
    for (py::ssize_t i = 0; i < n; ++i) {
      polyline.emplace_back(v[i * 2], v[i * 2 + 1]);
      box.extend(polyline.back());
    }
    const TraversabilityMap& map = handle.map;
    result = NamingTheArgument("vertices", "path query: ", [&] {
      const Eigen::Vector2d half_width = Eigen::Vector2d::Constant(0.5 * width_m);
      const std::unique_ptr<ExportedSurface> exported =
          as_exported ? std::make_unique<ExportedSurface>(
                            map, Eigen::AlignedBox2d(box.min() - half_width, box.max() + half_width), steps)
                      : nullptr;
      return map.QueryPath(polyline, width_m, WithConfidenceBarOver(map, exported.get(), min_confidence));
    });
  }
  py::array_t<PathRow> samples(static_cast<py::ssize_t>(result.samples.size()));
  PathRow* rows = samples.mutable_data();
  for (std::size_t i = 0; i < result.samples.size(); ++i) {
    const PathSample& s = result.samples[i];
    rows[i] = PathRow{s.distance_m, s.point.x(), s.point.y(), static_cast<std::uint8_t>(s.cls), s.cost,
                      s.fraction_observed, s.drivable_confidence};
  }
  py::dict out;
  out["samples"] = samples;
  out["worst"] = static_cast<int>(result.worst);
  out["mean_cost"] = result.mean_cost;
  out["fraction_observed"] = result.fraction_observed;
  out["length_m"] = result.length_m;
  out["blocked"] = result.blocked;
  out["first_non_traversable"] =
      result.blocked ? py::object(py::make_tuple(result.first_non_traversable.x(), result.first_non_traversable.y()))
                     : py::object(py::none());
  out["first_non_traversable_distance_m"] = result.first_non_traversable_distance_m;
  return out;
}

template <class T>
py::array_t<T> ImageArray(const Image<T>& image) {
  py::array_t<T> a({static_cast<py::ssize_t>(image.height()), static_cast<py::ssize_t>(image.width())});
  if (image.size() > 0) std::memcpy(a.mutable_data(), image.data(), image.size() * sizeof(T));
  return a;
}

py::dict Project(const MapHandle& handle, const std::optional<std::vector<double>>& region_arg,
                 std::optional<double> resolution_arg, bool as_exported, int fill_holes,
                 double local_ground_radius_m, int headings, const std::vector<double>& heading_footprint,
                 double min_confidence) {
  const TraversabilityMap& map = handle.map;
  const GridExportOptions steps = ExportSteps(fill_holes, local_ground_radius_m);
  CheckMinConfidence(min_confidence);
  Eigen::AlignedBox2d region;
  if (region_arg) {
    const std::vector<double>& r = *region_arg;
    if (r.size() != 4 || !std::isfinite(r[0]) || !std::isfinite(r[1]) || !std::isfinite(r[2]) ||
        !std::isfinite(r[3]) || !(r[0] < r[2] && r[1] < r[3])) {
      throw py::value_error("region: expected four finite numbers (x_min, y_min, x_max, y_max) with min < max");
    }
    region = Eigen::AlignedBox2d(Eigen::Vector2d(r[0], r[1]), Eigen::Vector2d(r[2], r[3]));
  } else {
    const Eigen::AlignedBox3d bounds = map.SurfaceBounds();
    if (bounds.isEmpty()) throw py::value_error("region: the map has no surface; give a region");
    region = Eigen::AlignedBox2d(bounds.min().head<2>(), bounds.max().head<2>());
  }
  const double resolution_m = resolution_arg.value_or(map.options().resolution_m);
  if (!(std::isfinite(resolution_m) && resolution_m > 0.0)) {
    throw py::value_error("resolution_m: must be a finite number > 0");
  }
  HeadingCostOptions heading_options;
  heading_options.headings = headings;
  if (heading_footprint.size() != 2) throw py::value_error("heading_footprint: expected (length_m, width_m)");
  heading_options.footprint_length_m = heading_footprint[0];
  heading_options.footprint_width_m = heading_footprint[1];
  std::string error;
  if (!heading_options.IsValid(&error)) {
    const bool footprint = error.rfind("headings", 0) != 0;
    throw py::value_error((footprint ? "heading_footprint: " + error : error));
  }
  GridProjection grid;
  std::vector<ImageF> heading_costs;
  {
    py::gil_scoped_release release;
    if (as_exported) {
      GridExportOptions options = steps;
      options.region = region;
      options.resolution_m = resolution_m;
      grid = ProjectAsExported(map, options);
    } else {
      grid = map.Project(region, resolution_m);
    }
    // Last, as the export applies it (GridExportOptions::min_confidence).
    if (min_confidence > 0.0) ApplyConfidenceBar(&grid, min_confidence);
    if (headings > 0) heading_costs = HeadingCosts(grid, map.metadata().vehicle, heading_options);
  }
  py::dict out;
  out["class"] = ImageArray(grid.classes);
  out["cost"] = ImageArray(grid.cost);
  out["height_m"] = ImageArray(grid.height_m);
  out["slope_deg"] = ImageArray(grid.slope_deg);
  out["step_m"] = ImageArray(grid.step_m);
  out["surface_z_m"] = ImageArray(grid.surface_z_m);
  if (headings > 0) {
    const py::ssize_t h = grid.height(), w = grid.width();
    py::array_t<float> stack({h, w, static_cast<py::ssize_t>(headings)});
    float* data = stack.mutable_data();
    for (py::ssize_t i = 0; i < h * w; ++i) {
      for (int k = 0; k < headings; ++k) data[i * headings + k] = heading_costs[static_cast<std::size_t>(k)][static_cast<std::size_t>(i)];
    }
    out["cost_heading"] = stack;
    py::list degrees;
    for (int k = 0; k < headings; ++k) degrees.append(360.0 * k / headings);
    out["headings_deg"] = degrees;
  }
  out["origin"] = py::make_tuple(grid.origin.x(), grid.origin.y());
  out["resolution_m"] = grid.resolution_m;
  out["extent"] = py::make_tuple(grid.origin.x(), grid.origin.x() + grid.width() * grid.resolution_m,
                                 grid.origin.y(), grid.origin.y() + grid.height() * grid.resolution_m);
  return out;
}

// Map.diff: what changed from `a` to `b` (DiffMaps), written to `out` when given.
py::dict Diff(const MapHandle& a, const MapHandle& b, const std::optional<py::object>& out_arg, double min_confidence,
              double slope_noise_deg, double step_noise_m, int boundary_shift_columns) {
  MapDiffOptions options;
  options.boundary_shift_columns = boundary_shift_columns;
  options.min_confidence = min_confidence;
  options.slope_noise_deg = slope_noise_deg;
  options.step_noise_m = step_noise_m;
  std::string error;
  if (!options.IsValid(&error)) throw py::value_error(error);
  const std::string out = out_arg ? PathArg(*out_arg, "out") : std::string();
#if SSTA_PYTHON_MAP_ONLY
  if (!out.empty()) {
    throw py::value_error("out: writing the diff's picture needs the full ssta build (this module was built with "
                          "SSTA_MAP_ONLY); compute the diff without out, or build without SSTA_MAP_ONLY");
  }
#endif
  MapDiff diff;
  {
    py::gil_scoped_release release;
    diff = DiffMaps(a.map, a.path, b.map, b.path, options);
#if !SSTA_PYTHON_MAP_ONLY
    if (!out.empty()) WriteMapDiff(diff, out, "Changes from " + a.path + " to " + b.path);
#endif
  }
  py::dict result;
  result["change"] = ImageArray(diff.change);
  result["class_a"] = ImageArray(diff.a.classes);
  result["class_b"] = ImageArray(diff.b.classes);
  result["confidence_a"] = ImageArray(diff.a.confidence);
  result["confidence_b"] = ImageArray(diff.b.confidence);
  py::dict counts;
  for (int id = 1; id < kCellChangeCount; ++id) {
    counts[CellChangeName(static_cast<CellChange>(id))] = diff.summary.counts[id];
  }
  result["counts"] = counts;
  result["origin"] = py::make_tuple(diff.b.origin.x(), diff.b.origin.y());
  result["resolution_m"] = diff.b.resolution_m;
  result["extent"] = py::make_tuple(diff.b.origin.x(), diff.b.origin.x() + diff.b.width() * diff.b.resolution_m,
                                    diff.b.origin.y(), diff.b.origin.y() + diff.b.height() * diff.b.resolution_m);
  return result;
}

// Every field of an Options struct under its YAML key.
template <class O>
py::dict FieldsDict(const O& options) {
  py::dict out;
  for (const OptionField<O>& f : O::Fields()) {
    const OptionValue value = f.get(options);
    if (const double* d = std::get_if<double>(&value)) {
      out[f.key.c_str()] = f.kind == OptionKind::kInteger ? py::object(py::int_(static_cast<long long>(*d)))
                                                          : py::object(py::float_(*d));
    } else if (const bool* b = std::get_if<bool>(&value)) {
      out[f.key.c_str()] = *b;
    } else if (const std::string* s = std::get_if<std::string>(&value)) {
      out[f.key.c_str()] = *s;
    } else {
      const Eigen::Vector3d& v = std::get<Eigen::Vector3d>(value);
      out[f.key.c_str()] = py::make_tuple(v.x(), v.y(), v.z());
    }
  }
  return out;
}

py::dict Metadata(const MapHandle& handle) {
  const TraversabilityMap& map = handle.map;
  const MapMetadata& meta = map.metadata();
  py::dict out;
  out["file"] = handle.path;
  out["resolution_m"] = map.options().resolution_m;
  out["vehicle"] = FieldsDict(meta.vehicle);
  out["fusion"] = FieldsDict(map.options());
  out["sequences"] = meta.sequences;
  out["calibration_summary"] = meta.calibration_summary;
  out["notes"] = meta.notes;
  if (meta.refined_mount) {
    py::dict mount;
    mount["configured"] = Matrix4(meta.refined_mount->configured);
    mount["refined"] = Matrix4(meta.refined_mount->refined);
    out["refined_mount"] = mount;
  } else {
    out["refined_mount"] = py::none();
  }
  out["software_version"] = map.software_version();
  out["frames_inserted"] = map.frames_inserted();
  out["last_timestamp_ns"] = map.last_timestamp_ns();
  const std::vector<Eigen::Vector3d>& sensor_path = map.sensor_path();
  py::array_t<double> path({static_cast<py::ssize_t>(sensor_path.size()), py::ssize_t{3}});
  for (std::size_t i = 0; i < sensor_path.size(); ++i) {
    for (int k = 0; k < 3; ++k) path.mutable_at(i, k) = sensor_path[i][k];
  }
  out["sensor_path"] = path;
  py::list recordings;
  for (const RecordingFingerprint& r : meta.recordings) {
    py::dict entry;
    entry["sequence"] = r.sequence;
    entry["frames"] = r.frames();
    entry["fingerprint"] = r.Digest();
    recordings.append(entry);
  }
  out["recordings"] = recordings;
  return out;
}

// The docstrings of ssta.Map and its methods. kAsExportedArgsDoc: the keyword arguments every
// query takes for as_exported, with their help, which ExportedDoc puts where a docstring says
// {as_exported}.
constexpr const char* kAsExportedArgsDoc =
    "    as_exported: answer as `ssta export --format grid` shows the cells (its local-ground and\n"
    "        hole-filling steps: a filled hole has its filled class, cost NaN), as `ssta query\n"
    "        --as-exported`. False: the map as observed.\n"
    "    fill_holes: with as_exported, an unknown cell with at least this many of its 8 neighbours\n"
    "        classified takes their most frequent class (0: off; 0..8), as `--fill-holes`.\n"
    "    local_ground_radius_m: with as_exported, the local-ground step judgement's radius [m]\n"
    "        (0: off), as `--local-ground`.\n";

constexpr const char* kQueryDoc = R"doc(
The map at N points, as `ssta query --points` answers them.

Args:
    points: N x 2 (x, y) or N x 3 (x, y, z) real numbers in W [m], no NaN. (x, y): the top
        observed surface of that map column (the ground the robot drives on); (x, y, z): the
        voxel holding that point.
{as_exported}
    min_confidence: drive only on answers this sure: a traversable or semi-traversable cell
        whose confidence is below it answers undecided (class 4, cost NaN), as `ssta query
        --min-confidence` (0: every answer as it is; 0..1).
Returns:
    A structured array of N rows with the fields of `ssta query`'s CSV, then two more:
    x, y, z (float64): the voxel centre [m]; for an unobserved cell the point asked (z NaN
        for an (x, y) point);
    class (uint8): the class id; 0 where unobserved;
    cost (float64): planning cost in [0, 1]: 0 traversable, 0.25..0.75 semi-traversable by
        its slope and step (0.5 decided by the frames), 1 non-traversable; NaN for classes 0 and 4;
    probability (float64): the class's probability from the frames' evidence;
    slope_deg (float64): the slope that decided the class [deg]: the fused surface's where
        decided_by is "surface" or "both"; NaN where the frames' votes decided alone
        ("frames") and where no class 1..3 was decided from the map's evidence;
    step_m (float64): the step that decided the class [m], likewise: the fused surface's
        largest height jump within the step radius; NaN where the frames decided;
    observations (uint32): frames that gave the cell a class;
    confidence (float64): posterior probability of the class from the frames and the fused
        surface around the column, in [0, 1];
    decided_by (str): which evidence decided the class: "frames" (the frames' class votes;
        always for an (x, y, z) voxel), "surface" (the fused surface around the column),
        "both", "export" (as_exported: the export's step or hole filling); "" where none;
    frame_mean_slope_deg (float64): the mean slope of the frames that gave the cell a class
        [deg]; NaN where none did;
    frame_mean_step_m (float64): their mean signed step [m];
    height_m (float64): the fused surface height (world z) [m];
    observed (bool): the map has a surface there.

Raises:
    ValueError naming `points` for another shape, a non-numeric dtype or NaN / infinity;
    ValueError for N x 3 points with as_exported (the exported grid is 2D), and naming
    `min_confidence` outside [0, 1].
)doc";

constexpr const char* kFootprintsDoc = R"doc(
The ground under N robot footprints, as `ssta query --footprint` answers each.

Args:
    poses: N x 3 (x, y, yaw): the rectangle's centre in W [m] and its heading [rad, from +x
        towards +y]. Note: yaw in radians (the command line takes degrees).
    length_m: the rectangle's side along the heading [m], >= 0.
    width_m: its side across the heading [m], >= 0. Every map column the rectangle touches
        counts: an obstacle under any part of it is under the robot.
{as_exported}
    min_confidence: drive only on answers this sure: a traversable or semi-traversable cell
        whose confidence is below it answers undecided (class 4, cost NaN), as `ssta query
        --min-confidence` (0: every answer as it is; 0..1).
Returns:
    A structured array of N rows: worst (uint8, the worst class under it: 3, then 4 (undecided),
    then 2, then 1; 0 when no cell is observed),
    mean_cost, max_cost (float64; NaN when no cell has a cost), fraction_observed (float64,
    observed columns / columns), cells and observed_cells (int32); the vehicle's attitude on
    the plane fitted to the fused heights under it: pitch_deg (float64, nose up positive),
    roll_deg (float64, left side up positive; both NaN with fewer than 3 heights),
    attitude (uint8: 1 below 0.8 of the map's vehicle max_pitch_deg / max_descent_deg /
    max_roll_deg, 2 up to them, 3 beyond, 0 without a plane), attitude_heights (int32, the
    heights fitted), drivable_confidence (float64: the lowest confidence of its traversable and
    semi-traversable cells; a planner that needs more treats the footprint as undecided; NaN
    without such a cell) and within_limits (bool: attitude 1 or 2).

Raises:
    ValueError naming `poses`, `length_m`, `width_m` or `min_confidence`; ssta.Error naming
    `poses[i]` for a footprint beyond the map's addressable area or over more than 10^7 columns.
)doc";

constexpr const char* kPathDoc = R"doc(
Checks a polyline with a width, as `ssta query --path FILE --width W`.

Samples every resolution/2 along the polyline; at each sample the top surfaces across the
width (perpendicular to the segment, one every resolution) give its worst class and max cost;
turns check their outside too.

Args:
    vertices: N x 2 (x, y) in W [m], N >= 1, no NaN.
    width_m: corridor width [m], >= 0.
{as_exported}
    min_confidence: drive only on answers this sure: a traversable or semi-traversable cell
        whose confidence is below it answers undecided (class 4, cost NaN), as `ssta query
        --min-confidence` (0: every answer as it is; 0..1).
Returns:
    A dict: samples (structured array: distance_m, x, y, class, cost, fraction_observed,
    drivable_confidence: the lowest confidence of the drivable cells across the width),
    worst (int), mean_cost, fraction_observed, length_m (float), blocked (bool),
    first_non_traversable ((x, y) or None) and first_non_traversable_distance_m (NaN when not
    blocked).

Raises:
    ValueError naming `vertices`, `width_m` or `min_confidence`; ssta.Error naming `vertices` for a path over more
    than 10^7 cells or 10^6 samples.
)doc";

constexpr const char* kProjectDoc = R"doc(
The top surface over a region as 2D arrays, for a planner or matplotlib.

Args:
    region: (x_min, y_min, x_max, y_max) in W [m]; None: the occupied voxels' bounds.
    resolution_m: pixel edge [m]; None: the map's. Finer than the map: each pixel's centre;
        coarser: the worst class among the map columns the pixel holds.
{as_exported}
        With as_exported the region is widened outwards to multiples of the resolution,
        exactly as `ssta export --format grid` (whose PNGs hold the same classes).
    headings: N > 0 adds cost_heading, the cost per heading as `ssta export --headings N`:
        heading k faces 360 k / N deg from +x towards +y; the class cost, raised where the
        vehicle's pitch or roll on the ground under the footprint nears (0.8 of) or passes the
        map's vehicle limits (max_pitch_deg, max_descent_deg, max_roll_deg; 1 beyond).
    heading_footprint: (length_m, width_m) of that footprint, centred at each pixel.
    min_confidence: a planner's bar, applied last: a traversable or semi-traversable pixel
        whose confidence is below it is class 4 with cost NaN, as `ssta export
        --min-confidence` writes it (0: off; 0..1).

Returns:
    A dict of H x W arrays, row 0 the largest y, column 0 the smallest x (an image; pass
    `extent` and origin='upper' to matplotlib's imshow): class (uint8), cost, height_m,
    slope_deg, step_m (float32: the slope and step that decided the class, as query's; NaN
    where unknown), surface_z_m (float32, the fused surface height); with headings, cost_heading
    (H x W x N float32) and headings_deg (N floats); and origin ((x, y) of the lower-left
    corner [m]), resolution_m, extent ((x_min, x_max, y_min, y_max) [m]).

Raises:
    ValueError naming `region` or `resolution_m`; ssta.Error for more than 2^26 pixels.
)doc";

constexpr const char* kMapDoc = R"doc(
A persistent 3D traversability map (an `.ot` file written by `ssta build-map` or
`ssta.build_map`), read-only. World frame W: right-handed, z up, metres; yaw in radians from +x
towards +y. Classes: 0 unknown, 1 traversable, 2 semi-traversable, 3 non-traversable,
4 undecided. Unknown numbers are NaN.

Thread safety: every query releases the GIL and only reads the map, so any number of Python
threads may query one Map at the same time.
)doc";

constexpr const char* kOpenDoc = R"doc(
Reads the map file at `path` (str or os.PathLike).

Raises FileNotFoundError naming the file when it does not exist, and ssta.Error (a ValueError)
naming it when it is truncated, corrupt, not an SSTA map or of a newer format: the messages of
`ssta query`.
)doc";

constexpr const char* kMetadataDoc = R"doc(
What the map knows about how it was made, as a dict: `file`, `resolution_m` [m], `vehicle`
(the vehicle section whose limits gave the classes, YAML keys and units as in
config/default.yaml), `fusion` (the map's fusion options), `sequences` (names fused, in order),
`calibration_summary`, `notes` (what a reader must know about the evidence: a truncated bag read
anyway), `refined_mount` (None, or {'configured', 'refined'}: cam0's body_T_camera
as 4x4 arrays), `software_version` (the ssta that saved it), `frames_inserted`,
`last_timestamp_ns`, `sensor_path` (K x 3 float64, the sensor's origins in W [m]) and
`recordings` (the fingerprints of the recordings fused, each {'sequence', 'frames',
'fingerprint'}; maps/README.md).
)doc";

constexpr const char* kDiffDoc = R"doc(
What changed from this map (the earlier drive) to `other`, as `ssta diff-maps` finds it: each
map column's class in both maps over the union of their surfaces, at their resolution.

Args:
    other: a Map of the same site (same resolution, world frame and vehicle).
    out: a folder (str or os.PathLike) to write diff.csv and diff.png into; None: none.
        Needs the full build: a map-only module (ssta.MAP_ONLY) raises ValueError.
    min_confidence, slope_noise_deg, step_noise_m, boundary_shift_columns: as
        `--min-confidence`, `--slope-noise-deg`, `--step-noise-m`, `--boundary-shift`.

Returns:
    A dict of H x W arrays, row 0 the largest y: change (uint8: 0 no class in either,
    1 unchanged, 2 new_obstacle, 3 cleared, 4 harder, 5 easier, 6 newly_seen,
    7 no_longer_seen, 8 uncertain), class_a, class_b (uint8), confidence_a, confidence_b
    (float32, NaN without a class); counts ({change name: columns}); origin, resolution_m,
    extent as project's.

Raises:
    ssta.Error naming both files and both values when the maps differ in resolution, world
    frame or vehicle; ValueError for options out of range.
)doc";

// `doc` with kAsExportedArgsDoc in place of its "{as_exported}".
std::string ExportedDoc(const char* doc) {
  std::string text = doc;
  const std::string mark = "{as_exported}";
  text.replace(text.find(mark), mark.size(), kAsExportedArgsDoc);
  return text;
}

}  // namespace

void BindMap(py::module_& m) {
  PYBIND11_NUMPY_DTYPE_EX(FootprintRow, worst, "worst", mean_cost, "mean_cost", max_cost, "max_cost",
                          fraction_observed, "fraction_observed", cells, "cells", observed_cells, "observed_cells",
                          pitch_deg, "pitch_deg", roll_deg, "roll_deg", attitude, "attitude", attitude_heights,
                          "attitude_heights", drivable_confidence, "drivable_confidence", within_limits,
                          "within_limits");
  PYBIND11_NUMPY_DTYPE_EX(PathRow, distance_m, "distance_m", x, "x", y, "y", cls, "class", cost, "cost",
                          fraction_observed, "fraction_observed", drivable_confidence, "drivable_confidence");

  py::class_<MapHandle, std::shared_ptr<MapHandle>>(m, "Map", kMapDoc)
      .def_static(
          "open",
          [](const py::object& path_arg) {
            const std::string path = PathArg(path_arg, "path");
            auto handle = std::make_shared<MapHandle>(MapHandle{
                ReportingMissingFiles({path}, [&] {
                  py::gil_scoped_release release;
                  return TraversabilityMap::Load(path);
                }),
                path});
            return handle;
          },
          py::arg("path"), kOpenDoc)
      .def_property_readonly(
          "resolution_m", [](const MapHandle& h) { return h.map.options().resolution_m; }, "Voxel edge [m].")
      .def_property_readonly("file", [](const MapHandle& h) { return h.path; }, "The file the map was read from.")
      .def_property_readonly(
          "bounds",
          [](const MapHandle& h) -> py::object {
            const Eigen::AlignedBox3d b = h.map.SurfaceBounds();
            if (b.isEmpty()) return py::none();
            return py::make_tuple(b.min().x(), b.min().y(), b.min().z(), b.max().x(), b.max().y(), b.max().z());
          },
          "(x_min, y_min, z_min, x_max, y_max, z_max) of the occupied voxels in W [m]; None when the map\n"
          "has no surface.")
      .def_property_readonly("metadata", &Metadata, kMetadataDoc)
      .def("query", &Query, py::arg("points"), py::kw_only(), py::arg("as_exported") = false,
           py::arg("fill_holes") = 5, py::arg("local_ground_radius_m") = 0.0, py::arg("min_confidence") = 0.0,
           ExportedDoc(kQueryDoc).c_str())
      .def("footprints", &Footprints, py::arg("poses"), py::arg("length_m"), py::arg("width_m"), py::kw_only(),
           py::arg("as_exported") = false, py::arg("fill_holes") = 5, py::arg("local_ground_radius_m") = 0.0,
           py::arg("min_confidence") = 0.0, ExportedDoc(kFootprintsDoc).c_str())
      .def("path", &Path, py::arg("vertices"), py::arg("width_m"), py::kw_only(), py::arg("as_exported") = false,
           py::arg("fill_holes") = 5, py::arg("local_ground_radius_m") = 0.0, py::arg("min_confidence") = 0.0,
           ExportedDoc(kPathDoc).c_str())
      .def("project", &Project, py::arg("region") = py::none(), py::arg("resolution_m") = py::none(),
           py::kw_only(), py::arg("as_exported") = false, py::arg("fill_holes") = 5,
           py::arg("local_ground_radius_m") = 0.0, py::arg("headings") = 0,
           py::arg("heading_footprint") = std::vector<double>{HeadingCostOptions{}.footprint_length_m,
                                                               HeadingCostOptions{}.footprint_width_m},
           py::arg("min_confidence") = 0.0, ExportedDoc(kProjectDoc).c_str())
      .def("diff", &Diff, py::arg("other"), py::kw_only(), py::arg("out") = py::none(),
           py::arg("min_confidence") = MapDiffOptions{}.min_confidence,
           py::arg("slope_noise_deg") = MapDiffOptions{}.slope_noise_deg,
           py::arg("step_noise_m") = MapDiffOptions{}.step_noise_m,
           py::arg("boundary_shift_columns") = MapDiffOptions{}.boundary_shift_columns, kDiffDoc)
      .def("__repr__", [](const MapHandle& h) {
        return "<ssta.Map '" + h.path + "', " + std::to_string(h.map.options().resolution_m) + " m voxels>";
      });
}

}  // namespace ssta::python
