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

/// Grey value seen through image point (u, v) [px] of a camera at `world_T_camera`.
double ShadeThrough(const Scene& scene, const RigOptions& rig, const RenderOptions& render,
                    const Eigen::Isometry3d& world_T_camera, double u, double v) {
  const double cu = 0.5 * (rig.width - 1), cv = 0.5 * (rig.height - 1);
  const Eigen::Vector3d d =
      world_T_camera.linear() * Eigen::Vector3d((u - cu) / rig.focal_px, (v - cv) / rig.focal_px, 1);
  const double t_max = render.max_ray_m / d.norm();
  const SurfaceHit hit = scene.CastRay(world_T_camera.translation(), d, t_max);
  if (!hit.hit) return SkyGrey(d, render);
  return ShadeHit(scene, hit, d, hit.t / rig.focal_px, render);
}

/// What a camera's pass reads: the renderer's scene, options, truth (may be null) and seed.
struct RenderInputs {
  const Scene& scene;
  const RigOptions& rig;
  const RenderOptions& render;
  const TerrainTruth* truth;
  std::uint64_t seed;
};

/// Where a camera's pass writes: its grey image and the z depth of each hit [m]; cam0's pass
/// also the disparity [px] and the raw true class of each hit within the label range.
struct CameraTargets {
  ImageU8* image;
  ImageF* depth;
  ImageF* disparity;   ///< cam0 only
  ImageU8* raw_class;  ///< cam0 only
};

/// Grey value of pixel (u, v) before the sensor noise: the mean over ss x ss subpixel rays
/// (RenderOptions::supersample > 1), else the shade of `hit`, seen along the pixel's ray `d`.
double PixelGrey(const RenderInputs& in, const Eigen::Isometry3d& world_T_cam, int u, int v, const SurfaceHit& hit,
                 const Eigen::Vector3d& d) {
  const int ss = in.render.supersample;
  if (ss <= 1) return hit.hit ? ShadeHit(in.scene, hit, d, hit.t / in.rig.focal_px, in.render) : SkyGrey(d, in.render);
  double grey = 0;
  for (int j = 0; j < ss; ++j) {
    for (int i = 0; i < ss; ++i) {
      grey += ShadeThrough(in.scene, in.rig, in.render, world_T_cam, u + (i + 0.5) / ss - 0.5, v + (j + 0.5) / ss - 0.5);
    }
  }
  grey /= ss * ss;
  return grey;
}

/// Renders camera `cam` (0 left, 1 right) at `world_T_cam` into `targets`, rows spread over the
/// threads; the sensor noise is seeded per frame, camera and row.
void RenderCamera(const RenderInputs& in, const Eigen::Isometry3d& world_T_cam, int frame_index, int cam,
                  const CameraTargets& targets) {
  const int w = in.rig.width, h = in.rig.height;
  const double f = in.rig.focal_px, cu = 0.5 * (w - 1), cv = 0.5 * (h - 1);
  const Eigen::Vector3d origin = world_T_cam.translation();
  const Eigen::Matrix3d r = world_T_cam.linear();
  ParallelFor(h, in.render.threads, [&](int v) {
    // One noise stream per row keeps the bytes independent of the thread count.
    Rng noise(Mix64(Mix64(in.seed * 1000003 + static_cast<std::uint64_t>(frame_index) * 2 + cam) + v));
    for (int u = 0; u < w; ++u) {
      const Eigen::Vector3d d = r * Eigen::Vector3d((u - cu) / f, (v - cv) / f, 1);
      const double t_max = in.render.max_ray_m / d.norm();
      const SurfaceHit hit = in.scene.CastRay(origin, d, t_max);
      double grey = PixelGrey(in, world_T_cam, u, v, hit, d);
      grey += in.render.sensor_noise_grey * noise.Gaussian();
      (*targets.image)(v, u) = static_cast<std::uint8_t>(std::clamp(std::lround(grey), 0L, 255L));
      if (!hit.hit) continue;
      (*targets.depth)(v, u) = static_cast<float>(hit.t);
      if (cam == 1) continue;
      (*targets.disparity)(v, u) = static_cast<float>(f * in.rig.baseline_m / hit.t);
      if (in.truth != nullptr && hit.t * d.norm() <= in.render.max_label_range_m) {
        (*targets.raw_class)(v, u) = in.truth->ClassOf(hit);
      }
    }
  });
}

/// Marks the left pixels whose surface point cam1 does not see: cam1 must see it at u - d
/// (rectified, same row and depth) in `right_depth` [m].
void MarkOccluded(const ImageF& right_depth, StereoFrame* frame) {
  const int w = frame->depth.width(), h = frame->depth.height();
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const float z = frame->depth(v, u);
      if (z <= 0) continue;
      const double ur = u - frame->disparity(v, u);
      const int u0 = static_cast<int>(std::floor(ur));
      bool visible = false;
      for (int uu = u0; uu <= u0 + 1; ++uu) {
        if (uu < 0 || uu >= w) continue;
        const float zr = right_depth(v, uu);
        if (zr > 0 && zr > z * 0.97f - 0.01f) visible = true;
      }
      if (!visible) frame->occluded(v, u) = 1;
    }
  }
}

/// The labels: the raw class, except where a different class lies within `band` pixels, and
/// 255 (don't care) where the pixel is occluded in cam1.
ImageU8 BandLabels(const ImageU8& raw_class, const ImageU8& occluded, int band) {
  const int w = raw_class.width(), h = raw_class.height();
  ImageU8 labels(w, h, kDontCare);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const std::uint8_t c = raw_class(v, u);
      if (c == kDontCare || occluded(v, u)) continue;
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
      if (!mixed) labels(v, u) = c;
    }
  }
  return labels;
}

}  // namespace

StereoFrame StereoRenderer::Render(const Eigen::Isometry3d& world_T_cam0, int frame_index) const {
  const int w = rig_.width, h = rig_.height;
  const Eigen::Isometry3d world_T_cam1 =
      world_T_cam0 * Eigen::Translation3d(rig_.baseline_m, 0, 0);
  StereoFrame out;
  out.left = ImageU8(w, h);
  out.right = ImageU8(w, h);
  out.disparity = ImageF(w, h, 0.f);
  out.depth = ImageF(w, h, 0.f);
  out.occluded = ImageU8(w, h, 0);
  ImageU8 raw_class(w, h, kDontCare);
  ImageF right_depth(w, h, 0.f);

  const RenderInputs in{scene_, rig_, render_, truth_, seed_};
  RenderCamera(in, world_T_cam0, frame_index, 0, {&out.left, &out.depth, &out.disparity, &raw_class});
  RenderCamera(in, world_T_cam1, frame_index, 1, {&out.right, &right_depth, nullptr, nullptr});
  MarkOccluded(right_depth, &out);
  out.labels = BandLabels(raw_class, out.occluded, render_.boundary_band_px);
  out.seen = ImageU8(w, h, 0);
  for (std::size_t i = 0; i < out.seen.size(); ++i) out.seen[i] = raw_class[i] != kDontCare && !out.occluded[i];
  return out;
}

}  // namespace ssta::synth
