#include "ssta/synth/scene.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "ssta/core/error.h"
#include "ssta/core/units.h"
#include "synth/random.h"

namespace ssta::synth {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// World (x, y) relative to a centre, expressed in a frame rotated by yaw (given as cos, sin).
Eigen::Vector2d ToLocal(double x, double y, double cx, double cy, double c, double s) {
  const double dx = x - cx, dy = y - cy;
  return {c * dx + s * dy, -s * dx + c * dy};
}

Eigen::Vector2d RotateToWorld(const Eigen::Vector2d& v, double c, double s) {
  return {c * v.x() - s * v.y(), s * v.x() + c * v.y()};
}

/// Rotation about z by the angle whose cosine and sine are c and s.
Eigen::Vector3d RotateZ(const Eigen::Vector3d& v, double c, double s) {
  return {c * v.x() - s * v.y(), s * v.x() + c * v.y(), v.z()};
}

double RampHeight(const GroundRamp& r, double x, double y, Eigen::Vector2d* gradient) {
  const Eigen::Vector2d l = ToLocal(x, y, r.x, r.y, r.cos_yaw, r.sin_yaw);
  const double ex = std::max(0.0, std::abs(l.x()) - r.half_x_m);
  const double ey = std::max(0.0, std::abs(l.y()) - r.half_y_m);
  const double k = r.tan_slope;
  const double e = std::max(ex, ey);
  const double h = r.height_m - k * e;
  if (h <= 0) return 0;
  if (gradient && e > 0) {
    const Eigen::Vector2d g_local = ex >= ey ? Eigen::Vector2d(-k * (l.x() > 0 ? 1 : -1), 0)
                                             : Eigen::Vector2d(0, -k * (l.y() > 0 ? 1 : -1));
    *gradient += RotateToWorld(g_local, r.cos_yaw, r.sin_yaw);
  }
  return h;
}

/// Smallest t > t_min where the ray enters the solid, with the outward normal there.
struct SolidHit {
  double t = kInf;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
};

SolidHit IntersectBox(const Obstacle& b, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                      double t_min) {
  const Eigen::Vector3d ol = RotateZ(o - Eigen::Vector3d(b.x, b.y, 0), b.cos_yaw, -b.sin_yaw);
  const Eigen::Vector3d dl = RotateZ(d, b.cos_yaw, -b.sin_yaw);
  const double lo[3] = {-b.a, -b.b, b.z_min}, hi[3] = {b.a, b.b, b.z_max};
  double t_enter = -kInf, t_exit = kInf;
  int axis = 2;
  double sign = 1;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(dl[i]) < 1e-15) {
      if (ol[i] < lo[i] || ol[i] > hi[i]) return {};
      continue;
    }
    double t0 = (lo[i] - ol[i]) / dl[i], t1 = (hi[i] - ol[i]) / dl[i];
    double s = -1;
    if (t0 > t1) {
      std::swap(t0, t1);
      s = 1;
    }
    if (t0 > t_enter) {
      t_enter = t0;
      axis = i;
      sign = s;
    }
    t_exit = std::min(t_exit, t1);
  }
  if (t_enter > t_exit || t_enter < t_min) return {};
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  n[axis] = sign;
  return {t_enter, RotateZ(n, b.cos_yaw, b.sin_yaw)};
}

SolidHit IntersectCylinder(const Obstacle& c, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                           double t_min) {
  const double ox = o.x() - c.x, oy = o.y() - c.y;
  const double qa = d.x() * d.x() + d.y() * d.y();
  SolidHit best;
  if (qa > 1e-18) {
    const double qb = 2 * (ox * d.x() + oy * d.y());
    const double qc = ox * ox + oy * oy - c.a * c.a;
    const double disc = qb * qb - 4 * qa * qc;
    if (disc >= 0) {
      const double t = (-qb - std::sqrt(disc)) / (2 * qa);
      const double z = o.z() + t * d.z();
      if (t >= t_min && z >= c.z_min && z <= c.z_max) {
        best.t = t;
        best.normal = Eigen::Vector3d(ox + t * d.x(), oy + t * d.y(), 0).normalized();
      }
    }
  }
  if (d.z() < 0 && o.z() > c.z_max) {  // the top cap, seen from above
    const double t = (c.z_max - o.z()) / d.z();
    const double px = ox + t * d.x(), py = oy + t * d.y();
    if (t >= t_min && t < best.t && px * px + py * py <= c.a * c.a) {
      best.t = t;
      best.normal = Eigen::Vector3d::UnitZ();
    }
  }
  return best;
}

