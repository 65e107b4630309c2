// The map's queries: single cells, column tops, footprints, paths, grid projections and the
// occupied voxels as a whole.

#include "ssta/mapping/traversability_map.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "mapping/map_impl.h"
#include "ssta/core/error.h"
#include "ssta/core/units.h"
#include "ssta/mapping/column_explanation.h"
#include "ssta/mapping/surface_judgement.h"
#include "ssta/mapping/vehicle_attitude.h"

namespace ssta {

using internal::KeyCenter;
using internal::NodeOccupied;
using internal::TravNode;
using internal::TravOcTree;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// The index (0: traversable .. 2: non-traversable) of the most probable of three classes, ties
/// to the worse.
int MostProbableClass(const std::array<double, 3>& p) {
  int best = 0;
  for (int k = 1; k < 3; ++k) {
    if (p[k] >= p[best]) best = k;
  }
  return best;
}

/// The highest occupied voxel of column (kx, ky) below `node`, which covers z keys
/// [z_base, z_base + 2^(16 - depth)). Inner occupancy is the max over the children, so a
/// subtree whose root is not occupied holds no occupied voxel and is skipped.
const TravNode* FindTopOccupied(const TravOcTree& tree, const TravNode* node, unsigned depth,
                                octomap::key_type kx, octomap::key_type ky, unsigned z_base,
                                octomap::key_type* kz) {
  const unsigned tree_depth = tree.getTreeDepth();
  if (!NodeOccupied(tree, *node)) return nullptr;
  if (!tree.nodeHasChildren(node)) {
    *kz = static_cast<octomap::key_type>(z_base + (1u << (tree_depth - depth)) - 1u);
    return node;
  }
  const unsigned bit = tree_depth - 1 - depth;
  const unsigned xy = ((kx >> bit) & 1u) | (((ky >> bit) & 1u) << 1);
  for (const unsigned zb : {1u, 0u}) {
    const unsigned pos = xy | (zb << 2);
    if (!tree.nodeChildExists(node, pos)) continue;
    const TravNode* found = FindTopOccupied(tree, tree.getNodeChild(node, pos), depth + 1, kx, ky,
                                            z_base + (zb << bit), kz);
    if (found != nullptr) return found;
  }
  return nullptr;
}

/// The highest occupied voxel of the column of `key` (x and y), its z written into `key`;
/// null when the column holds none.
const TravNode* ColumnTop(const TravOcTree& tree, octomap::OcTreeKey* key) {
  const TravNode* root = tree.getRoot();
  if (root == nullptr) return nullptr;
  octomap::key_type kz = 0;
  const TravNode* node = FindTopOccupied(tree, root, 0, (*key)[0], (*key)[1], 0, &kz);
  if (node != nullptr) (*key)[2] = kz;
  return node;
}

/// The fused surface of the columns whose centres lie within `radius_m` of `key`'s column but
/// not within `skip_within_m` of it (negative: none skipped), pass `keep` (given the column's
/// centre; null: all pass) and hold a fused height.
std::vector<SurfaceSample> SurfaceAround(const TravOcTree& tree, const octomap::OcTreeKey& key, double radius_m,
                                         double skip_within_m = -1.0,
                                         const std::function<bool(const Eigen::Vector2d&)>& keep = nullptr) {
  const double res = tree.getResolution();
  const int reach = static_cast<int>(std::floor(radius_m / res + 1e-9));
  std::vector<SurfaceSample> samples;
  for (int dj = -reach; dj <= reach; ++dj) {
    for (int di = -reach; di <= reach; ++di) {
      const double d2 = (di * di + dj * dj) * res * res;
      if (d2 > radius_m * radius_m + 1e-12) continue;
      if (skip_within_m >= 0.0 && d2 <= skip_within_m * skip_within_m + 1e-12) continue;
      const int kx = key[0] + di, ky = key[1] + dj;
      if (kx < 0 || ky < 0 || kx > 0xFFFF || ky > 0xFFFF) continue;
      octomap::OcTreeKey k(static_cast<octomap::key_type>(kx), static_cast<octomap::key_type>(ky), 0);
      // Before the column is looked up: finding its top is most of a judgement's cost.
      if (keep && !keep(Eigen::Vector2d(KeyCenter(tree, k[0]), KeyCenter(tree, k[1])))) continue;
      const TravNode* node = ColumnTop(tree, &k);
      // Only measured heights with their uncertainty (a map of points without height sigmas
      // has none): a voxel's centre is no surface height.
      if (node == nullptr || node->surface_weight <= 0.0f) continue;
      SurfaceSample s;
      s.xy = Eigen::Vector2d(KeyCenter(tree, k[0]), KeyCenter(tree, k[1]));
      s.height_m = node->surface_z;
      s.sigma_m = std::max(0.002, 1.0 / std::sqrt(static_cast<double>(node->surface_weight)));
      s.xy_sigma_m = node->surface_xy_sigma_m;
      samples.push_back(s);
    }
  }
  return samples;
}

/// Whether every column whose square meets the disc of `radius_m` about `key`'s column centre
/// holds a fused height: only then has the fused surface seen all the ground that the class
/// rule judges a point of the column by (the column's points lie up to half a cell from its
/// centre, so a jump just outside the centres' disc still counts).
bool DiscFullySeen(const TravOcTree& tree, const octomap::OcTreeKey& key, double radius_m) {
  const double res = tree.getResolution();
  const int reach = static_cast<int>(std::ceil(radius_m / res - 0.5 - 1e-9));
  for (int dj = -reach; dj <= reach; ++dj) {
    for (int di = -reach; di <= reach; ++di) {
      const double gx = std::max(0.0, std::abs(di) - 0.5) * res, gy = std::max(0.0, std::abs(dj) - 0.5) * res;
      if (gx * gx + gy * gy > radius_m * radius_m + 1e-12) continue;
      const int kx = key[0] + di, ky = key[1] + dj;
      if (kx < 0 || ky < 0 || kx > 0xFFFF || ky > 0xFFFF) return false;
      octomap::OcTreeKey k(static_cast<octomap::key_type>(kx), static_cast<octomap::key_type>(ky), 0);
      const TravNode* node = ColumnTop(tree, &k);
      if (node == nullptr || node->surface_weight <= 0.0f) return false;
    }
  }
  return true;
}

/// Whether the fused surface about `key`'s column is smeared sideways (`surface`, its verdict
/// over the step radius's disc) and, judged over the region its horizontal sigma widens that
/// disc to along the ray from the nearest point of the sensor's path (JudgeSmearedSurface),
/// finds a jump or slope above max at 2 sigmas or more (P >= 0.977): a hazard there that no
/// noise at its range explains, though stereo cannot place it within the step radius or beyond.
/// Off unless MapOptions::class_smeared_surface_hazards.
/// `disc` holds the columns SurfaceAround found within `disc_radius_m` (JudgeFromSurface's).
bool SmearedHazard(const TraversabilityMap& map, const TravOcTree& tree, const octomap::OcTreeKey& key,
                   const CellInfo& cell, const SurfaceVerdict& surface, const std::vector<SurfaceSample>& disc,
                   double disc_radius_m, ColumnExplanation* why) {
  if (!surface.smeared || !map.options().class_smeared_surface_hazards) return false;
  const VehicleOptions& vehicle = map.metadata().vehicle;
  const Eigen::Vector2d centre = cell.center.head<2>();
  const SurfaceRegion region =
      SmearedRegion(vehicle.step_radius_m, tree.getResolution(), surface.xy_sigma_m,
                    centre - internal::TraversabilityMapAccess::Impl(map).sensor_path.NearestXy(centre));
  // Only the columns JudgeSmearedSurface keeps (the region is narrower across the ray), and
  // those of `disc` without looking them up again.
  std::vector<SurfaceSample> samples =
      SurfaceAround(tree, key, std::max(region.along_m, region.across_m), disc_radius_m,
                    [&](const Eigen::Vector2d& xy) { return region.Contains(xy - centre); });
  samples.insert(samples.end(), disc.begin(), disc.end());
  const SurfaceVerdict wide = JudgeSmearedSurface(centre, samples, tree.getResolution(), region, vehicle);
  if (why != nullptr) {
    why->smeared_surface = wide;
    why->smeared_region = region;
  }
  constexpr double kTwoSigmas = 0.977;  // P(N(0, 1) < 2)
  return wide.determined && wide.probability[2] >= kTwoSigmas;
}

/// A column near a hazard that the smear of its heights does not let stereo place within the
/// step radius or beyond it (SmearedHazard): undecided, as a voxel without evidence is (no
/// judge, no probability, confidence or cost). `frames`: the frames' class probabilities, null
/// without votes.
void MarkSmearedHazard(const std::array<double, 3>* frames, CellInfo* cell, ColumnExplanation* why) {
  cell->cls = TravClass::kUndecided;
  cell->probability = cell->confidence = cell->cost = cell->slope_deg = cell->step_m = kNaN;
  cell->decided_by = ClassJudge::kNone;
  if (why != nullptr) {
    why->rule = JudgeRule::kSmearedHazard;
    if (frames != nullptr) why->frame_probability = *frames;
  }
}

/// The product rule of JudgeFromSurface: the surface's class probabilities `surface`, mixed
/// with `miss` of a uniform share (it may miss what the frames saw), times the frames'.
std::array<double, 3> SurfaceTimesFrames(const std::array<double, 3>& frames, const std::array<double, 3>& surface,
                                         double miss) {
  std::array<double, 3> product{};
  double total = 0.0;
  for (int k = 0; k < 3; ++k) total += (product[k] = frames[k] * ((1.0 - miss) * surface[k] + miss / 3.0));
  for (double& p : product) p /= total;
  return product;
}

/// A column's class from the frames' evidence and the fused surface around it (`cell` holds
/// DescribeCell's answer for the column's top voxel on entry). Each has its blind spot: a frame
/// sees a lip or the ring around a rock that the fused surface lacks the columns to show (the
/// floor below a drop-off is hidden, a rock's top is never seen), and the fused surface shows a
/// jump between columns that no single frame saw both sides of. So:
///  - a surface that finds a slope or a jump (its most probable class is not traversable)
///    makes the column the worse of the two verdicts (WorseOfClasses): either one's hazard counts;
///  - a surface that finds open ground vouches for it only where it sees every column that
///    meets the disc (DiscFullySeen): then its verdict, mixed with class_surface_miss_prob of
///    a uniform one (it may miss a lip beyond its edge or a thin obstacle), is a likelihood
///    multiplied into the frames';
///  - otherwise the frames decide alone;
///  - where the surface's heights are smeared sideways (far ground) and within their smear it
///    finds a hazard that noise does not explain (SmearedHazard), a column the above does not
///    call non-traversable is undecided.
/// An uncertain surface (stereo noise at range) so never turns open ground red by itself.
/// `decided_by` names the judge whose own most probable class the verdict is (both: each's, or
/// neither's after combining). The slope and step are the surface's where it decided or
/// co-decided, and NaN where the frames decided alone: a frame classes its pixels by its own
/// rules, so their mean slope and step (kept as frame_mean_*) mix the votes of every class and
/// did not decide it.
void JudgeFromSurface(const TraversabilityMap& map, const TravOcTree& tree, const octomap::OcTreeKey& key,
                      CellInfo* cell, ColumnExplanation* why = nullptr) {
  const TravNode* node = tree.search(key);
  if (node == nullptr || !NodeOccupied(tree, *node)) return;
  const VehicleOptions& vehicle = map.metadata().vehicle;
  const double disc_radius = SurfaceDiscRadius(vehicle.step_radius_m, tree.getResolution());
  const std::vector<SurfaceSample> samples = SurfaceAround(tree, key, disc_radius);
  const SurfaceVerdict surface = JudgeSurface(cell->center.head<2>(), samples, tree.getResolution(), vehicle);
  const auto& l = node->class_log_odds;
  const bool has_evidence = internal::HasClassEvidence(l, map.options());
  if (why != nullptr) {
    why->surface = surface;
    why->surface_columns = static_cast<int>(samples.size());
    why->disc_fully_seen = DiscFullySeen(tree, key, vehicle.step_radius_m);
  }
  if (!surface.determined && !has_evidence) return;  // undecided: nothing to judge by
  const std::array<double, 3> frames = internal::FrameClassProbabilities(l, map.options().class_prior_traversable_log_odds);
  const std::array<double, 3>& s = surface.probability;
  std::array<double, 3> posterior = frames;
  ClassJudge judge = ClassJudge::kFrames;
  JudgeRule rule = surface.determined ? JudgeRule::kFramesSurfacePartial : JudgeRule::kFramesAlone;
  if (surface.determined && !has_evidence) {
    posterior = s;
    judge = ClassJudge::kSurface;
    rule = JudgeRule::kSurfaceAlone;
  } else if (surface.determined) {
    if (s[1] >= s[0] || s[2] >= s[0]) {
      posterior = WorseOfClasses(frames, s);
      judge = ClassJudge::kBoth;
      rule = JudgeRule::kWorseOfTwo;
    } else if (surface.coverage >= 1.0 && DiscFullySeen(tree, key, vehicle.step_radius_m)) {
      posterior = SurfaceTimesFrames(frames, s, map.options().class_surface_miss_prob);
      judge = ClassJudge::kBoth;
      rule = JudgeRule::kProduct;
    }
  }
  const JudgeRule withheld =
      judge == ClassJudge::kFrames ? internal::WithheldVerdict(l, map.options()) : JudgeRule::kNone;
  if (withheld != JudgeRule::kNone) {
    // The frames decide (so they have evidence), and their votes lean to an obstacle on too
    // little of it for the prior to overrule them, or call one on fewer clear views than
    // class_obstacle_min_evidence_views (what stereo noise at their range can make): the column
    // stays undecided, as DescribeCell (which `cell` comes from) left it.
    if (why != nullptr) {
      why->rule = withheld;
      why->frame_probability = frames;
    }
    return;
  }
  const int best = MostProbableClass(posterior);
  if (best != 2 && SmearedHazard(map, tree, key, *cell, surface, samples, disc_radius, why)) {
    return MarkSmearedHazard(has_evidence ? &frames : nullptr, cell, why);
  }
  if (judge == ClassJudge::kBoth) {
    const bool frames_class = MostProbableClass(frames) == best, surface_class = MostProbableClass(s) == best;
    if (frames_class != surface_class) judge = frames_class ? ClassJudge::kFrames : ClassJudge::kSurface;
  }
  cell->cls = static_cast<TravClass>(best + 1);
  cell->decided_by = judge;
  cell->confidence = posterior[best];
  cell->probability = has_evidence ? frames[static_cast<std::size_t>(best)] : kNaN;
  if (judge == ClassJudge::kFrames) {
    cell->slope_deg = cell->step_m = kNaN;
  } else {
    cell->slope_deg = surface.slope_deg;
    cell->step_m = surface.step_m;
  }
  cell->cost = map.Cost(cell->cls, cell->slope_deg, cell->step_m, cell->confidence);
  if (why != nullptr) {
    why->rule = rule;
    why->posterior = posterior;
    if (has_evidence) why->frame_probability = frames;
  }
}

/// Rank of a class in worst-of answers (footprints, paths, coarse pixels): an undecided surface
/// outranks traversable and semi-traversable ones (the map saw something there it cannot
/// judge) and yields to an obstacle; unknown ranks lowest.
int Severity(TravClass c) {
  switch (c) {
    case TravClass::kTraversable: return 1;
    case TravClass::kSemiTraversable: return 2;
    case TravClass::kUndecided: return 3;
    case TravClass::kNonTraversable: return 4;
    default: return 0;
  }
}

/// A cell the footprint and path queries count: an observed surface, or (from a surface source
/// such as ExportedSurface) an unobserved cell that was given a class, as a filled hole.
bool Known(const CellInfo& cell) {
  const int c = static_cast<int>(cell.cls);
  return cell.observed || (c >= 1 && c <= 3);
}

/// The centres (x, y in W [m]) of the map columns the footprint rectangle of `q` touches: whose
/// squares share more than 1e-9 m of area-width with it (separating axes: the world's x and y,
/// the rectangle's length and width), so an obstacle under any part of the footprint counts.
/// Throws ssta::Error when the rectangle reaches beyond the map's addressable area or spans
/// more than 10^7 columns.
std::vector<Eigen::Vector2d> FootprintColumns(const TravOcTree& tree, const FootprintQuery& q) {
  const double c = std::cos(q.yaw), s = std::sin(q.yaw);
  const double half_l = 0.5 * q.length_m, half_w = 0.5 * q.width_m;
  const double extent_x = std::abs(c) * half_l + std::abs(s) * half_w;
  const double extent_y = std::abs(s) * half_l + std::abs(c) * half_w;

  std::vector<Eigen::Vector2d> columns;
  octomap::OcTreeKey lo, hi;
  if (!tree.CoordToKeyChecked(q.x - extent_x, q.y - extent_y, 0.0, &lo) ||
      !tree.CoordToKeyChecked(q.x + extent_x, q.y + extent_y, 0.0, &hi)) {
    throw Error("footprint query: the rectangle reaches beyond the map's addressable area (+-" +
                std::to_string(static_cast<long>(tree.getResolution() * 32768.0)) + " m)");
  }
  constexpr double kMaxColumns = 1e7;  // ~160 MB of columns, 316 x 316 m at 0.1 m
  if ((static_cast<double>(hi[0]) - lo[0] + 1.0) * (static_cast<double>(hi[1]) - lo[1] + 1.0) > kMaxColumns) {
    throw Error("footprint query: the rectangle spans more than 10^7 map columns");
  }
  const double half_cell = 0.5 * tree.getResolution();
  // Half the square's extent along the rectangle's own axes (a square turned by yaw).
  const double cell_along = half_cell * (std::abs(c) + std::abs(s));
  constexpr double kOverlap = 1e-9;  // a column that only meets the rectangle's edge is not under it
  for (unsigned kx = lo[0]; kx <= hi[0]; ++kx) {
    for (unsigned ky = lo[1]; ky <= hi[1]; ++ky) {
      const double cx = KeyCenter(tree, static_cast<octomap::key_type>(kx));
      const double cy = KeyCenter(tree, static_cast<octomap::key_type>(ky));
      const double dx = cx - q.x, dy = cy - q.y;
      const double along = c * dx + s * dy, across = -s * dx + c * dy;
      const bool apart = std::abs(dx) >= extent_x + half_cell - kOverlap ||
                         std::abs(dy) >= extent_y + half_cell - kOverlap ||
                         std::abs(along) >= half_l + cell_along - kOverlap ||
                         std::abs(across) >= half_w + cell_along - kOverlap;
      if (!apart) columns.emplace_back(cx, cy);
    }
  }
  if (columns.empty()) columns.emplace_back(q.x, q.y);
  return columns;
}

/// A point where a path query reads across the path: its position, its direction of travel
/// (unit) and its distance along the path [m].
struct Station {
  Eigen::Vector2d p;
  Eigen::Vector2d dir;
  double s;
};

/// Throws ssta::Error when `samples` path samples, each reading the cells across `width_m`
/// (one every `resolution_m`, at least one), are too many. Caps: 10^7 cells read (as a
/// footprint's columns), 10^6 samples kept (~260 MB of them).
void CheckPathSize(double samples, double width_m, double resolution_m) {
  constexpr double kMaxCells = 1e7, kMaxSamples = 1e6;
  if (samples * (width_m / resolution_m + 1.0) > kMaxCells) {
    throw Error("path query: the path and its width span more than 10^7 samples");
  }
  if (samples > kMaxSamples) throw Error("path query: the path spans more than 10^6 samples (resolution / 2 apart)");
}

/// Appends the stations of the lateral line turning about `at` from direction `from` by
/// `angle` [rad], `s_at` along the path. The line sweeps a sector of the disc of radius
/// width_m / 2: stations at `at` whose lateral ends lie at most `spacing` apart along the arc
/// (`from` itself included, the end direction not); none when width_m is 0.
void AppendTurn(const Eigen::Vector2d& at, const Eigen::Vector2d& from, double angle, double s_at,
                double width_m, double spacing, std::vector<Station>* stations) {
  if (width_m <= 0.0) return;
  const int n = static_cast<int>(std::ceil(std::abs(angle) * 0.5 * width_m / spacing));
  for (int k = 0; k < n; ++k) {
    const double a = angle * k / n;
    const Eigen::Vector2d dir(std::cos(a) * from.x() - std::sin(a) * from.y(),
                              std::sin(a) * from.x() + std::cos(a) * from.y());
    stations->push_back({at, dir, s_at});
  }
}

/// The stations of a path query along `polyline` (at least one vertex): every `spacing` [m]
/// along each segment, the turn at each vertex between two segments, and the last vertex.
/// `*length_m`: the polyline's length.
std::vector<Station> PathStations(const std::vector<Eigen::Vector2d>& polyline, double width_m,
                                  double spacing, double* length_m) {
  std::vector<Station> stations;
  double s = 0.0;
  Eigen::Vector2d last_dir(1.0, 0.0);
  bool moved = false;
  for (std::size_t i = 0; i + 1 < polyline.size(); ++i) {
    const Eigen::Vector2d a = polyline[i], b = polyline[i + 1];
    const double len = (b - a).norm();
    if (len <= 0.0) continue;
    const Eigen::Vector2d dir = (b - a) / len;
    // At a vertex the vehicle turns: the outside of the turn is swept too.
    if (moved) {
      AppendTurn(a, last_dir, std::atan2(last_dir.x() * dir.y() - last_dir.y() * dir.x(), last_dir.dot(dir)), s,
                 width_m, spacing, &stations);
    }
    last_dir = dir;
    moved = true;
    const int n = std::max(1, static_cast<int>(std::ceil(len / spacing)));
    for (int k = 0; k < n; ++k) {
      const double t = static_cast<double>(k) / n;
      stations.push_back({a + t * (b - a), last_dir, s + t * len});
    }
    s += len;
  }
  if (!moved) {
    // One point (or only repeated ones): no heading, so any: the disc of the half width.
    AppendTurn(polyline.back(), last_dir, kPi, s, width_m, spacing, &stations);
  }
  stations.push_back({polyline.back(), last_dir, s});
  *length_m = s;
  return stations;
}

/// The path sample at `station`: the worst class and the max cost among the `lateral` cells
/// across `width_m` (perpendicular to the direction of travel) that `read(x, y)` gives.
template <typename Read>
PathSample SampleAcross(const Station& station, double width_m, int lateral, const Read& read) {
  PathSample sample;
  sample.point = station.p;
  sample.distance_m = station.s;
  const Eigen::Vector2d normal(-station.dir.y(), station.dir.x());
  int observed = 0;
  bool have_cell = false;
  for (int j = 0; j < lateral; ++j) {
    const double offset = lateral == 1 ? 0.0 : -0.5 * width_m + j * width_m / (lateral - 1);
    const Eigen::Vector2d q = station.p + offset * normal;
    const CellInfo cell = read(q.x(), q.y());
    if (j == lateral / 2 && !have_cell) sample.cell = cell;
    if (!Known(cell)) continue;
    ++observed;
    if (Severity(cell.cls) > Severity(sample.cls)) {
      sample.cls = cell.cls;
      sample.cell = cell;
      have_cell = true;
    }
    if (std::isfinite(cell.cost)) {
      sample.cost = std::isnan(sample.cost) ? cell.cost : std::max(sample.cost, cell.cost);
    }
    if (IsDrivable(cell.cls)) {
      sample.drivable_confidence = std::fmin(sample.drivable_confidence, cell.confidence);  // NaN: no say
    }
  }
  sample.fraction_observed = static_cast<double>(observed) / lateral;
  return sample;
}

}  // namespace

