// The catalogue of named scenes. The vehicle starts at the origin heading +x; a corridor
// |y| < 1 m stays free for the first metres (Scene::clear_run_m) so that default runs never
// drive into an obstacle.

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "ssta/core/error.h"
#include "ssta/synth/scene.h"
#include "ssta/core/units.h"
#include "synth/random.h"

namespace ssta::synth {
namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
}  // namespace


std::vector<std::string> SceneNames() { return {"yard", "hills", "dropoff", "forest", "ramp", "random"}; }

namespace {

Obstacle MakeBox(double x, double y, double yaw, double half_x, double half_y, double height,
                 double ground_z, Material material) {
  Obstacle b;
  b.shape = Obstacle::Shape::kBox;
  b.x = x;
  b.y = y;
  b.yaw_rad = yaw;
  b.a = half_x;
  b.b = half_y;
  b.z_min = ground_z - 0.5;
  b.z_max = ground_z + height;
  b.material = material;
  return b;
}

/// A rock: two or three overlapping ellipsoid lobes, partly buried, about `height` tall.
void AddRock(Scene* s, Rng* rng, double x, double y, double height) {
  // Rests on the visible ground (a pit floor too) but never straddles a pit's edge.
  const double ground = s->GroundHeight(x, y);
  const double sunk = s->BaseHeight(x, y) - ground;
  const double reach = 2.5 * height + 0.3;
  for (const auto& [dx, dy] : {std::pair{reach, 0.0}, {-reach, 0.0}, {0.0, reach}, {0.0, -reach}}) {
    const double sunk_there = s->BaseHeight(x + dx, y + dy) - s->GroundHeight(x + dx, y + dy);
    if (std::abs(sunk_there - sunk) > 1e-9) return;
  }
  const int lobes = 2 + static_cast<int>(rng->Uniform(0, 2));
  for (int k = 0; k < lobes; ++k) {
    Obstacle e;
    e.shape = Obstacle::Shape::kEllipsoid;
    const double scale = k == 0 ? 1.0 : rng->Uniform(0.5, 0.8);
    e.x = x + (k == 0 ? 0 : rng->Uniform(-0.5, 0.5) * height * 1.5);
    e.y = y + (k == 0 ? 0 : rng->Uniform(-0.5, 0.5) * height * 1.5);
    e.yaw_rad = rng->Uniform(0, kPi);
    const double h = height * scale;
    e.c = h / 0.8;  // 80 % of the vertical radius sticks out of the ground
    e.a = h * rng->Uniform(1.1, 1.8);
    e.b = h * rng->Uniform(0.9, 1.4);
    e.z_min = ground + h - 2 * e.c;
    e.z_max = ground + h;
    e.material = Material::kRock;
    s->obstacles.push_back(e);
  }
}

/// Uniform position in [x0, x1] x [-y_max, y_max] outside the corridor |y| < y_free.
Eigen::Vector2d SidePosition(Rng* rng, double x0, double x1, double y_free, double y_max) {
  const double y = rng->Uniform(y_free, y_max) * (rng->Uniform(0, 1) < 0.5 ? -1 : 1);
  return {rng->Uniform(x0, x1), y};
}

Scene MakeYard(std::uint64_t seed) {
  Scene s;
  Rng rng(seed * 7919 + 11);
  s.ground_material = Material::kGravel;
  // Ramps of graded slope (traversable / semi / non with the default vehicle).
  s.ramps.push_back({8.0, 4.6, 0.0, 0.8, 0.6, 0.25, 8.0});
  s.ramps.push_back({8.0, -4.2, 0.3, 0.7, 0.7, 0.45, 18.0});
  s.ramps.push_back({14.0, -0.5, -0.2, 1.0, 1.2, 0.60, 30.0});
  s.Finish();  // the base ground is complete: obstacles below are placed on it
  // Curbs and a step platform of graded height.
  s.obstacles.push_back(MakeBox(4.0, 2.0, 0.0, 0.15, 0.8, 0.05, 0, Material::kConcrete));
  s.obstacles.push_back(MakeBox(4.5, -1.8, 0.1, 0.15, 0.7, 0.15, 0, Material::kConcrete));
  s.obstacles.push_back(MakeBox(12.5, 4.2, 0.0, 1.2, 1.0, 0.30, 0, Material::kBrick));
  // Crates.
  s.obstacles.push_back(MakeBox(8.0, -0.6, 0.4, 0.3, 0.3, 0.5, 0, Material::kWood));
  for (int i = 0; i < 2; ++i) {
    const Eigen::Vector2d p = SidePosition(&rng, 9, 18, 2.0, 6.0);
    s.obstacles.push_back(MakeBox(p.x(), p.y(), rng.Uniform(0, kPi), rng.Uniform(0.2, 0.5),
                                  rng.Uniform(0.2, 0.5), rng.Uniform(0.3, 0.9), 0, Material::kWood));
  }
  // Rocks of several sizes.
  const double heights[] = {0.06, 0.12, 0.18, 0.25, 0.4, 0.08, 0.3};
  for (double h : heights) {
    const Eigen::Vector2d p = SidePosition(&rng, 3.0, 16.0, 1.6, 5.0);
    AddRock(&s, &rng, p.x(), p.y(), h);
  }
  s.clear_run_m = 6.5;  // the crate at x = 8
  return s;
}

Scene MakeHills(std::uint64_t seed) {
  Scene s;
  Rng rng(seed * 104729 + 3);
  s.ground_material = Material::kGrass;
  for (int i = 0; i < 14; ++i) {
    GroundBump b;
    b.x = rng.Uniform(-4, 28);
    b.y = rng.Uniform(-14, 14);
    b.amplitude_m = rng.Uniform(0.3, 1.4) * (rng.Uniform(0, 1) < 0.3 ? -1 : 1);
    // Keep each bump's steepest flank between about 5 and 30 degrees.
    const double max_grad = rng.Uniform(0.1, 0.55);
    b.radius_m = std::max(4.0, std::abs(b.amplitude_m) * 1.717 / max_grad);
    s.bumps.push_back(b);
  }
  // A ditch with vertical walls across the way ahead.
  s.pits.push_back({6.5, 0.5, 0.15, 0.5, 7.0, 0.5});
  s.Finish();
  for (int i = 0; i < 5; ++i) {
    const Eigen::Vector2d p = SidePosition(&rng, 3.0, 18.0, 1.6, 7.0);
    AddRock(&s, &rng, p.x(), p.y(), rng.Uniform(0.05, 0.4));
  }
  s.clear_run_m = 5.5;  // the ditch at x = 6.5
  return s;
}

Scene MakeDropoff(std::uint64_t seed) {
  Scene s;
  Rng rng(seed * 15485863 + 5);
  s.ground_material = Material::kSoil;
  s.bumps.push_back({3.0, 4.0, 0.15, 7.0});
  // The ground ends 6 m ahead: 0.8 m down to a lower level that runs on (seen from ~12 m).
  s.pits.push_back({6.0 + 30.0, 0.0, 0.0, 30.0, 40.0, 0.8});
  // A small hole beside the way.
  s.pits.push_back({4.5, 2.2, 0.3, 0.4, 0.5, 0.3});
  s.Finish();
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector2d p = SidePosition(&rng, 2.5, 5.0, 1.5, 4.0);
    AddRock(&s, &rng, p.x(), p.y(), rng.Uniform(0.05, 0.3));
  }
  for (int i = 0; i < 4; ++i) {  // rocks down below, on the lower level
    const Eigen::Vector2d p = SidePosition(&rng, 12.0, 18.0, 0.0, 6.0);
    AddRock(&s, &rng, p.x(), p.y(), rng.Uniform(0.2, 0.6));
  }
  s.clear_run_m = 5.5;  // the drop at x = 6
  return s;
}