SolidHit IntersectLog(const Obstacle& g, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                      double t_min) {
  const Eigen::Vector3d centre(g.x, g.y, g.z_max - g.a);
  const Eigen::Vector3d ol = RotateZ(o - centre, g.cos_yaw, -g.sin_yaw);
  const Eigen::Vector3d dl = RotateZ(d, g.cos_yaw, -g.sin_yaw);
  SolidHit best;
  const double qa = dl.y() * dl.y() + dl.z() * dl.z();
  if (qa > 1e-18) {
    const double qb = 2 * (ol.y() * dl.y() + ol.z() * dl.z());
    const double qc = ol.y() * ol.y() + ol.z() * ol.z() - g.a * g.a;
    const double disc = qb * qb - 4 * qa * qc;
    if (disc >= 0) {
      const double t = (-qb - std::sqrt(disc)) / (2 * qa);
      const Eigen::Vector3d p = ol + t * dl;
      if (t >= t_min && std::abs(p.x()) <= g.b) {
        best.t = t;
        best.normal = Eigen::Vector3d(0, p.y(), p.z()).normalized();
      }
    }
  }
  for (double side : {-1.0, 1.0}) {  // the two end discs
    if (std::abs(dl.x()) < 1e-15) break;
    const double t = (side * g.b - ol.x()) / dl.x();
    const Eigen::Vector3d p = ol + t * dl;
    if (t >= t_min && t < best.t && dl.x() * side < 0 &&
        p.y() * p.y() + p.z() * p.z() <= g.a * g.a) {
      best.t = t;
      best.normal = Eigen::Vector3d(side, 0, 0);
    }
  }
  if (best.t < kInf) best.normal = RotateZ(best.normal, g.cos_yaw, g.sin_yaw);
  return best;
}

SolidHit IntersectEllipsoid(const Obstacle& e, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                            double t_min) {
  const Eigen::Vector3d centre(e.x, e.y, e.z_min + e.c);
  const Eigen::Vector3d radii(e.a, e.b, e.c);
  const Eigen::Vector3d ol = RotateZ(o - centre, e.cos_yaw, -e.sin_yaw).cwiseQuotient(radii);
  const Eigen::Vector3d dl = RotateZ(d, e.cos_yaw, -e.sin_yaw).cwiseQuotient(radii);
  const double qa = dl.squaredNorm();
  const double qb = 2 * ol.dot(dl);
  const double qc = ol.squaredNorm() - 1;
  const double disc = qb * qb - 4 * qa * qc;
  if (disc < 0) return {};
  const double t = (-qb - std::sqrt(disc)) / (2 * qa);
  if (t < t_min) return {};
  const Eigen::Vector3d p = ol + t * dl;  // on the unit sphere
  const Eigen::Vector3d n_local = p.cwiseQuotient(radii);
  return {t, RotateZ(n_local, e.cos_yaw, e.sin_yaw).normalized()};
}

SolidHit IntersectObstacle(const Obstacle& ob, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                           double t_min) {
  switch (ob.shape) {
    case Obstacle::Shape::kBox: return IntersectBox(ob, o, d, t_min);
    case Obstacle::Shape::kCylinder: return IntersectCylinder(ob, o, d, t_min);
    case Obstacle::Shape::kLog: return IntersectLog(ob, o, d, t_min);
    case Obstacle::Shape::kEllipsoid: return IntersectEllipsoid(ob, o, d, t_min);
  }
  return {};
}

/// True when the ray can pass within `radius` of `centre` beyond t_min and before t_max.
bool RayNearSphere(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& centre,
                   double radius, double t_max) {
  const Eigen::Vector3d w = centre - o;
  const double dd = d.squaredNorm();
  const double tc = std::clamp(w.dot(d) / dd, 0.0, t_max);
  return (w - tc * d).squaredNorm() <= radius * radius;
}

}  // namespace

double Scene::BaseHeight(double x, double y) const {
  double z = plane_gradient.x() * x + plane_gradient.y() * y;
  for (const GroundBump& b : bumps) {
    const double q = 1 - ((x - b.x) * (x - b.x) + (y - b.y) * (y - b.y)) / (b.radius_m * b.radius_m);
    if (q > 0) z += b.amplitude_m * q * q * q;
  }
  for (const GroundRamp& r : ramps) z += RampHeight(r, x, y, nullptr);
  return z;
}