CellInfo TraversabilityMap::CellAt(const Eigen::Vector3d& p_world) const {
  const TravOcTree& tree = *impl_->tree;
  octomap::OcTreeKey key;
  if (!p_world.allFinite() || !tree.CoordToKeyChecked(p_world.x(), p_world.y(), p_world.z(), &key)) {
    CellInfo cell;
    cell.center = p_world;
    return cell;
  }
  return internal::DescribeCell(*this, tree, tree.search(key), key);
}

CellInfo TraversabilityMap::TopSurfaceAt(double x, double y) const {
  const TravOcTree& tree = *impl_->tree;
  octomap::OcTreeKey key;
  CellInfo unobserved;
  if (!std::isfinite(x) || !std::isfinite(y) || !tree.CoordToKeyChecked(x, y, 0.0, &key)) {
    unobserved.center = {x, y, kNaN};
    return unobserved;
  }
  unobserved.center = {KeyCenter(tree, key[0]), KeyCenter(tree, key[1]), kNaN};
  const TravNode* node = ColumnTop(tree, &key);
  if (node == nullptr) return unobserved;
  CellInfo cell = internal::DescribeCell(*this, tree, node, key);
  JudgeFromSurface(*this, tree, key, &cell);
  return cell;
}

const char* JudgeRuleName(JudgeRule rule) {
  switch (rule) {
    case JudgeRule::kSurfaceAlone: return "surface alone";
    case JudgeRule::kFramesAlone: return "frames alone";
    case JudgeRule::kSmearedHazard: return "smeared hazard";
    case JudgeRule::kFramesSurfacePartial: return "frames (surface partial)";
    case JudgeRule::kWorseOfTwo: return "worse of two";
    case JudgeRule::kProduct: return "product";
    case JudgeRule::kPriorWithheld: return "prior withheld";
    case JudgeRule::kObstacleWithheld: return "obstacle withheld";
    default: return "none";
  }
}

