#pragma once

#include <functional>
#include <vector>

#include <Eigen/Core>

#include "ssta/core/image.h"
#include "ssta/geometry/normal_estimator.h"
#include "ssta/geometry/segmenter.h"

namespace ssta::test {

/// A rectified pinhole camera at the origin of its frame (x right, y down, z forward).
struct PinholeCamera {
  int width = 640;
  int height = 480;
  double f_px = 450.0;
  double cu_px = 319.5;
  double cv_px = 239.5;
  double baseline_m = 0.12;
  /// Viewing direction of pixel (v, u), with z = 1.
  Eigen::Vector3d Ray(int v, int u) const { return {(u - cu_px) / f_px, (v - cv_px) / f_px, 1.0}; }
};

/// An analytic world of planes and boxes in the camera frame; renders organized clouds by
/// casting one ray per pixel and keeping the nearest hit.
class Scene {
 public:
  /// Plane n . p + d = 0, kept where `keep(p)` holds (all of it when keep is empty).
  void AddPlane(const Eigen::Vector3d& n, double d,
                std::function<bool(const Eigen::Vector3d&)> keep = {});
  /// Axis-aligned box [min, max] in the camera frame.
  void AddBox(const Eigen::Vector3d& min, const Eigen::Vector3d& max);

  /// Organized cloud: nearest hit per pixel with Z <= max_range_m, NaN elsewhere. When
  /// `normals` is not null it receives the true unit normal towards the camera per pixel.
  Image3f Render(const PinholeCamera& camera, Image3f* normals = nullptr,
                 double max_range_m = 30.0) const;

 private:
  struct Plane {
    Eigen::Vector3d n;
    double d;
    std::function<bool(const Eigen::Vector3d&)> keep;
  };
  struct Box {
    Eigen::Vector3d min, max;
  };
  std::vector<Plane> planes_;
  std::vector<Box> boxes_;
};

/// Horizontal ground plane `height_m` below the camera (y = +height_m, camera looking level).
Scene GroundScene(double height_m);

/// Disparity f * b / Z of each valid point, 0 where invalid.
ImageF DisparityOf(const Image3f& cloud, const PinholeCamera& camera);

/// Moves each valid point along its ray by Gaussian noise with sigma = k * Z^2 [m] (stereo:
/// constant disparity noise k * f * b px). Deterministic for a given seed.
void AddDepthNoise(double k_per_m, unsigned seed, Image3f* cloud);

/// Angle between two vectors [deg] (NaN if either is not finite).
double AngleDeg(const Eigen::Vector3f& a, const Eigen::Vector3f& b);

/// Normals over a fixed 13 px window, the scale of the analytic worlds these tests render.
inline NormalOptions FixedWindow13() {
  NormalOptions options;
  options.smoothing_size_px = 13;
  options.depth_dependent_smoothing = false;
  options.subsample = 1;  // a normal per pixel: the tests compare each pixel's window
  return options;
}

/// Segmentation by neighbouring normals alone (eq. 1) within `roughness_deg`, with the
/// disparity test and without the segment-angle test.
inline SegmenterOptions NeighbourNormals(double roughness_deg = 2.0) {
  SegmenterOptions options;
  options.roughness_deg = roughness_deg;
  options.max_segment_angle_deg = 0.0;
  return options;
}

}  // namespace ssta::test
