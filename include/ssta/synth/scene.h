#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ssta/core/vehicle_options.h"
#include "ssta/core/classes.h"

namespace ssta::synth {

/// Surface materials; each has its own albedo and procedural texture.
enum class Material : std::uint8_t {
  kGrass, kGravel, kConcrete, kSoil, kRock, kBark, kWood, kBrick, kTextureless
};

/// A smooth bump of the base ground: `amplitude_m * (1 - r^2 / radius_m^2)^3` for r < radius_m,
/// zero beyond (twice continuously differentiable; negative amplitude = dip). Its steepest
/// slope is 1.717 * |amplitude_m| / radius_m, reached at r = radius_m / sqrt(5).
struct GroundBump {
  double x = 0, y = 0;         ///< centre in world [m]
  double amplitude_m = 0;      ///< height at the centre [m]
  double radius_m = 1;         ///< support radius [m]
};

/// A ramp in the base ground: a truncated pyramid whose flat top (half sizes `half_x_m`,
/// `half_y_m` in its own frame, rotated by `yaw_rad`) stands `height_m` above its
/// surroundings and whose four planar flanks rise at exactly `slope_deg`.
struct GroundRamp {
  double x = 0, y = 0, yaw_rad = 0;
  double half_x_m = 1, half_y_m = 1;
  double height_m = 0.5;
  double slope_deg = 10;
  double cos_yaw = 1, sin_yaw = 0, tan_slope = 0;  ///< cached by Scene::Finish
};

/// A negative obstacle: inside the oriented rectangle the ground lies `depth_m` below the base
/// ground, with vertical walls (a pit, trench or drop-off).
struct Pit {
  double x = 0, y = 0, yaw_rad = 0;
  double half_x_m = 1, half_y_m = 1;
  double depth_m = 0.5;
  double cos_yaw = 1, sin_yaw = 0;  ///< cached by Scene::Finish
};

/// A positive obstacle solid. All are closed analytic solids in world coordinates, placed so
/// that their bottom is buried in the ground.
struct Obstacle {
  enum class Shape : std::uint8_t {
    kBox,        ///< oriented box: half sizes (a, b) around (x, y), yaw; z from z_min to z_max
    kCylinder,   ///< vertical cylinder (trunk, post): radius a; z from z_min to z_max
    kLog,        ///< horizontal cylinder lying along yaw: radius a, half length b, axis at z_max - a
    kEllipsoid,  ///< rock lobe: radii (a, b, c), yaw, centre at (x, y, z_min + c)
  };
  Shape shape = Shape::kBox;
  double x = 0, y = 0, yaw_rad = 0;
  double a = 0.5, b = 0.5, c = 0.5;
  double z_min = -0.5, z_max = 0.5;  ///< world heights [m]
  Material material = Material::kConcrete;
  Eigen::Vector3d bound_centre = Eigen::Vector3d::Zero();  ///< bounding sphere (set by Finish)
  double bound_radius = 0;
  double cos_yaw = 1, sin_yaw = 0;  ///< cached by Finish
};

/// A flat disc of the ground painted without texture (fault `--textureless-patches`).
struct TexturelessPatch {
  double x = 0, y = 0, radius_m = 1;
};

/// Where a ray meets the scene.
struct SurfaceHit {
  bool hit = false;               ///< false: the ray sees the sky
  double t = 0;                   ///< ray parameter, in units of the ray direction given
  Eigen::Vector3d p_world = Eigen::Vector3d::Zero();  ///< hit point in world [m]
  Eigen::Vector3d normal_world = Eigen::Vector3d::UnitZ();  ///< unit outward normal
  double step_m = 0;              ///< hit height above the base ground under it [m] (signed)
  bool vertical_face = false;     ///< wall of a pit or drop-off
  Material material = Material::kGrass;
  int object_id = 0;              ///< 0 ground, k > 0 obstacle k - 1, -k pit k - 1
};

/// A static synthetic world: smooth base ground (plane + bumps + ramps) minus pits, plus
/// obstacle solids. World frame z up, metres. Immutable after construction; thread-safe to read.
class Scene {
 public:
  std::string name;
  Eigen::Vector2d plane_gradient = Eigen::Vector2d::Zero();  ///< base plane dz/dx, dz/dy
  std::vector<GroundBump> bumps;
  std::vector<GroundRamp> ramps;
  std::vector<Pit> pits;
  std::vector<Obstacle> obstacles;
  std::vector<TexturelessPatch> textureless;
  Material ground_material = Material::kGrass;
  Eigen::Vector2d start_xy = Eigen::Vector2d::Zero();  ///< where the vehicle starts [m]
  double start_yaw_rad = 0;                            ///< its heading [rad]
  /// How far the vehicle can drive from the start before its path meets an obstacle, pit or
  /// steep ramp [m]. The pose follows the base ground only, so beyond this it would drive
  /// through obstacles or float over pits.
  double clear_run_m = 1e9;
  std::uint64_t texture_seed = 1;