/// A vertical trunk of `radius` standing `height` above the base ground at (x, y).
Obstacle MakeTrunk(const Scene& s, double x, double y, double radius, double height) {
  Obstacle c;
  c.shape = Obstacle::Shape::kCylinder;
  c.x = x;
  c.y = y;
  c.a = radius;
  c.z_min = s.BaseHeight(x, y) - 0.5;
  c.z_max = c.z_min + 0.5 + height;
  c.material = Material::kBark;
  return c;
}

/// A log of `radius` lying along `yaw` on the higher end of the base ground under it.
Obstacle MakeLog(const Scene& s, double x, double y, double yaw, double radius, double half_length) {
  Obstacle g;
  g.shape = Obstacle::Shape::kLog;
  g.x = x;
  g.y = y;
  g.yaw_rad = yaw;
  g.a = radius;
  g.b = half_length;
  const Eigen::Vector2d axis(std::cos(yaw), std::sin(yaw));
  double ground = -kInf;
  for (double u = -1; u <= 1; u += 0.25) {
    ground = std::max(ground, s.BaseHeight(x + u * half_length * axis.x(), y + u * half_length * axis.y()));
  }
  g.z_max = ground + 2 * radius - 0.02;
  g.z_min = g.z_max - 2 * radius;
  g.material = Material::kWood;
  return g;
}