ColumnExplanation TraversabilityMap::ExplainColumn(double x, double y) const {
  ColumnExplanation why;
  why.cell = TopSurfaceAt(x, y);
  if (!why.cell.observed) return why;
  const TravOcTree& tree = *impl_->tree;
  octomap::OcTreeKey key;
  if (!tree.CoordToKeyChecked(x, y, 0.0, &key)) return why;
  const TravNode* node = ColumnTop(tree, &key);  // the voxel TopSurfaceAt described
  if (node == nullptr) return why;
  for (int k = 0; k < 3; ++k) why.frame_log_odds[static_cast<std::size_t>(k)] = node->class_log_odds[static_cast<std::size_t>(k)];
  why.evidence_views = internal::ClassEvidenceViews(node->class_log_odds, options());
  why.occupancy_log_odds = node->getLogOdds();
  why.occupancy = node->getOccupancy();
  why.occupied_threshold = tree.getOccupancyThres();
  CellInfo judged = internal::DescribeCell(*this, tree, node, key);
  JudgeFromSurface(*this, tree, key, &judged, &why);
  return why;
}

FootprintResult TraversabilityMap::QueryFootprint(const FootprintQuery& q, const SurfaceSource& surface) const {
  if (!(std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.yaw) && q.length_m >= 0.0 &&
        q.width_m >= 0.0 && std::isfinite(q.length_m) && std::isfinite(q.width_m))) {
    throw Error("footprint query: x, y, yaw must be finite and length_m, width_m >= 0");
  }
  const std::vector<Eigen::Vector2d> columns = FootprintColumns(*impl_->tree, q);

  FootprintResult result;
  double cost_sum = 0.0;
  int cost_count = 0;
  std::vector<Eigen::Vector3d> ground;  // the fused heights under the footprint
  const Eigen::Vector2d centre(q.x, q.y);
  double worst_distance2 = std::numeric_limits<double>::infinity();  // squared, to the centre
  for (const Eigen::Vector2d& col : columns) {
    const CellInfo cell = surface ? surface(col.x(), col.y()) : TopSurfaceAt(col.x(), col.y());
    if (cell.observed && std::isfinite(cell.surface_z_m)) ground.emplace_back(col.x(), col.y(), cell.surface_z_m);
    ++result.cells;
    if (!Known(cell)) continue;
    ++result.observed_cells;
    const int severity = Severity(cell.cls), worst = Severity(result.worst);
    if (severity >= worst) {
      const double distance2 = (col - centre).squaredNorm();
      if (severity > worst || distance2 < worst_distance2) {
        result.worst = cell.cls;
        result.worst_x_m = col.x();
        result.worst_y_m = col.y();
        worst_distance2 = distance2;
      }
    }
    if (IsDrivable(cell.cls)) {
      result.drivable_confidence = std::fmin(result.drivable_confidence, cell.confidence);  // NaN: no say
    }
    if (std::isfinite(cell.cost)) {
      cost_sum += cell.cost;
      ++cost_count;
      result.max_cost = std::isnan(result.max_cost) ? cell.cost : std::max(result.max_cost, cell.cost);
    }
  }
  if (cost_count > 0) result.mean_cost = cost_sum / cost_count;
  result.fraction_observed = static_cast<double>(result.observed_cells) / result.cells;
  const VehicleAttitude attitude = AttitudeOnGround(ground, q.yaw, impl_->metadata.vehicle);
  result.pitch_deg = attitude.pitch_deg;
  result.roll_deg = attitude.roll_deg;
  result.attitude = attitude.verdict;
  result.attitude_heights = attitude.heights;
  return result;
}

