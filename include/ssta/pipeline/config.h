#pragma once

#include <string>

#include <Eigen/Core>

#include "ssta/analysis/surface_analyzer.h"
#include "ssta/core/vehicle_options.h"
#include "ssta/geometry/normal_estimator.h"
#include "ssta/sensors/gravity_provider.h"
#include "ssta/geometry/segmenter.h"
#include "ssta/mapping/map_options.h"
#include "ssta/mount/refinement_options.h"
#include "ssta/stereo/rectifier.h"
#include "ssta/stereo/stereo_matcher.h"
#include "ssta/stereo/triangulator.h"

namespace ssta {

/// Every option of the per-frame pipeline, one struct per stage (one YAML section each).
/// Defaults are the values documented in config/default.yaml.
struct Config {
  VehicleOptions vehicle;
  RectifierOptions rectification;
  StereoMatcherOptions stereo;
  TriangulationOptions triangulation;
  NormalOptions normals;
  SegmenterOptions segmentation;
  AnalysisOptions analysis;
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

/// The config as YAML text (every key, as ApplyConfigFile reads it back exactly).
std::string ConfigToYaml(const Config& config);

/// The same with each key's unit and meaning as a comment (`ssta config`, config/default.yaml).
std::string ConfigToCommentedYaml(const Config& config);

}  // namespace ssta