Eigen::Vector2d Scene::BaseGradient(double x, double y) const {
  Eigen::Vector2d g = plane_gradient;
  for (const GroundBump& b : bumps) {
    const double dx = x - b.x, dy = y - b.y, r2 = b.radius_m * b.radius_m;
    const double q = 1 - (dx * dx + dy * dy) / r2;
    if (q <= 0) continue;
    const double k = -6 * b.amplitude_m * q * q / r2;  // d/dx of A q^3 = 3 A q^2 (-2 dx / R^2)
    g += Eigen::Vector2d(k * dx, k * dy);
  }
  for (const GroundRamp& r : ramps) RampHeight(r, x, y, &g);
  return g;
}

int Scene::PitAt(double x, double y) const {
  for (std::size_t i = 0; i < pits.size(); ++i) {
    const Pit& p = pits[i];
    const Eigen::Vector2d l = ToLocal(x, y, p.x, p.y, p.cos_yaw, p.sin_yaw);
    if (std::abs(l.x()) < p.half_x_m && std::abs(l.y()) < p.half_y_m) return static_cast<int>(i);
  }
  return -1;
}

double Scene::GroundHeight(double x, double y) const {
  const int pit = PitAt(x, y);
  return BaseHeight(x, y) - (pit >= 0 ? pits[pit].depth_m : 0.0);
}

Material Scene::GroundMaterialAt(double x, double y, int pit) const {
  if (pit >= 0) return Material::kSoil;
  for (const TexturelessPatch& p : textureless) {
    if ((x - p.x) * (x - p.x) + (y - p.y) * (y - p.y) < p.radius_m * p.radius_m) {
      return Material::kTextureless;
    }
  }
  for (const GroundRamp& r : ramps) {
    if (RampHeight(r, x, y, nullptr) > 1e-9) return Material::kConcrete;
  }
  return ground_material;
}