Scene MakeForest(std::uint64_t seed) {
  Scene s;
  Rng rng(seed * 32452843 + 7);
  s.ground_material = Material::kSoil;
  for (int i = 0; i < 6; ++i) {
    s.bumps.push_back({rng.Uniform(0, 25), rng.Uniform(-10, 10), rng.Uniform(-0.2, 0.25),
                       rng.Uniform(5.0, 10.0)});
  }
  s.Finish();
  for (int i = 0; i < 18; ++i) {  // trunks
    const Eigen::Vector2d p = SidePosition(&rng, 2.5, 28.0, 1.3, 11.0);
    const double radius = rng.Uniform(0.1, 0.35);  // before the height: the draw order fixes each seed's scene
    const double height = rng.Uniform(6, 12);
    s.obstacles.push_back(MakeTrunk(s, p.x(), p.y(), radius, height));
  }
  auto add_log = [&](double x, double y, double yaw, double radius, double half_length) {
    s.obstacles.push_back(MakeLog(s, x, y, yaw, radius, half_length));
  };
  add_log(6.5, 0.3, kPi / 2 + 0.15, 0.07, 1.6);  // a thin log across the way (about 0.12 m)
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector2d p = SidePosition(&rng, 4.0, 16.0, 2.7, 7.0);
    add_log(p.x(), p.y(), rng.Uniform(0, kPi), rng.Uniform(0.1, 0.25), rng.Uniform(1.0, 2.2));
  }
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector2d p = SidePosition(&rng, 3.0, 14.0, 1.5, 6.0);
    AddRock(&s, &rng, p.x(), p.y(), rng.Uniform(0.05, 0.3));
  }
  s.clear_run_m = 5.5;  // the log across the way at x = 6.5
  return s;
}

/// The random scene keeps its way ahead clear: for the first kClearRunM metres, within
/// |y| < kCorridorM [m].
constexpr double kClearRunM = 7.0, kCorridorM = 1.5;

/// Uniform position in [x0, x1] x [-y_max, y_max] off the random scene's way ahead: beyond the
/// clear run, or beside the corridor, by at least `keep_off` [m]. Draws until one is.
Eigen::Vector2d PlaceOffWay(Rng* rng, double x0, double x1, double y_max, double keep_off) {
  for (;;) {
    const Eigen::Vector2d p(rng->Uniform(x0, x1), rng->Uniform(-y_max, y_max));
    if (p.x() > kClearRunM + keep_off || std::abs(p.y()) > kCorridorM + keep_off) return p;
  }
}

/// The random scene's base ground: material, tilted plane, rolling slopes and ridges (steepest
/// flanks 3 to 35 deg), and ramps off the way ahead.
void AddRandomGround(Scene* s, Rng* rng) {
  const Material grounds[] = {Material::kGrass, Material::kGravel, Material::kSoil, Material::kConcrete};
  s->ground_material = grounds[static_cast<int>(rng->Uniform(0, 4))];
  const double tilt = DegToRad(rng->Uniform(0, 4)), tilt_dir = rng->Uniform(0, 2 * kPi);
  s->plane_gradient = std::tan(tilt) * Eigen::Vector2d(std::cos(tilt_dir), std::sin(tilt_dir));
  const int bumps = static_cast<int>(rng->Uniform(0, 12));
  for (int i = 0; i < bumps; ++i) {
    GroundBump b;
    b.x = rng->Uniform(-5, 30);
    b.y = rng->Uniform(-15, 15);
    b.amplitude_m = rng->Uniform(0.2, 1.5) * (rng->Uniform(0, 1) < 0.3 ? -1 : 1);
    const double max_grad = std::tan(DegToRad(rng->Uniform(3, 35)));
    b.radius_m = std::max(3.0, std::abs(b.amplitude_m) * 1.717 / max_grad);
    s->bumps.push_back(b);
  }
  const int ramps = static_cast<int>(rng->Uniform(0, 4));
  for (int i = 0; i < ramps; ++i) {
    GroundRamp r;
    const double half = rng->Uniform(0.5, 2.0), height = rng->Uniform(0.2, 1.0);
    r.slope_deg = rng->Uniform(5, 35);
    const double reach = half + height / std::tan(DegToRad(r.slope_deg));
    const Eigen::Vector2d p = PlaceOffWay(rng, 2, 25, 12, reach);
    r.x = p.x();
    r.y = p.y();
    r.yaw_rad = rng->Uniform(0, kPi);
    r.half_x_m = half;
    r.half_y_m = rng->Uniform(0.5, 2.0);
    r.height_m = height;
    s->ramps.push_back(r);
  }
}

