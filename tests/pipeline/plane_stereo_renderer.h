#pragma once

// Renders a rectified stereo pair of a textured plane by casting each pixel's ray against the
// plane analytically. The texture is anchored on the plane, so both views see the same surface.

#include <cmath>
#include <cstdint>

#include <Eigen/Geometry>

#include "ssta/core/image.h"

namespace ssta::testing {

struct PlaneScene {
  int width = 320, height = 240;
  double f = 300.0, cu = 160.0, cv = 120.0, baseline_m = 0.12;
  double camera_height_m = 1.0;  ///< above the plane, along world up, at the camera position
  double pitch_deg = 15.0;       ///< camera pitched down
  double slope_deg = 12.0;       ///< plane rises away from the camera at this angle

  /// World up in the camera frame (x right, y down, z forward).
  Eigen::Vector3d UpCamera() const {
    const double t = pitch_deg * M_PI / 180.0;
    return {0.0, -std::cos(t), -std::sin(t)};
  }
  /// Plane normal (pointing up) in the camera frame.
  Eigen::Vector3d NormalCamera() const {
    const double s = (pitch_deg + slope_deg) * M_PI / 180.0;
    return {0.0, -std::cos(s), -std::sin(s)};
  }
};

inline double Hash(int x, int y) {
  std::uint32_t h = static_cast<std::uint32_t>(x) * 374761393u + static_cast<std::uint32_t>(y) * 668265263u;
  h = (h ^ (h >> 13)) * 1274126177u;
  return ((h ^ (h >> 16)) & 0xffff) / 65535.0;
}

inline double ValueNoise(double s, double t) {
  const int i = static_cast<int>(std::floor(s)), j = static_cast<int>(std::floor(t));
  const double fs = s - i, ft = t - j;
  const double a = Hash(i, j), b = Hash(i + 1, j), c = Hash(i, j + 1), d = Hash(i + 1, j + 1);
  const double ss = fs * fs * (3 - 2 * fs), tt = ft * ft * (3 - 2 * ft);
  return (a * (1 - ss) + b * ss) * (1 - tt) + (c * (1 - ss) + d * ss) * tt;
}

inline double Texture(double s, double t) {
  double sum = 0, amp = 1, freq = 8.0, norm = 0;  // finest features ~ 1.5 cm
  for (int octave = 0; octave < 4; ++octave) {
    sum += amp * ValueNoise(s * freq, t * freq);
    norm += amp;
    amp *= 0.5;
    freq *= 2.1;
  }
  return sum / norm;
}

/// Renders the view of a camera at `camera_x` (metres along camera x) of the scene's plane.
inline ImageU8 RenderPlane(const PlaneScene& scene, double camera_x) {
  const Eigen::Vector3d n = scene.NormalCamera();
  const double d_plane = scene.camera_height_m * std::cos(scene.slope_deg * M_PI / 180.0);  // n.p + D = 0
  const Eigen::Vector3d a = Eigen::Vector3d::UnitX();
  const Eigen::Vector3d b = n.cross(a).normalized();
  ImageU8 image(scene.width, scene.height, 0);
  for (int v = 0; v < scene.height; ++v) {
    for (int u = 0; u < scene.width; ++u) {
      const Eigen::Vector3d origin(camera_x, 0, 0);
      const Eigen::Vector3d ray((u - scene.cu) / scene.f, (v - scene.cv) / scene.f, 1.0);
      const double denom = n.dot(ray);
      if (denom >= -1e-9) {
        image(v, u) = 200;  // sky: no intersection in front of the camera
        continue;
      }
      const double t = -(n.dot(origin) + d_plane) / denom;
      const Eigen::Vector3d p = origin + t * ray;
      image(v, u) = static_cast<std::uint8_t>(std::lround(30 + 190 * Texture(p.dot(a), p.dot(b))));
    }
  }
  return image;
}

}  // namespace ssta::testing