namespace {

/// World rectangle [x0, x1] x [y0, y1] [m].
struct Extent {
  double x0, x1, y0, y1;
};

/// Layout of the bound grid: lower-left corner (x0, y0) in world [m], side of its square cells
/// [m], and its size in cells.
struct GridLayout {
  double x0, y0, cell;
  int nx, ny;
};

/// Per bound cell (row-major), the maxima over its samples of the visible ground height [m],
/// the base ground height [m] and the base slope |grad| [m/m], and whether a pit shows in it.
struct CellSamples {
  std::vector<float> z, base, slope;
  std::vector<std::uint8_t> pit;
};

/// Per bound cell (row-major), conservative upper bounds of the ground height [m] and of the
/// base slope |grad| [m/m].
struct CellBounds {
  std::vector<float> zmax, slope;
};

/// The bound cells grouped in square blocks: the max of the cells' height bounds per block
/// (row-major) and over the whole grid [m].
struct BlockMaxima {
  int nx = 0, ny = 0;
  std::vector<float> zmax;
  double zmax_all = -kInf;
};

/// Samples per side of a bound cell, edges included.
constexpr int kSamples = 5;

/// Caches the cosine and sine of each ramp's, pit's and obstacle's yaw, and each ramp's slope
/// tangent.
void CacheTrig(Scene* scene) {
  for (GroundRamp& r : scene->ramps) {
    r.cos_yaw = std::cos(r.yaw_rad);
    r.sin_yaw = std::sin(r.yaw_rad);
    r.tan_slope = std::tan(DegToRad(r.slope_deg));
  }
  for (Pit& p : scene->pits) {
    p.cos_yaw = std::cos(p.yaw_rad);
    p.sin_yaw = std::sin(p.yaw_rad);
  }
  for (Obstacle& ob : scene->obstacles) {
    ob.cos_yaw = std::cos(ob.yaw_rad);
    ob.sin_yaw = std::sin(ob.yaw_rad);
  }
}

/// The world area every bump, ramp and pit reaches, and at least 30 m around the start [m].
/// Precondition: the ramps' tan_slope is cached.
Extent SceneExtent(const Scene& scene) {
  double x0 = scene.start_xy.x() - 30, x1 = scene.start_xy.x() + 30;
  double y0 = scene.start_xy.y() - 30, y1 = scene.start_xy.y() + 30;
  auto cover = [&](double x, double y, double r) {
    x0 = std::min(x0, x - r);
    x1 = std::max(x1, x + r);
    y0 = std::min(y0, y - r);
    y1 = std::max(y1, y + r);
  };
  for (const GroundBump& b : scene.bumps) cover(b.x, b.y, b.radius_m);
  for (const GroundRamp& r : scene.ramps) {
    cover(r.x, r.y, std::hypot(r.half_x_m, r.half_y_m) + r.height_m / r.tan_slope);
  }
  for (const Pit& p : scene.pits) cover(p.x, p.y, std::hypot(p.half_x_m, p.half_y_m));
  return {x0, x1, y0, y1};
}

/// Cells of side `cell` [m] over `extent`, with a margin of one cell on every side.
GridLayout LayOutBoundGrid(const Extent& extent, double cell) {
  GridLayout grid;
  grid.x0 = extent.x0 - cell;
  grid.y0 = extent.y0 - cell;
  grid.cell = cell;
  grid.nx = static_cast<int>(std::ceil((extent.x1 - extent.x0) / cell)) + 2;
  grid.ny = static_cast<int>(std::ceil((extent.y1 - extent.y0) / cell)) + 2;
  return grid;
}

/// Samples kSamples x kSamples points of each cell of `grid` on the ground of `scene`.
CellSamples SampleBoundGrid(const Scene& scene, const GridLayout& grid) {
  const std::size_t cells = static_cast<std::size_t>(grid.nx) * grid.ny;
  CellSamples out;
  out.z.resize(cells);
  out.base.resize(cells);
  out.slope.resize(cells);
  out.pit.assign(cells, 0);
  const double spacing = grid.cell / (kSamples - 1);
  for (int iy = 0; iy < grid.ny; ++iy) {
    for (int ix = 0; ix < grid.nx; ++ix) {
      double z = -kInf, zb = -kInf, g = 0;
      bool pit = false;
      for (int j = 0; j < kSamples; ++j) {
        for (int i = 0; i < kSamples; ++i) {
          const double x = grid.x0 + ix * grid.cell + i * spacing;
          const double y = grid.y0 + iy * grid.cell + j * spacing;
          const double base = scene.BaseHeight(x, y);
          const double ground = scene.GroundHeight(x, y);
          z = std::max(z, ground);
          zb = std::max(zb, base);
          pit = pit || ground < base;
          g = std::max(g, scene.BaseGradient(x, y).norm());
        }
      }
      const std::size_t k = static_cast<std::size_t>(iy) * grid.nx + ix;
      out.z[k] = static_cast<float>(z);
      out.base[k] = static_cast<float>(zb);
      out.slope[k] = static_cast<float>(g);
      out.pit[k] = pit ? 1 : 0;
    }
  }
  return out;
}

/// Makes the sampled maxima conservative: a margin for what falls between the samples, and
/// (for the slope) the neighbours' maxima too.
CellBounds BoundCells(const CellSamples& samples, const GridLayout& grid) {
  const std::size_t cells = static_cast<std::size_t>(grid.nx) * grid.ny;
  const double spacing = grid.cell / (kSamples - 1);
  CellBounds out;
  out.zmax.assign(cells, 0.f);
  out.slope.assign(cells, 0.f);
  for (int iy = 0; iy < grid.ny; ++iy) {
    for (int ix = 0; ix < grid.nx; ++ix) {
      double g = 0, base_near = -kInf;
      bool pit_near = false;
      for (int j = std::max(0, iy - 1); j <= std::min(grid.ny - 1, iy + 1); ++j) {
        for (int i = std::max(0, ix - 1); i <= std::min(grid.nx - 1, ix + 1); ++i) {
          const std::size_t n = static_cast<std::size_t>(j) * grid.nx + i;
          g = std::max(g, static_cast<double>(samples.slope[n]));
          base_near = std::max(base_near, static_cast<double>(samples.base[n]));
          pit_near = pit_near || samples.pit[n];
        }
      }
      const std::size_t k = static_cast<std::size_t>(iy) * grid.nx + ix;
      out.slope[k] = static_cast<float>(1.25 * g + 0.05);
      double z = samples.z[k] + out.slope[k] * spacing * 0.7072 + 1e-4;
      // Near a pit's edge the samples may miss a sliver of higher ground: bound by the base.
      if (pit_near) z = std::max(z, base_near + out.slope[k] * grid.cell * 1.5 + 1e-4);
      out.zmax[k] = static_cast<float>(z);
    }
  }
  return out;
}

/// Groups the cells of `grid` in blocks of `block_cells` x `block_cells` and takes the max of
/// the height bounds `zmax` [m] per block and over all.
BlockMaxima BuildBlockMaxima(const std::vector<float>& zmax, const GridLayout& grid, int block_cells) {
  BlockMaxima out;
  out.nx = (grid.nx + block_cells - 1) / block_cells;
  out.ny = (grid.ny + block_cells - 1) / block_cells;
  out.zmax.assign(static_cast<std::size_t>(out.nx) * out.ny, -std::numeric_limits<float>::infinity());
  for (int iy = 0; iy < grid.ny; ++iy) {
    for (int ix = 0; ix < grid.nx; ++ix) {
      const float z = zmax[static_cast<std::size_t>(iy) * grid.nx + ix];
      float& b = out.zmax[static_cast<std::size_t>(iy / block_cells) * out.nx + ix / block_cells];
      b = std::max(b, z);
      out.zmax_all = std::max(out.zmax_all, static_cast<double>(z));
    }
  }
  return out;
}

/// Sets each obstacle's bounding sphere: centre in world and radius [m].
void ObstacleBounds(std::vector<Obstacle>* obstacles) {
  for (Obstacle& ob : *obstacles) {
    switch (ob.shape) {
      case Obstacle::Shape::kBox:
        ob.bound_centre = {ob.x, ob.y, 0.5 * (ob.z_min + ob.z_max)};
        ob.bound_radius = std::sqrt(ob.a * ob.a + ob.b * ob.b +
                                    0.25 * (ob.z_max - ob.z_min) * (ob.z_max - ob.z_min));
        break;
      case Obstacle::Shape::kCylinder:
        ob.bound_centre = {ob.x, ob.y, 0.5 * (ob.z_min + ob.z_max)};
        ob.bound_radius = std::hypot(ob.a, 0.5 * (ob.z_max - ob.z_min));
        break;
      case Obstacle::Shape::kLog:
        ob.bound_centre = {ob.x, ob.y, ob.z_max - ob.a};
        ob.bound_radius = std::hypot(ob.a, ob.b);
        break;
      case Obstacle::Shape::kEllipsoid:
        ob.bound_centre = {ob.x, ob.y, ob.z_min + ob.c};
        ob.bound_radius = std::max({ob.a, ob.b, ob.c});
        break;
    }
  }
}

}  // namespace

