#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "ssta/analysis/frame_analysis.h"
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

class Sequence;

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

/// Calls `visit(name, what, section)` for every section of `config` (a Config or a const
/// Config), in file order, with the section's YAML name, a line saying what it configures, and
/// its options struct. The one list of the config's sections: the reader, the writers, the
/// checks and the Python binding all walk it, so a new section is one line here.
template <class C, class Visit>
void ForEachConfigSection(C& config, Visit&& visit) {
  visit("vehicle", "what the vehicle can drive over (docs/interfaces.md, section 3)", config.vehicle);
  visit("rectification", "", config.rectification);
  visit("stereo", "stereo matching (paper III-B)", config.stereo);
  visit("triangulation", "Z = f b / d, X = (u - cu) Z / f, Y = (v - cv) Z / f", config.triangulation);
  visit("normals", "per-pixel normals from integral images (paper III-C)", config.normals);
  visit("segmentation", "4-connected components of normals (paper III-D, eq. 1)", config.segmentation);
  visit("analysis", "SSTA on each segment (paper III-E) and the label refinements after it", config.analysis);
  visit("gravity", "up direction per frame, for the slopes and the map's poses", config.gravity);
  visit("attitude", "IMU attitude filter (Mahony-style complementary filter)", config.attitude);
  visit("map", "fusion into the persistent map (build-map; maps/README.md)", config.map);
  visit("refinement", "Ceres refinement of cam0's mount from the ground (docs/mount_calibration.md)",
        config.refinement);
}

/// Reads `path` over `config`: the keys the file holds replace the values in `config`, the rest
/// stay (a file may hold only a vehicle section). Throws ssta::Error naming the file and key
/// for an unknown section or key, a wrong type, or a value out of range.
void ApplyConfigFile(const std::string& path, Config* config);

/// Defaults overlaid with `path` (ApplyConfigFile).
Config LoadConfig(const std::string& path);

/// The config a run on `sequence` uses: the defaults, then the sequence's own vehicle.yaml (if
/// `sequence` is given and ships one), then each of `files` in order (later files override
/// earlier ones), as `--config A --config B` layers them. Throws as ApplyConfigFile.
Config LoadLayeredConfig(const Sequence* sequence, const std::vector<std::string>& files);

/// The config as YAML text (every key, as ApplyConfigFile reads it back exactly).
std::string ConfigToYaml(const Config& config);

/// The same with each key's unit and meaning as a comment (`ssta config`, config/default.yaml).
std::string ConfigToCommentedYaml(const Config& config);

}  // namespace ssta