PathResult TraversabilityMap::QueryPath(const std::vector<Eigen::Vector2d>& polyline_world, double width_m,
                                        const SurfaceSource& surface) const {
  if (polyline_world.empty()) throw Error("path query: the polyline has no vertices");
  if (!(width_m >= 0.0 && std::isfinite(width_m))) throw Error("path query: width_m must be >= 0");
  for (const auto& v : polyline_world) {
    if (!v.allFinite()) throw Error("path query: polyline vertices must be finite");
  }
  const double res = impl_->options.resolution_m;
  const double spacing = 0.5 * res;
  double total_length = 0.0;
  for (std::size_t i = 0; i + 1 < polyline_world.size(); ++i) total_length += (polyline_world[i + 1] - polyline_world[i]).norm();
  CheckPathSize(total_length / spacing + 1.0, width_m, res);
  PathResult result;
  const std::vector<Station> stations = PathStations(polyline_world, width_m, spacing, &result.length_m);
  CheckPathSize(static_cast<double>(stations.size()), width_m, res);  // with the turns' samples

  const int lateral = width_m > 0.0 ? static_cast<int>(std::ceil(width_m / res)) + 1 : 1;
  auto read = [&](double x, double y) { return surface ? surface(x, y) : TopSurfaceAt(x, y); };
  double cost_sum = 0.0, observed_sum = 0.0;
  int cost_count = 0;
  for (const Station& station : stations) {
    PathSample sample = SampleAcross(station, width_m, lateral, read);
    observed_sum += sample.fraction_observed;
    if (std::isfinite(sample.cost)) {
      cost_sum += sample.cost;
      ++cost_count;
    }
    if (Severity(sample.cls) > Severity(result.worst)) result.worst = sample.cls;
    if (sample.cls == TravClass::kNonTraversable && !result.blocked) {
      result.blocked = true;
      result.first_non_traversable = sample.point;
      result.first_non_traversable_distance_m = sample.distance_m;
    }
    result.samples.push_back(std::move(sample));
  }
  if (cost_count > 0) result.mean_cost = cost_sum / cost_count;
  result.fraction_observed = observed_sum / static_cast<double>(result.samples.size());
  return result;
}

