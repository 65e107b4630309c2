#pragma once

#include <cstdint>

#include <Eigen/Geometry>

#include "ssta/core/image.h"
#include "ssta/io/camera_calibration.h"
#include "ssta/synth/scene.h"
#include "ssta/synth/synth_options.h"
#include "ssta/synth/terrain_truth.h"

namespace ssta::synth {

/// One rendered stereo pair with its ground truth, all in the left (cam0) image.
struct StereoFrame {
  ImageU8 left;         ///< cam0 grey image
  ImageU8 right;        ///< cam1 grey image
  ImageU8 labels;       ///< true class ids (TerrainTruth), 255 = don't care
  ImageU8 seen;         ///< 1 where both cameras see a surface point within the label range
  ImageF disparity;     ///< true disparity u_left - u_right [px], 0 where the sky is seen
  ImageF depth;         ///< cam0 z depth [m], 0 where the sky is seen
  ImageU8 occluded;     ///< 1 where the left pixel's surface point is hidden in cam1
};

/// Ray-casts a rectified stereo pair of a Scene. Pixel centres are at integer (u, v) with the
/// principal point at ((w-1)/2, (h-1)/2). Texture is anchored in the world (3D value noise per
/// material, band-limited by distance), shading is Lambert from a sun plus ambient with cast
/// shadows (RenderOptions::shadows), the sky is a textureless vertical gradient. Render is
/// const and spreads image rows over RenderOptions::threads threads.
class StereoRenderer {
 public:
  /// Precondition: the options are valid; `scene` and `truth` outlive the renderer. Without a
  /// truth (null) every label is 255.
  StereoRenderer(const Scene& scene, const RigOptions& rig, const RenderOptions& render, const TerrainTruth* truth,
                 std::uint64_t seed);

  /// Renders the pair seen by cam0 at `world_T_cam0` (cam1 is `baseline_m` along cam0 x).
  /// `frame_index` seeds the sensor noise.
  StereoFrame Render(const Eigen::Isometry3d& world_T_cam0, int frame_index) const;

  /// The true intrinsics of both cameras (T_BS left as identity).
  CameraCalibration Intrinsics() const;

 private:
  const Scene& scene_;
  RigOptions rig_;
  RenderOptions render_;
  const TerrainTruth* truth_;
  std::uint64_t seed_;
};

/// Grey value [0, 255] of a surface point of `material` at `p_world` before shading. The
/// texture has no detail finer than `footprint_m` (the size of a pixel there).
double Albedo(Material material, const Eigen::Vector3d& p_world, double footprint_m,
              std::uint64_t seed);

}  // namespace ssta::synth