void Scene::Finish() {
  CacheTrig(this);
  // Bound grid: sampled maxima of height and slope per cell, made conservative by a margin
  // and (for the slope) by taking the neighbours' maxima too.
  const GridLayout grid = LayOutBoundGrid(SceneExtent(*this), bound_cell_);
  bound_x0_ = grid.x0;
  bound_y0_ = grid.y0;
  bound_nx_ = grid.nx;
  bound_ny_ = grid.ny;
  CellBounds bounds = BoundCells(SampleBoundGrid(*this, grid), grid);
  bound_zmax_ = std::move(bounds.zmax);
  bound_slope_ = std::move(bounds.slope);
  BlockMaxima blocks = BuildBlockMaxima(bound_zmax_, grid, kBlockCells);
  block_nx_ = blocks.nx;
  block_ny_ = blocks.ny;
  block_zmax_ = std::move(blocks.zmax);
  bound_zmax_all_ = blocks.zmax_all;
  ObstacleBounds(&obstacles);
}

SurfaceHit Scene::PlaneHit(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t0,
                           double t1) const {
  // o.z + t d.z = g . (o.xy + t d.xy)
  const double a = o.z() - plane_gradient.dot(o.head<2>());
  const double b = d.z() - plane_gradient.dot(d.head<2>());
  if (a <= 0 || b >= 0) return {};
  const double t = -a / b;
  if (t < t0 || t > t1) return {};
  SurfaceHit hit;
  hit.hit = true;
  hit.t = t;
  hit.p_world = o + t * d;
  hit.normal_world = Eigen::Vector3d(-plane_gradient.x(), -plane_gradient.y(), 1).normalized();
  hit.material = ground_material;
  return hit;
}