GridProjection TraversabilityMap::Project(const Eigen::AlignedBox2d& region,
                                          double resolution_m) const {
  if (!(resolution_m > 0.0 && std::isfinite(resolution_m))) {
    throw Error("grid projection: resolution must be positive");
  }
  if (region.isEmpty() || !region.min().allFinite() || !region.max().allFinite() ||
      !(region.sizes().array() > 0.0).all()) {
    throw Error("grid projection: the region is empty");
  }
  const Eigen::Vector2d cells = (region.sizes() / resolution_m).array() - 1e-9;
  const double w = std::max(1.0, std::ceil(cells.x()));
  const double h = std::max(1.0, std::ceil(cells.y()));
  if (w * h > static_cast<double>(1 << 26)) {  // 21 bytes a pixel: ~1.1 GB (819 m square at 0.1 m)
    throw Error("grid projection: more than 2^26 pixels; use a coarser resolution or a smaller region");
  }
  GridProjection grid;
  grid.origin = region.min();
  grid.resolution_m = resolution_m;
  const int width = static_cast<int>(w), height = static_cast<int>(h);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  grid.classes = ImageU8(width, height, 0);
  grid.cost = ImageF(width, height, nan);
  grid.height_m = ImageF(width, height, nan);
  grid.slope_deg = ImageF(width, height, nan);
  grid.step_m = ImageF(width, height, nan);
  grid.confidence = ImageF(width, height, nan);
  grid.surface_z_m = ImageF(width, height, nan);
  // A pixel coarser than the map's columns takes the worst of the columns whose centres it
  // holds (a planner must not read an obstacle's pixel as free); at the map's resolution or
  // finer, the column under the pixel's centre.
  const double map_res = impl_->options.resolution_m;
  const bool coarse = resolution_m > map_res * (1.0 + 1e-9);
  auto worst_in_pixel = [&](int v, int u) {
    const Eigen::Vector2d c = grid.PixelCenter(v, u);
    if (!coarse) return TopSurfaceAt(c.x(), c.y());
    const Eigen::Vector2d lo = c.array() - 0.5 * resolution_m, hi = c.array() + 0.5 * resolution_m;
    CellInfo worst;  // unobserved until a column is; a coarser pixel holds at least one centre
    // Column centres sit at (k + 0.5) * map_res: those in [lo, hi).
    for (double x = (std::ceil(lo.x() / map_res - 0.5) + 0.5) * map_res; x < hi.x(); x += map_res) {
      for (double y = (std::ceil(lo.y() / map_res - 0.5) + 0.5) * map_res; y < hi.y(); y += map_res) {
        const CellInfo cell = TopSurfaceAt(x, y);
        if (cell.observed && (!worst.observed || Severity(cell.cls) > Severity(worst.cls))) worst = cell;
      }
    }
    return worst;
  };
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const CellInfo cell = worst_in_pixel(v, u);
      if (!cell.observed) continue;
      grid.classes(v, u) = static_cast<std::uint8_t>(cell.cls);
      grid.cost(v, u) = static_cast<float>(cell.cost);
      grid.height_m(v, u) = static_cast<float>(cell.center.z());
      grid.slope_deg(v, u) = static_cast<float>(cell.slope_deg);
      grid.step_m(v, u) = static_cast<float>(cell.step_m);
      grid.confidence(v, u) = static_cast<float>(cell.confidence);
      grid.surface_z_m(v, u) = static_cast<float>(cell.surface_z_m);
    }
  }
  return grid;
}

