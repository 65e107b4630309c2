#include "geometry/synthetic_scene.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include <Eigen/Geometry>

namespace ssta::test {

void Scene::AddPlane(const Eigen::Vector3d& n, double d,
                     std::function<bool(const Eigen::Vector3d&)> keep) {
  planes_.push_back({n.normalized(), d / n.norm(), std::move(keep)});
}

void Scene::AddBox(const Eigen::Vector3d& min, const Eigen::Vector3d& max) {
  boxes_.push_back({min, max});
}

Image3f Scene::Render(const PinholeCamera& camera, Image3f* normals, double max_range_m) const {
  Image3f cloud(camera.width, camera.height, NanVector3f());
  if (normals) *normals = Image3f(camera.width, camera.height, NanVector3f());
  constexpr double kInf = std::numeric_limits<double>::infinity();
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      const Eigen::Vector3d ray = camera.Ray(v, u);
      double best_t = kInf;
      Eigen::Vector3d best_n = Eigen::Vector3d::Zero();
      for (const Plane& plane : planes_) {
        const double denom = plane.n.dot(ray);
        if (std::abs(denom) < 1e-12) continue;
        const double t = -plane.d / denom;
        if (!(t > 0.0) || t >= best_t) continue;
        if (plane.keep && !plane.keep(t * ray)) continue;
        best_t = t;
        best_n = plane.n;
      }
      for (const Box& box : boxes_) {
        // Slab method: entry parameter and the axis of the entry face.
        double t_near = -kInf, t_far = kInf;
        int axis = -1;
        double side = 0.0;
        bool miss = false;
        for (int k = 0; k < 3; ++k) {
          if (std::abs(ray[k]) < 1e-12) {
            if (0.0 < box.min[k] || 0.0 > box.max[k]) miss = true;
            continue;
          }
          double t0 = box.min[k] / ray[k], t1 = box.max[k] / ray[k];
          double s = -1.0;  // entering through the min face: outward normal -axis
          if (t0 > t1) {
            std::swap(t0, t1);
            s = 1.0;
          }
          if (t0 > t_near) {
            t_near = t0;
            axis = k;
            side = s;
          }
          t_far = std::min(t_far, t1);
        }
        if (miss || axis < 0 || t_near > t_far || !(t_near > 0.0) || t_near >= best_t) continue;
        best_t = t_near;
        best_n = Eigen::Vector3d::Zero();
        best_n[axis] = side;
      }
      if (best_t == kInf) continue;
      const Eigen::Vector3d p = best_t * ray;
      if (p.z() > max_range_m) continue;
      cloud(v, u) = p.cast<float>();
      if (normals) {
        const Eigen::Vector3d n = best_n.dot(p) > 0.0 ? -best_n : best_n;
        (*normals)(v, u) = n.cast<float>();
      }
    }
  }
  return cloud;
}

Scene GroundScene(double height_m) {
  Scene scene;
  scene.AddPlane({0.0, 1.0, 0.0}, -height_m);
  return scene;
}

ImageF DisparityOf(const Image3f& cloud, const PinholeCamera& camera) {
  ImageF disparity(cloud.width(), cloud.height(), 0.0f);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (IsFinite(cloud[i])) {
      disparity[i] = static_cast<float>(camera.f_px * camera.baseline_m / cloud[i].z());
    }
  }
  return disparity;
}

void AddDepthNoise(double k_per_m, unsigned seed, Image3f* cloud) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (std::size_t i = 0; i < cloud->size(); ++i) {
    Eigen::Vector3f& p = (*cloud)[i];
    if (!IsFinite(p)) continue;
    const double z = p.z();
    const double noisy_z = z + k_per_m * z * z * normal(rng);
    p *= static_cast<float>(noisy_z / z);
  }
}

double AngleDeg(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
  if (!IsFinite(a) || !IsFinite(b)) return std::numeric_limits<double>::quiet_NaN();
  const double c = a.cast<double>().normalized().dot(b.cast<double>().normalized());
  return std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / 3.14159265358979323846;
}

}  // namespace ssta::test