  /// Height of the smooth base ground (no pits, no obstacles) at (x, y) [m].
  double BaseHeight(double x, double y) const;
  /// Gradient (dz/dx, dz/dy) of the base ground.
  Eigen::Vector2d BaseGradient(double x, double y) const;
  /// Height of the visible ground: base ground, lowered inside pits [m].
  double GroundHeight(double x, double y) const;

  /// Casts the ray `origin + t * direction` for t in (0, t_max]; `direction` need not be unit
  /// (t is then in its units, e.g. camera depth when direction has camera z = 1).
  /// Precondition: Finish() was called after the last edit.
  SurfaceHit CastRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                     double t_max) const;

  /// Precomputes bounds (obstacle spheres, ground height range, slope bound). Call after edits.
  void Finish();

 private:
  int PitAt(double x, double y) const;
  SurfaceHit CastGround(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_max) const;
  Material GroundMaterialAt(double x, double y, int pit) const;

  /// Refines a ground crossing bracketed by gap(lo) > 0 >= gap(hi) into a hit.
  SurfaceHit RefineGround(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double lo,
                          double hi) const;
  /// Hit on the bare base plane (outside the bound grid, where no feature reaches).
  SurfaceHit PlaneHit(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t0,
                      double t1) const;

  /// Coarse grid over every ground feature holding an upper bound of the ground height per
  /// cell; rays skip cells they pass above. Outside it the ground is the bare base plane.
  double bound_x0_ = 0, bound_y0_ = 0, bound_cell_ = 0.5;
  int bound_nx_ = 0, bound_ny_ = 0;
  std::vector<float> bound_zmax_;
  std::vector<float> bound_slope_;  ///< upper bound of |grad BaseHeight| per cell
  static constexpr int kBlockCells = 8;  ///< bound cells per side of a coarse block
  int block_nx_ = 0, block_ny_ = 0;
  std::vector<float> block_zmax_;   ///< max of bound_zmax_ per block
  double bound_zmax_all_ = 0;       ///< max of bound_zmax_
};

/// The scene names MakeScene knows: yard, hills, dropoff, forest, ramp.
std::vector<std::string> SceneNames();

/// Builds a named scene; the layout's random parts come from `seed`. `ramp_slope_deg` is the
/// slope of the `ramp` scene. Throws ssta::Error for an unknown name.
Scene MakeScene(const std::string& name, std::uint64_t seed, double ramp_slope_deg = 20.0);

/// Lays `count` textureless discs on flat-ish ground ahead of the start pose (seeded).
void AddTexturelessPatches(Scene* scene, int count, std::uint64_t seed);

/// Sets a wooden box (a crate) on the visible ground of `scene`: centred at (x, y) in world
/// [m], its sides `length_m` along the heading `yaw_rad` and `width_m` across, its top
/// `height_m` above the ground under its centre, its bottom buried. Calls Finish().
void AddBox(Scene* scene, double x, double y, double yaw_rad, double length_m, double width_m, double height_m);

}  // namespace ssta::synth