std::vector<CellInfo> TraversabilityMap::SurfaceCells() const {
  const TravOcTree& tree = *impl_->tree;
  const double res = tree.getResolution();
  std::vector<CellInfo> cells;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!NodeOccupied(tree, *it)) continue;
    const double half = 0.5 * it.getSize();
    octomap::OcTreeKey base;
    if (!tree.coordToKeyChecked(it.getX() - half + 0.5 * res, it.getY() - half + 0.5 * res,
                                it.getZ() - half + 0.5 * res, base)) {
      continue;
    }
    internal::ForEachVoxelOfLeaf(base, tree.getTreeDepth(), it.getDepth(), [&](const octomap::OcTreeKey& key) {
      cells.push_back(internal::DescribeCell(*this, tree, &*it, key));
    });
  }
  return cells;
}

Eigen::AlignedBox3d TraversabilityMap::SurfaceBounds() const {
  const TravOcTree& tree = *impl_->tree;
  Eigen::AlignedBox3d box;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!NodeOccupied(tree, *it)) continue;
    const Eigen::Vector3d c(it.getX(), it.getY(), it.getZ());
    const Eigen::Vector3d half = Eigen::Vector3d::Constant(0.5 * it.getSize());
    box.extend(c - half);
    box.extend(c + half);
  }
  return box;
}

}  // namespace ssta