SurfaceHit Scene::CastGround(const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                             double t_max) const {
  const double len = d.norm();
  const double t_min = 1e-4 / len;
  // Clip the ray to the bound grid's box.
  double t_in = t_min, t_out = t_max;
  const double lo[2] = {bound_x0_, bound_y0_};
  const double hi[2] = {bound_x0_ + bound_nx_ * bound_cell_, bound_y0_ + bound_ny_ * bound_cell_};
  for (int a = 0; a < 2; ++a) {
    if (std::abs(d[a]) < 1e-15) {
      if (o[a] < lo[a] || o[a] > hi[a]) t_in = kInf;
      continue;
    }
    double ta = (lo[a] - o[a]) / d[a], tb = (hi[a] - o[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    t_in = std::max(t_in, ta);
    t_out = std::min(t_out, tb);
  }
  if (t_in >= t_out) return PlaneHit(o, d, t_min, t_max);
  if (t_in > t_min) {
    const SurfaceHit before = PlaneHit(o, d, t_min, t_in);
    if (before.hit) return before;
  }

  const double horiz = std::hypot(d.x(), d.y());
  auto gap = [&](double tt) {
    const Eigen::Vector3d p = o + tt * d;
    return p.z() - GroundHeight(p.x(), p.y());
  };
  double t = t_in;
  if (gap(t) <= 0) return {};  // starts under the ground
  double t_prev = t;
  bool crossed = false;
  // Exit parameter of the square [x0 + ix * size, ...) x [y0 + iy * size, ...) the ray is in.
  auto exit_of = [&](int ix, int iy, double size) {
    double te = t_out;
    if (d.x() > 0) te = std::min(te, (bound_x0_ + (ix + 1) * size - o.x()) / d.x());
    if (d.x() < 0) te = std::min(te, (bound_x0_ + ix * size - o.x()) / d.x());
    if (d.y() > 0) te = std::min(te, (bound_y0_ + (iy + 1) * size - o.y()) / d.y());
    if (d.y() < 0) te = std::min(te, (bound_y0_ + iy * size - o.y()) / d.y());
    return te;
  };
  const double block_size = bound_cell_ * kBlockCells;
  while (t <= t_out) {
    const Eigen::Vector3d p = o + t * d;
    if (p.z() > bound_zmax_all_ && d.z() >= 0) break;  // above everything and rising
    const int bx = std::clamp(static_cast<int>((p.x() - bound_x0_) / block_size), 0, block_nx_ - 1);
    const int by = std::clamp(static_cast<int>((p.y() - bound_y0_) / block_size), 0, block_ny_ - 1);
    const double t_block = exit_of(bx, by, block_size);
    if (std::min(p.z(), o.z() + t_block * d.z()) > block_zmax_[static_cast<std::size_t>(by) * block_nx_ + bx]) {
      t = std::max(t_block, t) + 1e-7 / len;  // the ray passes above this whole block
      continue;
    }
    const int ix = std::clamp(static_cast<int>((p.x() - bound_x0_) / bound_cell_), 0, bound_nx_ - 1);
    const int iy = std::clamp(static_cast<int>((p.y() - bound_y0_) / bound_cell_), 0, bound_ny_ - 1);
    const double t_cell = exit_of(ix, iy, bound_cell_);
    const std::size_t cell = static_cast<std::size_t>(iy) * bound_nx_ + ix;
    const double z_low = std::min(p.z(), o.z() + t_cell * d.z());
    // Fastest the gap to the ground can shrink per unit t inside this cell.
    const double close_rate = bound_slope_[cell] * horiz - d.z();
    if (z_low > bound_zmax_[cell] || close_rate <= 0) {
      t = std::max(t_cell, t) + 1e-7 / len;  // the ray cannot meet the ground in this cell
      continue;
    }
    const double h = p.z() - GroundHeight(p.x(), p.y());
    if (h <= 0) {
      crossed = true;
      break;
    }
    t_prev = t;
    const double min_step = (0.003 + 0.0015 * t * len) / len;
    t = std::min(t + std::max(0.9 * h / close_rate, min_step), std::max(t_cell, t) + 1e-7 / len);
  }
  if (!crossed) {
    if (t_out >= t_max) return {};
    return PlaneHit(o, d, t_out, t_max);
  }
  return RefineGround(o, d, t_prev, t);
}

SurfaceHit Scene::RefineGround(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double lo,
                               double hi) const {
  const double len = d.norm();
  auto gap = [&](double tt) {
    const Eigen::Vector3d p = o + tt * d;
    return p.z() - GroundHeight(p.x(), p.y());
  };
  // Illinois (modified regula falsi): keeps the bracket, converges fast on smooth ground and
  // still closes in on the jump of a pit wall.
  double f_lo = gap(lo), f_hi = gap(hi);
  int side = 0;
  for (int i = 0; i < 80 && (hi - lo) * len > 1e-6; ++i) {
    double m = hi - f_hi * (hi - lo) / (f_hi - f_lo);
    if (!(m > lo && m < hi)) m = 0.5 * (lo + hi);
    const double f_m = gap(m);
    if (f_m > 0) {
      lo = m;
      f_lo = f_m;
      if (side == 1) f_hi *= 0.5;
      side = 1;
    } else {
      hi = m;
      f_hi = f_m;
      if (side == -1) f_lo *= 0.5;
      side = -1;
    }
  }
  SurfaceHit hit;
  hit.hit = true;
  hit.t = hi;
  hit.p_world = o + hi * d;
  const Eigen::Vector3d p_lo = o + lo * d;
  const double x = hit.p_world.x(), y = hit.p_world.y();
  const int pit = PitAt(x, y);
  const int pit_lo = PitAt(p_lo.x(), p_lo.y());
  const double jump = GroundHeight(x, y) - GroundHeight(p_lo.x(), p_lo.y());
  const double base = BaseHeight(x, y);
  if (pit_lo >= 0 && pit != pit_lo && jump > 1e-4) {
    // The far wall of a pit, seen from inside it: faces back into the pit.
    const Pit& p = pits[pit_lo];
    const Eigen::Vector2d l = ToLocal(p_lo.x(), p_lo.y(), p.x, p.y, p.cos_yaw, p.sin_yaw);
    const Eigen::Vector2d n_local = (p.half_x_m - std::abs(l.x()) < p.half_y_m - std::abs(l.y()))
                                        ? Eigen::Vector2d(l.x() > 0 ? -1 : 1, 0)
                                        : Eigen::Vector2d(0, l.y() > 0 ? -1 : 1);
    const Eigen::Vector2d n = RotateToWorld(n_local, p.cos_yaw, p.sin_yaw);
    hit.normal_world = Eigen::Vector3d(n.x(), n.y(), 0);
    hit.vertical_face = true;
    hit.step_m = std::min(0.0, hit.p_world.z() - base);
    hit.material = Material::kSoil;
    hit.object_id = -(pit_lo + 1);
    return hit;
  }
  const Eigen::Vector2d g = BaseGradient(x, y);
  hit.normal_world = Eigen::Vector3d(-g.x(), -g.y(), 1).normalized();
  hit.step_m = pit >= 0 ? -pits[pit].depth_m : 0.0;
  hit.material = GroundMaterialAt(x, y, pit);
  hit.object_id = pit >= 0 ? -(pit + 1) : 0;
  return hit;
}

SurfaceHit Scene::CastRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                          double t_max) const {
  const double t_min = 1e-4 / direction.norm();
  double best_t = t_max;
  int best = -1;
  Eigen::Vector3d best_normal;
  for (std::size_t i = 0; i < obstacles.size(); ++i) {
    const Obstacle& ob = obstacles[i];
    if (!RayNearSphere(origin, direction, ob.bound_centre, ob.bound_radius, best_t)) continue;
    const SolidHit s = IntersectObstacle(ob, origin, direction, t_min);
    if (s.t < best_t) {
      best_t = s.t;
      best = static_cast<int>(i);
      best_normal = s.normal;
    }
  }
  SurfaceHit ground = CastGround(origin, direction, best_t);
  if (ground.hit) return ground;
  if (best < 0) return {};
  SurfaceHit hit;
  hit.hit = true;
  hit.t = best_t;
  hit.p_world = origin + best_t * direction;
  hit.normal_world = best_normal;
  hit.step_m = hit.p_world.z() - BaseHeight(hit.p_world.x(), hit.p_world.y());
  hit.material = obstacles[best].material;
  hit.object_id = best + 1;
  return hit;
}


}  // namespace ssta::synth
