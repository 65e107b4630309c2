#pragma once

#include <string>

#include <Eigen/Core>

#include "ssta/analysis/surface_analyzer.h"
#include "ssta/analysis/vehicle_options.h"
#include "ssta/geometry/normal_estimator.h"
#include "ssta/pipeline/attitude_filter.h"
#include "ssta/geometry/segmenter.h"
#include "ssta/mapping/map_options.h"
#include "ssta/refinement/refinement_options.h"
#include "ssta/stereo/rectifier.h"
#include "ssta/stereo/stereo_matcher.h"
#include "ssta/stereo/triangulator.h"

namespace ssta {

/// Where each frame's gravity (up direction) comes from (YAML `gravity.source`).
enum class GravitySource {
  kAuto,   ///< "auto": the IMU when it has samples around the frame, else the pose, else level
  kImu,    ///< "imu": mean accelerometer reading around the frame (platform at rest or cruising)
  kPose,   ///< "pose": the attitude of pose0 (or EuRoC's ground truth) at the frame
  kLevel,  ///< "level": the body is level, up = body z; the camera tilt comes from cam0's T_BS
  kFixed,  ///< "fixed": `up_camera` as given, in the original cam0 frame
};

/// YAML section `gravity`.
struct GravityOptions {
  GravitySource source = GravitySource::kAuto;
  Eigen::Vector3d up_camera{0.0, -1.0, 0.0};  ///< for source "fixed": up in cam0 (y down)
  bool IsValid(std::string* error) const;
};

/// The map's fusion defaults for stereo: hits only within 12 m (farther stereo points are too
/// noisy to classify), a voxel counts as occupied from 2 hits (P >= 0.8), so one stray point
/// does not become a column's top surface, and free space is carved gently (P 0.45 per ray),
/// because rays to far ground graze the voxels of nearer ground and would clear them.
MapOptions PipelineMapDefaults();

/// YAML section `map`: how frames are fused into a TraversabilityMap.
struct MappingOptions {
  MapOptions fusion = PipelineMapDefaults();  ///< voxel size, range and the log-odds sensor model
  int pixel_stride = 1;         ///< insert every n-th pixel in u and v (the map thins per voxel)
  /// Pixels whose left-image grey-level standard deviation over the stereo block is below this
  /// are not inserted (sky and blank areas: matching noise); 0: off. Unlike stereo.min_texture
  /// it leaves the per-frame classification as it is. In [0, 128).
  double min_texture = 2.0;
  /// [px, odd] the map's points sit at the matcher's disparity refined to sub-pixel precision
  /// over this window (RefineDisparitySubpixel; 0: off). SGBM's disparities lean ~0.12 px short
  /// and lock to whole pixels: at 12 m that is ~0.35 m of range bias. The per-frame classes keep
  /// the matcher's disparity, on which they were measured; without effect when
  /// stereo.subpixel_window_px already refines it, or with a given (oracle) disparity.
  int subpixel_window_px = 7;
  int checkpoint_every_frames = 200;  ///< save the map every n frames while building (0: never)
  bool IsValid(std::string* error) const;
};

/// The pipeline's tuned stage defaults where they differ from each module's own neutral ones
/// (measured on the synthetic yard with SGBM; see docs/accuracy.md): a wider matching block, a
/// depth-dependent 31 px normal window, looser neighbour roughness held together by the
/// segment-angle test, a verdict for every small segment that has a trustworthy plane, and
/// per-pixel slopes within segments (smooth hillsides).
StereoMatcherOptions PipelineStereoDefaults();
NormalOptions PipelineNormalDefaults();
SegmenterOptions PipelineSegmenterDefaults();
AnalysisOptions PipelineAnalysisDefaults();

/// Every option of the per-frame pipeline, one struct per stage (one YAML section each).
/// Defaults are the values documented in config/default.yaml.
struct Config {
  VehicleOptions vehicle;
  RectifierOptions rectification;
  StereoMatcherOptions stereo = PipelineStereoDefaults();
  TriangulationOptions triangulation;
  NormalOptions normals = PipelineNormalDefaults();
  SegmenterOptions segmentation = PipelineSegmenterDefaults();
  AnalysisOptions analysis = PipelineAnalysisDefaults();
  GravityOptions gravity;
  AttitudeFilterOptions attitude;
  MappingOptions map;
  RefinementOptions refinement;

  /// Validates every section; on failure the message reads "section.key: ...".
  bool IsValid(std::string* error) const;
};

/// Reads `path` over `config`: the keys the file holds replace the values in `config`, the rest
/// stay (a file may hold only a vehicle section). Throws ssta::Error naming the file and key
/// for an unknown section or key, a wrong type, or a value out of range.
void ApplyConfigFile(const std::string& path, Config* config);

/// Defaults overlaid with `path` (ApplyConfigFile).
Config LoadConfig(const std::string& path);

/// The config as YAML text (every key, as ApplyConfigFile reads it back).
std::string ConfigToYaml(const Config& config);

std::string GravitySourceName(GravitySource source);

}  // namespace ssta