/// The random scene's pits: maybe a ditch or trench across the way and a drop-off to a lower
/// level (both beyond the clear run), and holes off the way ahead.
void AddRandomPits(Scene* s, Rng* rng) {
  if (rng->Uniform(0, 1) < 0.5) {  // a ditch or trench across the way, beyond the clear run
    const double width = rng->Uniform(0.4, 1.6);
    s->pits.push_back({kClearRunM + 1.0 + rng->Uniform(0, 8) + width / 2, rng->Uniform(-1, 1), rng->Uniform(-0.3, 0.3),
                       width / 2, rng->Uniform(3, 9), rng->Uniform(0.2, 1.0)});
  }
  if (rng->Uniform(0, 1) < 0.35) {  // a drop-off to a lower level that runs on
    const double edge = kClearRunM + 1.0 + rng->Uniform(0, 10);
    s->pits.push_back({edge + 40.0, 0.0, rng->Uniform(-0.3, 0.3), 40.0, 60.0, rng->Uniform(0.3, 1.5)});
  }
  const int holes = static_cast<int>(rng->Uniform(0, 4));
  for (int i = 0; i < holes; ++i) {
    const double half = rng->Uniform(0.15, 0.6);
    const Eigen::Vector2d p = PlaceOffWay(rng, 2, 20, 8, 1.5 * half);
    s->pits.push_back({p.x(), p.y(), rng->Uniform(0, kPi), half, rng->Uniform(0.15, 0.6), rng->Uniform(0.1, 0.5)});
  }
}

/// The random scene's obstacles off the way ahead, on the finished ground: curbs, terraces,
/// crates, rocks, trunks and logs.
void AddRandomObstacles(Scene* s, Rng* rng) {
  const int curbs = static_cast<int>(rng->Uniform(0, 4));
  for (int i = 0; i < curbs; ++i) {
    const Eigen::Vector2d p = PlaceOffWay(rng, 2, 20, 8, 1.0);
    s->obstacles.push_back(MakeBox(p.x(), p.y(), rng->Uniform(0, kPi), rng->Uniform(0.1, 0.2), rng->Uniform(0.5, 2.0),
                                   rng->Uniform(0.03, 0.3), s->GroundHeight(p.x(), p.y()), Material::kConcrete));
  }
  const int terraces = static_cast<int>(rng->Uniform(0, 3));
  for (int i = 0; i < terraces; ++i) {
    const double half = rng->Uniform(0.8, 2.5);
    const Eigen::Vector2d p = PlaceOffWay(rng, 3, 22, 10, half * 1.5);
    s->obstacles.push_back(MakeBox(p.x(), p.y(), rng->Uniform(0, kPi), half, rng->Uniform(0.8, 2.5),
                                   rng->Uniform(0.15, 0.6), s->GroundHeight(p.x(), p.y()), Material::kBrick));
  }
  const int crates = static_cast<int>(rng->Uniform(0, 6));
  for (int i = 0; i < crates; ++i) {
    const Eigen::Vector2d p = PlaceOffWay(rng, 2, 22, 9, 0.7);
    s->obstacles.push_back(MakeBox(p.x(), p.y(), rng->Uniform(0, kPi), rng->Uniform(0.15, 0.6), rng->Uniform(0.15, 0.6),
                                   rng->Uniform(0.25, 1.2), s->GroundHeight(p.x(), p.y()), Material::kWood));
  }
  const int rocks = static_cast<int>(rng->Uniform(0, 11));
  for (int i = 0; i < rocks; ++i) {
    const double height = rng->Uniform(0.05, 0.5);
    const Eigen::Vector2d p = PlaceOffWay(rng, 2, 22, 9, 2.5 * height + 0.3);
    AddRock(s, rng, p.x(), p.y(), height);
  }
  const int trunks = static_cast<int>(rng->Uniform(0, 16));
  for (int i = 0; i < trunks; ++i) {
    const Eigen::Vector2d p = PlaceOffWay(rng, 2, 28, 12, 0.5);
    s->obstacles.push_back(MakeTrunk(*s, p.x(), p.y(), rng->Uniform(0.08, 0.4), rng->Uniform(4, 12)));
  }
  const int logs = static_cast<int>(rng->Uniform(0, 5));
  for (int i = 0; i < logs; ++i) {
    const double half_length = rng->Uniform(0.8, 2.2);
    const Eigen::Vector2d p = PlaceOffWay(rng, 3, 20, 9, half_length);
    s->obstacles.push_back(MakeLog(*s, p.x(), p.y(), rng->Uniform(0, kPi), rng->Uniform(0.06, 0.3), half_length));
  }
}

