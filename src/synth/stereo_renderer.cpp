#include "ssta/synth/stereo_renderer.h"

#include <algorithm>
#include <cmath>

#include "synth/parallel.h"
#include "synth/random.h"

namespace ssta::synth {
namespace {

/// Hash of an integer lattice point to [-1, 1].
inline double LatticeValue(std::int64_t x, std::int64_t y, std::int64_t z, std::uint64_t seed) {
  std::uint64_t h = seed;
  h = Mix64(h ^ static_cast<std::uint64_t>(x));
  h = Mix64(h ^ static_cast<std::uint64_t>(y));
  h = Mix64(h ^ static_cast<std::uint64_t>(z));
  return static_cast<double>(h >> 11) * (2.0 / 9007199254740992.0) - 1.0;
}

/// Smooth 3D value noise in [-1, 1], one lattice cell per unit.
double ValueNoise(const Eigen::Vector3d& p, std::uint64_t seed) {
  const double fx = std::floor(p.x()), fy = std::floor(p.y()), fz = std::floor(p.z());
  const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy),
             iz = static_cast<std::int64_t>(fz);
  auto smooth = [](double t) { return t * t * (3 - 2 * t); };
  const double sx = smooth(p.x() - fx), sy = smooth(p.y() - fy), sz = smooth(p.z() - fz);
  double c[2][2];
  for (int dz = 0; dz < 2; ++dz) {
    for (int dy = 0; dy < 2; ++dy) {
      const double a = LatticeValue(ix, iy + dy, iz + dz, seed);
      const double b = LatticeValue(ix + 1, iy + dy, iz + dz, seed);
      c[dz][dy] = a + (b - a) * sx;
    }
  }
  const double y0 = c[0][0] + (c[0][1] - c[0][0]) * sy;
  const double y1 = c[1][0] + (c[1][1] - c[1][0]) * sy;
  return y0 + (y1 - y0) * sz;
}

struct MaterialLook {
  double mean;       ///< average grey
  double contrast;   ///< grey amplitude of the noise
  double frequency;  ///< lowest octave [cycles/m]
};

MaterialLook LookOf(Material m) {
  switch (m) {
    case Material::kGrass: return {100, 60, 3.0};
    case Material::kGravel: return {128, 65, 4.0};
    case Material::kConcrete: return {150, 60, 2.5};
    case Material::kSoil: return {110, 60, 3.0};
    case Material::kRock: return {125, 70, 3.5};
    case Material::kBark: return {80, 55, 5.0};
    case Material::kWood: return {140, 50, 4.0};
    case Material::kBrick: return {150, 55, 3.0};
    case Material::kTextureless: return {140, 0, 1.0};
  }
  return {128, 50, 2.0};
}

constexpr int kOctaves = 8;

}  // namespace

double Albedo(Material material, const Eigen::Vector3d& p_world, double footprint_m,
              std::uint64_t seed) {
  const MaterialLook look = LookOf(material);
  if (look.contrast <= 0) return look.mean;
  const std::uint64_t mseed = Mix64(seed * 131 + static_cast<std::uint64_t>(material));
  double sum = 0, amplitude = 1, norm = 0;
  double frequency = look.frequency;
  for (int k = 0; k < kOctaves; ++k) {
    // Band limit: fade an octave out as its wavelength shrinks from 4 to 2 pixel footprints.
    const double cycles_per_pixel = frequency * footprint_m;
    const double weight = std::clamp((0.5 - cycles_per_pixel) / 0.25, 0.0, 1.0);
    norm += amplitude;
    if (weight <= 0) break;
    sum += weight * amplitude * ValueNoise(p_world * frequency, mseed + static_cast<std::uint64_t>(k));
    amplitude *= 0.85;
    frequency *= 2.03;
  }
  return look.mean + look.contrast * 2.2 * sum / norm;
}

StereoRenderer::StereoRenderer(const Scene& scene, const RigOptions& rig, const RenderOptions& render,
                               const TerrainTruth* truth, std::uint64_t seed)
    : scene_(scene), rig_(rig), render_(render), truth_(truth), seed_(seed) {}

CameraCalibration StereoRenderer::Intrinsics() const {
  CameraCalibration c;
  c.width = rig_.width;
  c.height = rig_.height;
  c.fu = c.fv = rig_.focal_px;
  c.cu = 0.5 * (rig_.width - 1);
  c.cv = 0.5 * (rig_.height - 1);
  c.rate_hz = rig_.rate_hz;
  return c;
}

namespace {

constexpr double kShadowRayM = 60.0;  ///< occluders farther towards the sun are ignored

double SkyGrey(const Eigen::Vector3d& d, const RenderOptions& render) {
  const double elevation = d.z() / d.norm();
  return render.sky_grey + 50.0 * std::clamp(elevation, 0.0, 1.0);
}

/// Grey value of a hit seen along `d`: textured albedo times ambient plus sun (Lambert), the
/// sun blocked when `shadows` and the way to it is not free.
double ShadeHit(const Scene& scene, const SurfaceHit& hit, const Eigen::Vector3d& d, double footprint_m,
                const RenderOptions& render) {
  // A pixel's footprint stretches by 1 / incidence along the view direction but not across
  // it; the geometric mean keeps detail along image rows (what stereo matches) at grazing
  // angles while still limiting aliasing down the columns.
  const double incidence = std::max(0.05, std::abs(hit.normal_world.dot(d)) / d.norm());
  const double albedo =
      Albedo(hit.material, hit.p_world, footprint_m / std::sqrt(incidence), scene.texture_seed);
  const Eigen::Vector3d towards_sun = render.sun_direction.normalized();
  const double sun = std::max(0.0, hit.normal_world.dot(towards_sun));
  const bool lit = sun > 0 && !(render.shadows && scene.CastRay(hit.p_world + 2e-3 * hit.normal_world,
                                                                 towards_sun, kShadowRayM).hit);
  return albedo * (render.ambient + (lit ? render.sun_gain * sun : 0.0));
}

}  // namespace

