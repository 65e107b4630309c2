#pragma once

// Hand-built worlds for the mapping tests, with answers known by construction.

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "mapping/map_impl.h"
#include "ssta/mapping/traversability_map.h"

namespace ssta::testing {

/// The class evidence of the plain log-odds model: the plurality of a voxel's points is the
/// frame's vote, every vote counts alike (no obstacle gain, no noise weighting), there is no
/// prior for open ground and any nonzero evidence is a verdict. The tests that check its formulas use it;
/// safe_fusion_test.cpp checks what the shipped weighting adds.
inline MapOptions PlainVotes(MapOptions o = MapOptions{}) {
  o.class_worst_share = 0.0;
  o.class_obstacle_gain = 1.0;
  o.class_vote_noise_steps = 0.0;
  o.class_vote_smear_radii = 0.0;
  o.class_prior_traversable_log_odds = 0.0;
  o.class_min_evidence_views = 0.0;
  return o;
}

/// OctoMap's plain sensor model, which these tests are written against: every ray carves to its
/// endpoint (no clearance, no shortening before obstacles, traversable voxels not spared), a
/// voxel is occupied from P 0.5, the class evidence decays by 0.4 per passing ray, and votes
/// count as PlainVotes.
inline MapOptions OctoMapCarving() {
  MapOptions o = PlainVotes();
  o.max_range_m = 15.0;
  o.occupancy_miss_prob = 0.4;
  o.occupied_threshold_prob = 0.5;
  o.class_free_decay_log_odds = 0.4;
  o.free_space_clearance_m = 0.0;
  o.free_space_obstacle_shortening_per_m2 = -1.0;
  o.free_space_keeps_traversable = false;
  return o;
}

inline ClassifiedPoint Pt(double x, double y, double z, TravClass cls, float slope_deg = 0.0f,
                          float step_m = 0.0f) {
  ClassifiedPoint p;
  p.world_p = Eigen::Vector3f(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
  p.cls = cls;
  p.slope_deg = slope_deg;
  p.step_m = step_m;
  return p;
}

/// Voxel centre along one axis for index i at 0.1 m: 0.05 + 0.1 i.
inline double C(int i) { return 0.05 + 0.1 * i; }

/// The box of the floor-and-box world: columns x, y in [1.0, 1.3), voxels z in [0, 0.3).
inline bool InBoxColumn(int ix, int iy) { return ix >= 10 && ix < 13 && iy >= 10 && iy < 13; }

/// A flat traversable floor, one voxel thick at z in [0, 0.1), over x in [0, 3) and y in
/// [0, 2.5) at 0.1 m, with a 0.3 m cube of non-traversable voxels on x, y in [1.0, 1.3)
/// (no floor under it: a camera cannot see there). One point per voxel centre.
inline std::vector<ClassifiedPoint> FloorAndBox() {
  std::vector<ClassifiedPoint> points;
  for (int ix = 0; ix < 30; ++ix) {
    for (int iy = 0; iy < 25; ++iy) {
      if (InBoxColumn(ix, iy)) {
        for (int iz = 0; iz < 3; ++iz) {
          points.push_back(Pt(C(ix), C(iy), C(iz), TravClass::kNonTraversable, 80.0f, 0.3f));
        }
      } else {
        points.push_back(Pt(C(ix), C(iy), C(0), TravClass::kTraversable, 2.0f, 0.01f));
      }
    }
  }
  return points;
}

/// Sensor origin high above the middle of the floor-and-box world.
inline Eigen::Vector3d FloorAndBoxOrigin() { return {1.5, 1.25, 3.0}; }

inline TraversabilityMap FloorAndBoxMap() {
  TraversabilityMap map(OctoMapCarving());
  map.InsertFrame(FloorAndBox(), FloorAndBoxOrigin(), 1000);
  return map;
}

/// The vehicle of the heading tests: the limits, 25 deg climb and descent, 15 deg roll.
inline VehicleOptions HillsideVehicle() {
  VehicleOptions v;
  v.max_pitch_deg = 25.0;
  v.max_descent_deg = 25.0;
  v.max_roll_deg = 15.0;
  return v;
}

/// A hillside rising along +x at `slope_deg`, z = tan(slope) x, over x, y in [0, 4) m: one point
/// per 0.1 m column at its centre's height with a 1 cm height sigma (so the fused surface heights
/// lie on the plane), seen once from above, for a map of `vehicle`.
inline TraversabilityMap HillsideMap(double slope_deg, const VehicleOptions& vehicle) {
  std::vector<ClassifiedPoint> points;
  const double gradient = std::tan(slope_deg * 3.14159265358979323846 / 180.0);
  for (int ix = 0; ix < 40; ++ix) {
    for (int iy = 0; iy < 40; ++iy) {
      ClassifiedPoint p = Pt(C(ix), C(iy), gradient * C(ix), TravClass::kSemiTraversable, static_cast<float>(slope_deg));
      p.height_sigma_m = 0.01f;
      p.horizontal_sigma_m = 0.01f;
      points.push_back(p);
    }
  }
  MapOptions options;
  options.max_range_m = 30.0;
  options.occupied_threshold_prob = 0.5;  // one frame's hit makes a voxel occupied
  MapMetadata metadata;
  metadata.vehicle = vehicle;
  TraversabilityMap map(options, metadata);
  map.InsertFrame(points, {2.0, 2.0, 15.0}, 1);
  return map;
}

/// Softmax probability of class index `c` given float class log-odds.
inline double Softmax(const std::array<float, 3>& l, int c) {
  double d = 0.0;
  for (float v : l) d += std::exp(static_cast<double>(v));
  return std::exp(static_cast<double>(l[c])) / d;
}

/// The internal octree of a map.
inline const internal::TravOcTree& Tree(const TraversabilityMap& map) {
  return internal::TraversabilityMapAccess::Tree(map);
}

/// The leaf node holding `p` (null when unobserved).
inline const internal::TravNode* NodeAt(const TraversabilityMap& map, const Eigen::Vector3d& p) {
  return Tree(map).search(p.x(), p.y(), p.z());
}

}  // namespace ssta::testing