/// Terrain composed from the elements of every scene, drawn from `seed`: rolling slopes and
/// ridges, ditches, trenches and a drop-off to a lower level, ramps and terraces, curbs, crates,
/// rocks, trunks and logs. The way ahead (|y| < 1.5 m) stays clear for the first 7 m, so the
/// vehicle path (which follows the base ground only) never meets an obstacle or a pit.
Scene MakeRandom(std::uint64_t seed) {
  Scene s;
  Rng rng(seed * 2654435761ULL + 17);
  AddRandomGround(&s, &rng);
  AddRandomPits(&s, &rng);
  s.Finish();  // the base ground and its pits are complete: objects below are placed on them
  AddRandomObstacles(&s, &rng);
  s.clear_run_m = kClearRunM;
  return s;
}

Scene MakeRamp(double slope_deg) {
  Scene s;
  s.ground_material = Material::kConcrete;
  s.plane_gradient = {std::tan(DegToRad(slope_deg)), 0.0};
  return s;
}

}  // namespace

Scene MakeScene(const std::string& name, std::uint64_t seed, double ramp_slope_deg) {
  Scene s;
  if (name == "yard") {
    s = MakeYard(seed);
  } else if (name == "hills") {
    s = MakeHills(seed);
  } else if (name == "dropoff") {
    s = MakeDropoff(seed);
  } else if (name == "forest") {
    s = MakeForest(seed);
  } else if (name == "random") {
    s = MakeRandom(seed);
  } else if (name == "ramp") {
    if (!(ramp_slope_deg >= 0 && ramp_slope_deg < 60)) {
      throw Error("ramp_slope_deg: must be in [0, 60) degrees");
    }
    s = MakeRamp(ramp_slope_deg);
  } else {
    throw Error("scene: unknown scene '" + name +
                "' (expected one of yard, hills, dropoff, forest, ramp, random)");
  }
  s.name = name;
  s.texture_seed = seed;
  s.Finish();
  return s;
}

void AddTexturelessPatches(Scene* scene, int count, std::uint64_t seed) {
  Rng rng(seed * 49979687 + 13);
  for (int i = 0; i < count; ++i) {
    const double along = rng.Uniform(2.0, 9.0);
    const double across = rng.Uniform(-3.0, 3.0) * along / 6.0;
    const Eigen::Vector2d dir(std::cos(scene->start_yaw_rad), std::sin(scene->start_yaw_rad));
    const Eigen::Vector2d left(-dir.y(), dir.x());
    const Eigen::Vector2d p = scene->start_xy + along * dir + across * left;
    scene->textureless.push_back({p.x(), p.y(), rng.Uniform(0.3, 0.8)});
  }
  scene->Finish();
}

void AddBox(Scene* scene, double x, double y, double yaw_rad, double length_m, double width_m, double height_m) {
  scene->obstacles.push_back(
      MakeBox(x, y, yaw_rad, 0.5 * length_m, 0.5 * width_m, height_m, scene->GroundHeight(x, y), Material::kWood));
  scene->Finish();
}

}  // namespace ssta::synth