double StereoRenderer::Shade(const Eigen::Isometry3d& world_T_camera, double u, double v) const {
  const double cu = 0.5 * (rig_.width - 1), cv = 0.5 * (rig_.height - 1);
  const Eigen::Vector3d d =
      world_T_camera.linear() * Eigen::Vector3d((u - cu) / rig_.focal_px, (v - cv) / rig_.focal_px, 1);
  const double t_max = render_.max_ray_m / d.norm();
  const SurfaceHit hit = scene_.CastRay(world_T_camera.translation(), d, t_max);
  if (!hit.hit) return SkyGrey(d, render_);
  return ShadeHit(scene_, hit, d, hit.t / rig_.focal_px, render_);
}

StereoFrame StereoRenderer::Render(const Eigen::Isometry3d& world_T_cam0, int frame_index) const {
  const int w = rig_.width, h = rig_.height;
  const double f = rig_.focal_px, cu = 0.5 * (w - 1), cv = 0.5 * (h - 1);
  const Eigen::Isometry3d world_T_cam1 =
      world_T_cam0 * Eigen::Translation3d(rig_.baseline_m, 0, 0);
  StereoFrame out;
  out.left = ImageU8(w, h);
  out.right = ImageU8(w, h);
  out.labels = ImageU8(w, h, kDontCare);
  out.disparity = ImageF(w, h, 0.f);
  out.depth = ImageF(w, h, 0.f);
  out.occluded = ImageU8(w, h, 0);
  ImageU8 raw_class(w, h, kDontCare);
  ImageF right_depth(w, h, 0.f);
  const int ss = render_.supersample;

  for (int cam = 0; cam < 2; ++cam) {
    const Eigen::Isometry3d& world_T_cam = cam == 0 ? world_T_cam0 : world_T_cam1;
    const Eigen::Vector3d origin = world_T_cam.translation();
    const Eigen::Matrix3d r = world_T_cam.linear();
    ImageU8& image = cam == 0 ? out.left : out.right;
    ParallelFor(h, render_.threads, [&](int v) {
      // One noise stream per row keeps the bytes independent of the thread count.
      Rng noise(Mix64(Mix64(seed_ * 1000003 + static_cast<std::uint64_t>(frame_index) * 2 + cam) + v));
      for (int u = 0; u < w; ++u) {
        const Eigen::Vector3d d = r * Eigen::Vector3d((u - cu) / f, (v - cv) / f, 1);
        const double t_max = render_.max_ray_m / d.norm();
        const SurfaceHit hit = scene_.CastRay(origin, d, t_max);
        double grey;
        if (ss > 1) {
          grey = 0;
          for (int j = 0; j < ss; ++j) {
            for (int i = 0; i < ss; ++i) {
              grey += Shade(world_T_cam, u + (i + 0.5) / ss - 0.5, v + (j + 0.5) / ss - 0.5);
            }
          }
          grey /= ss * ss;
        } else {
          grey = hit.hit ? ShadeHit(scene_, hit, d, hit.t / f, render_) : SkyGrey(d, render_);
        }
        grey += render_.sensor_noise_grey * noise.Gaussian();
        image(v, u) = static_cast<std::uint8_t>(std::clamp(std::lround(grey), 0L, 255L));
        if (!hit.hit) continue;
        if (cam == 1) {
          right_depth(v, u) = static_cast<float>(hit.t);
          continue;
        }
        out.depth(v, u) = static_cast<float>(hit.t);
        out.disparity(v, u) = static_cast<float>(f * rig_.baseline_m / hit.t);
        if (truth_ != nullptr && hit.t * d.norm() <= render_.max_label_range_m) raw_class(v, u) = truth_->ClassOf(hit);
      }
    });
  }

  // Occlusion: the left point must be what cam1 sees at u - d (rectified, same row and depth).
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const float z = out.depth(v, u);
      if (z <= 0) continue;
      const double ur = u - out.disparity(v, u);
      const int u0 = static_cast<int>(std::floor(ur));
      bool visible = false;
      for (int uu = u0; uu <= u0 + 1; ++uu) {
        if (uu < 0 || uu >= w) continue;
        const float zr = right_depth(v, uu);
        if (zr > 0 && zr > z * 0.97f - 0.01f) visible = true;
      }
      if (!visible) out.occluded(v, u) = 1;
    }
  }

  // Labels: the raw class, except where a different class lies within the boundary band.
  const int band = render_.boundary_band_px;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const std::uint8_t c = raw_class(v, u);
      if (c == kDontCare || out.occluded(v, u)) continue;
      bool mixed = false;
      for (int dv = -band; dv <= band && !mixed; ++dv) {
        for (int du = -band; du <= band; ++du) {
          if (!raw_class.Contains(v + dv, u + du)) continue;
          const std::uint8_t n = raw_class(v + dv, u + du);
          if (n != kDontCare && n != c) {
            mixed = true;
            break;
          }
        }
      }
      if (!mixed) out.labels(v, u) = c;
    }
  }
  return out;
}

}  // namespace ssta::synth
