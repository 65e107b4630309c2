#include "ssta/pipeline/config.h"

#include <sstream>

#include "io/yaml_reader.h"
#include "pipeline/config_text.h"
#include "ssta/io/file_util.h"

namespace ssta {
namespace {

using internal::YamlSection;

bool Fail(std::string* error, const std::string& message) {
  if (error) *error = message;
  return false;
}

template <typename Options>
bool CheckSection(const Options& options, const char* section, std::string* error) {
  std::string e;
  if (options.IsValid(&e)) return true;
  return Fail(error, std::string(section) + "." + e);
}

GravitySource ParseGravitySource(const std::string& name, const std::string& where) {
  if (name == "auto") return GravitySource::kAuto;
  if (name == "imu") return GravitySource::kImu;
  if (name == "pose") return GravitySource::kPose;
  if (name == "level") return GravitySource::kLevel;
  if (name == "fixed") return GravitySource::kFixed;
  throw Error(where + ": unknown gravity source '" + name + "' (auto, imu, pose, level, fixed)");
}

template <typename Enum, typename Parse>
void ReadEnum(YamlSection& s, const std::string& key, Enum* value, Parse parse) {
  if (!s.Has(key)) {
    s.Ignore(key);
    return;
  }
  const auto name = s.Require<std::string>(key);
  try {
    *value = parse(name);
  } catch (const Error& e) {
    throw Error(s.Name(key) + ": " + e.what());
  }
}

void ReadVehicle(YamlSection s, VehicleOptions* o) {
  s.Read("max_slope_deg", &o->max_slope_deg);
  s.Read("semi_slope_deg", &o->semi_slope_deg);
  s.Read("max_step_m", &o->max_step_m);
  s.Read("semi_step_m", &o->semi_step_m);
  s.Read("min_camera_height_m", &o->min_camera_height_m);
  s.Read("max_camera_height_m", &o->max_camera_height_m);
  s.Ignore("name");
  s.Ignore("description");
  s.RejectUnknownKeys();
}

void ReadStereo(YamlSection s, StereoMatcherOptions* o) {
  ReadEnum(s, "algorithm", &o->algorithm, [](const std::string& n) { return ParseMatcherType(n); });
  s.Read("min_disparity", &o->min_disparity);
  s.Read("num_disparities", &o->num_disparities);
  s.Read("block_size", &o->block_size);
  ReadEnum(s, "sgbm_mode", &o->sgbm_mode, [](const std::string& n) { return ParseSgbmMode(n); });
  s.Read("uniqueness_ratio", &o->uniqueness_ratio);
  s.Read("left_right_check", &o->left_right_check);
  s.Read("left_right_max_diff", &o->left_right_max_diff);
  s.Read("speckle_window_size", &o->speckle_window_size);
  s.Read("speckle_range", &o->speckle_range);
  s.Read("min_texture", &o->min_texture);
  s.Read("border_margin", &o->border_margin);
  s.Read("subpixel_window_px", &o->subpixel_window_px);
  s.Read("pcl_ratio_filter", &o->pcl_ratio_filter);
  s.Read("pcl_peak_filter", &o->pcl_peak_filter);
  s.Read("pcl_preprocessing", &o->pcl_preprocessing);
  s.Read("acso_smoothness_strong", &o->acso_smoothness_strong);
  s.Read("acso_smoothness_weak", &o->acso_smoothness_weak);
  s.Read("acso_gamma_s", &o->acso_gamma_s);
  s.Read("acso_gamma_c", &o->acso_gamma_c);
  s.Read("downscale", &o->downscale);
  s.RejectUnknownKeys();
}

void ReadNormals(YamlSection s, NormalOptions* o) {
  ReadEnum(s, "method", &o->method, [](const std::string& n) { return ParseNormalMethod(n); });
  s.Read("smoothing_size_px", &o->smoothing_size_px);
  s.Read("max_depth_change_factor", &o->max_depth_change_factor);
  s.Read("depth_dependent_smoothing", &o->depth_dependent_smoothing);
  s.Read("subsample", &o->subsample);
  s.Read("threads", &o->threads);
  s.RejectUnknownKeys();
}

void ReadGravity(YamlSection s, GravityOptions* o) {
  if (s.Has("source")) o->source = ParseGravitySource(s.Require<std::string>("source"), s.Name("source"));
  s.Ignore("source");
  std::vector<double> up;
  s.ReadList("up_camera", &up, 3);
  if (!up.empty()) o->up_camera = Eigen::Vector3d(up[0], up[1], up[2]);
  s.RejectUnknownKeys();
}

}  // namespace








bool Config::IsValid(std::string* error) const {
  return CheckSection(vehicle, "vehicle", error) && CheckSection(rectification, "rectification", error) &&
         CheckSection(stereo, "stereo", error) && CheckSection(triangulation, "triangulation", error) &&
         CheckSection(normals, "normals", error) && CheckSection(segmentation, "segmentation", error) &&
         CheckSection(analysis, "analysis", error) && CheckSection(gravity, "gravity", error) &&
         CheckSection(attitude, "attitude", error) && CheckSection(map, "map", error) &&
         CheckSection(refinement, "refinement", error);
}

void ApplyConfigFile(const std::string& path, Config* config) {
  internal::ApplyConfigText(ReadTextFile(path), path, config);
}

void internal::ApplyConfigText(const std::string& text, const std::string& path, Config* config) {
  YamlSection root(internal::ParseYaml(text, path), path, "");
  Config c = *config;
  ReadVehicle(root.Child("vehicle"), &c.vehicle);
  {
    YamlSection s = root.Child("rectification");
    s.Read("crop_to_common_area", &c.rectification.crop_to_common_area);
    s.Read("alpha", &c.rectification.alpha);
    s.RejectUnknownKeys();
  }
  ReadStereo(root.Child("stereo"), &c.stereo);
  {
    YamlSection s = root.Child("triangulation");
    s.Read("min_range_m", &c.triangulation.min_range_m);
    s.Read("max_range_m", &c.triangulation.max_range_m);
    s.RejectUnknownKeys();
  }
  ReadNormals(root.Child("normals"), &c.normals);
  {
    YamlSection s = root.Child("segmentation");
    s.Read("roughness_deg", &c.segmentation.roughness_deg);
    s.Read("max_disparity_jump_px", &c.segmentation.max_disparity_jump_px);
    s.Read("max_segment_angle_deg", &c.segmentation.max_segment_angle_deg);
    s.RejectUnknownKeys();
  }
  {
    YamlSection s = root.Child("analysis");
    s.Read("inliers_min_ratio", &c.analysis.inliers_min_ratio);
    s.Read("pixel_slopes", &c.analysis.pixel_slopes);
    s.Read("pixel_slope_window_px", &c.analysis.pixel_slope_window_px);
    ReadEnum(s, "step_reference", &c.analysis.step_reference,
             [](const std::string& n) { return ParseStepReference(n); });
    ReadEnum(s, "small_segments", &c.analysis.small_segments,
             [](const std::string& n) { return ParseSmallSegmentPolicy(n); });
    s.Read("min_plane_points", &c.analysis.min_plane_points);
    s.Read("min_ground_share", &c.analysis.min_ground_share);
    s.Read("max_ground_rms_m", &c.analysis.max_ground_rms_m);
    s.Read("ground_tolerance_px", &c.analysis.ground_tolerance_px);
    s.Read("ground_consistent_share", &c.analysis.ground_consistent_share);
    s.Read("fragment_tolerance_px", &c.analysis.fragment_tolerance_px);
    s.Read("fragment_consistent_share", &c.analysis.fragment_consistent_share);
    s.Read("fragment_host_min_points", &c.analysis.fragment_host_min_points);
    s.Read("undecided_fill_radius_px", &c.analysis.undecided_fill_radius_px);
    s.Read("undecided_fill_share", &c.analysis.undecided_fill_share);
    s.Read("undecided_height_fill", &c.analysis.undecided_height_fill);
    s.Read("label_min_texture", &c.analysis.label_min_texture);
    s.Read("face_window_px", &c.analysis.face_window_px);
    s.Read("face_columns_px", &c.analysis.face_columns_px);
    s.Read("face_grow_tolerance_px", &c.analysis.face_grow_tolerance_px);
    s.Read("face_min_slope_deg", &c.analysis.face_min_slope_deg);
    s.RejectUnknownKeys();
  }
  ReadGravity(root.Child("gravity"), &c.gravity);
  {
    YamlSection s = root.Child("attitude");
    s.Read("kp", &c.attitude.kp);
    s.Read("ki", &c.attitude.ki);
    s.Read("accel_gate", &c.attitude.accel_gate);
    s.Read("init_window_s", &c.attitude.init_window_s);
    s.Read("max_rest_gravity_error_mps2", &c.attitude.max_rest_gravity_error_mps2);
    s.Read("init_gyro_bias", &c.attitude.init_gyro_bias);
    s.RejectUnknownKeys();
  }
  {
    YamlSection s = root.Child("map");
    MapOptions& f = c.map.fusion;
    s.Read("resolution_m", &f.resolution_m);
    s.Read("max_range_m", &f.max_range_m);
    s.Read("occupancy_hit_prob", &f.occupancy_hit_prob);
    s.Read("occupancy_miss_prob", &f.occupancy_miss_prob);
    s.Read("occupancy_clamp_min_prob", &f.occupancy_clamp_min_prob);
    s.Read("occupancy_clamp_max_prob", &f.occupancy_clamp_max_prob);
    s.Read("occupied_threshold_prob", &f.occupied_threshold_prob);
    s.Read("class_hit_log_odds", &f.class_hit_log_odds);
    s.Read("class_miss_log_odds", &f.class_miss_log_odds);
    s.Read("class_free_decay_log_odds", &f.class_free_decay_log_odds);
    s.Read("class_clamp_min", &f.class_clamp_min);
    s.Read("class_clamp_max", &f.class_clamp_max);
    s.Read("free_space_clearance_m", &f.free_space_clearance_m);
    s.Read("free_space_ray_cell", &f.free_space_ray_cell);
    s.Read("free_space_obstacle_shortening_per_m2", &f.free_space_obstacle_shortening_per_m2);
    s.Read("free_space_keeps_traversable", &f.free_space_keeps_traversable);
    s.Read("pixel_stride", &c.map.pixel_stride);
    s.Read("min_texture", &c.map.min_texture);
    s.Read("subpixel_window_px", &c.map.subpixel_window_px);
    s.Read("checkpoint_every_frames", &c.map.checkpoint_every_frames);
    s.RejectUnknownKeys();
  }
  {
    YamlSection s = root.Child("refinement");
    RefinementOptions& r = c.refinement;
    s.Read("points_per_frame", &r.points_per_frame);
    s.Read("min_points_per_frame", &r.min_points_per_frame);
    s.Read("max_range_m", &r.max_range_m);
    s.Read("min_frames", &r.min_frames);
    s.Read("point_sigma_m", &r.point_sigma_m);
    s.Read("point_sigma_range_m", &r.point_sigma_range_m);
    ReadEnum(s, "robust_loss", &r.robust_loss, [](const std::string& n) { return ParseRobustLoss(n); });
    s.Read("loss_scale", &r.loss_scale);
    ReadEnum(s, "ground_reference", &r.ground_reference,
             [](const std::string& n) { return ParseGroundReference(n); });
    s.Read("terrain_tilt_sigma_deg", &r.terrain_tilt_sigma_deg);
    s.Read("prior_sigma_deg", &r.prior_sigma_deg);
    s.Read("max_sigma_ratio", &r.max_sigma_ratio);
    s.Read("body_height_m", &r.body_height_m);
    s.Read("terrain_height_sigma_m", &r.terrain_height_sigma_m);
    s.Read("estimate_height", &r.estimate_height);
    s.Read("height_prior_sigma_m", &r.height_prior_sigma_m);
    s.Read("max_iterations", &r.max_iterations);
    s.Read("online", &r.online);
    s.Read("window_frames", &r.window_frames);
    s.Read("solve_every_frames", &r.solve_every_frames);
    s.RejectUnknownKeys();
  }
  root.RejectUnknownKeys();
  std::string error;
  if (!c.IsValid(&error)) throw Error(path + ": " + error);
  *config = c;
}

Config LoadConfig(const std::string& path) {
  Config config;
  ApplyConfigFile(path, &config);
  return config;
}


std::string ConfigToYaml(const Config& c) {
  std::ostringstream y;
  y << std::boolalpha;
  y << "vehicle:\n"
    << "  max_slope_deg: " << c.vehicle.max_slope_deg << "\n"
    << "  semi_slope_deg: " << c.vehicle.semi_slope_deg << "\n"
    << "  max_step_m: " << c.vehicle.max_step_m << "\n"
    << "  semi_step_m: " << c.vehicle.semi_step_m << "\n"
    << "  min_camera_height_m: " << c.vehicle.min_camera_height_m << "\n"
    << "  max_camera_height_m: " << c.vehicle.max_camera_height_m << "\n";
  y << "rectification:\n  crop_to_common_area: " << c.rectification.crop_to_common_area << "\n"
    << "  alpha: " << c.rectification.alpha << "\n";
  const auto& s = c.stereo;
  y << "stereo:\n"
    << "  algorithm: " << MatcherTypeName(s.algorithm) << "\n"
    << "  min_disparity: " << s.min_disparity << "\n"
    << "  num_disparities: " << s.num_disparities << "\n"
    << "  block_size: " << s.block_size << "\n"
    << "  sgbm_mode: " << SgbmModeName(s.sgbm_mode) << "\n"
    << "  uniqueness_ratio: " << s.uniqueness_ratio << "\n"
    << "  left_right_check: " << s.left_right_check << "\n"
    << "  left_right_max_diff: " << s.left_right_max_diff << "\n"
    << "  speckle_window_size: " << s.speckle_window_size << "\n"
    << "  speckle_range: " << s.speckle_range << "\n"
    << "  min_texture: " << s.min_texture << "\n"
    << "  border_margin: " << s.border_margin << "\n"
    << "  subpixel_window_px: " << s.subpixel_window_px << "\n"
    << "  pcl_ratio_filter: " << s.pcl_ratio_filter << "\n"
    << "  pcl_peak_filter: " << s.pcl_peak_filter << "\n"
    << "  pcl_preprocessing: " << s.pcl_preprocessing << "\n"
    << "  acso_smoothness_strong: " << s.acso_smoothness_strong << "\n"
    << "  acso_smoothness_weak: " << s.acso_smoothness_weak << "\n"
    << "  acso_gamma_s: " << s.acso_gamma_s << "\n"
    << "  acso_gamma_c: " << s.acso_gamma_c << "\n"
    << "  downscale: " << s.downscale << "\n";
  y << "triangulation:\n"
    << "  min_range_m: " << c.triangulation.min_range_m << "\n"
    << "  max_range_m: " << c.triangulation.max_range_m << "\n";
  y << "normals:\n"
    << "  method: " << NormalMethodName(c.normals.method) << "\n"
    << "  smoothing_size_px: " << c.normals.smoothing_size_px << "\n"
    << "  max_depth_change_factor: " << c.normals.max_depth_change_factor << "\n"
    << "  depth_dependent_smoothing: " << c.normals.depth_dependent_smoothing << "\n"
    << "  subsample: " << c.normals.subsample << "\n"
    << "  threads: " << c.normals.threads << "\n";
  y << "segmentation:\n"
    << "  roughness_deg: " << c.segmentation.roughness_deg << "\n"
    << "  max_disparity_jump_px: " << c.segmentation.max_disparity_jump_px << "\n"
    << "  max_segment_angle_deg: " << c.segmentation.max_segment_angle_deg << "\n";
  y << "analysis:\n"
    << "  inliers_min_ratio: " << c.analysis.inliers_min_ratio << "\n"
    << "  pixel_slopes: " << c.analysis.pixel_slopes << "\n"
    << "  pixel_slope_window_px: " << c.analysis.pixel_slope_window_px << "\n"
    << "  step_reference: " << StepReferenceName(c.analysis.step_reference) << "\n"
    << "  small_segments: " << SmallSegmentPolicyName(c.analysis.small_segments) << "\n"
    << "  min_plane_points: " << c.analysis.min_plane_points << "\n"
    << "  min_ground_share: " << c.analysis.min_ground_share << "\n"
    << "  max_ground_rms_m: " << c.analysis.max_ground_rms_m << "\n"
    << "  ground_tolerance_px: " << c.analysis.ground_tolerance_px << "\n"
    << "  ground_consistent_share: " << c.analysis.ground_consistent_share << "\n"
    << "  fragment_tolerance_px: " << c.analysis.fragment_tolerance_px << "\n"
    << "  fragment_consistent_share: " << c.analysis.fragment_consistent_share << "\n"
    << "  fragment_host_min_points: " << c.analysis.fragment_host_min_points << "\n"
    << "  undecided_fill_radius_px: " << c.analysis.undecided_fill_radius_px << "\n"
    << "  undecided_fill_share: " << c.analysis.undecided_fill_share << "\n"
    << "  undecided_height_fill: " << c.analysis.undecided_height_fill << "\n"
    << "  label_min_texture: " << c.analysis.label_min_texture << "\n"
    << "  face_window_px: " << c.analysis.face_window_px << "\n"
    << "  face_columns_px: " << c.analysis.face_columns_px << "\n"
    << "  face_grow_tolerance_px: " << c.analysis.face_grow_tolerance_px << "\n"
    << "  face_min_slope_deg: " << c.analysis.face_min_slope_deg << "\n";
  y << "gravity:\n"
    << "  source: " << GravitySourceName(c.gravity.source) << "\n"
    << "  up_camera: [" << c.gravity.up_camera.x() << ", " << c.gravity.up_camera.y() << ", "
    << c.gravity.up_camera.z() << "]\n";
  y << "attitude:\n"
    << "  kp: " << c.attitude.kp << "\n"
    << "  ki: " << c.attitude.ki << "\n"
    << "  accel_gate: " << c.attitude.accel_gate << "\n"
    << "  init_window_s: " << c.attitude.init_window_s << "\n"
    << "  max_rest_gravity_error_mps2: " << c.attitude.max_rest_gravity_error_mps2 << "\n"
    << "  init_gyro_bias: " << c.attitude.init_gyro_bias << "\n";
  const MapOptions& f = c.map.fusion;
  y << "map:\n"
    << "  resolution_m: " << f.resolution_m << "\n"
    << "  max_range_m: " << f.max_range_m << "\n"
    << "  occupancy_hit_prob: " << f.occupancy_hit_prob << "\n"
    << "  occupancy_miss_prob: " << f.occupancy_miss_prob << "\n"
    << "  occupancy_clamp_min_prob: " << f.occupancy_clamp_min_prob << "\n"
    << "  occupancy_clamp_max_prob: " << f.occupancy_clamp_max_prob << "\n"
    << "  occupied_threshold_prob: " << f.occupied_threshold_prob << "\n"
    << "  class_hit_log_odds: " << f.class_hit_log_odds << "\n"
    << "  class_miss_log_odds: " << f.class_miss_log_odds << "\n"
    << "  class_free_decay_log_odds: " << f.class_free_decay_log_odds << "\n"
    << "  class_clamp_min: " << f.class_clamp_min << "\n"
    << "  class_clamp_max: " << f.class_clamp_max << "\n"
    << "  free_space_clearance_m: " << f.free_space_clearance_m << "\n"
    << "  free_space_ray_cell: " << f.free_space_ray_cell << "\n"
    << "  free_space_obstacle_shortening_per_m2: " << f.free_space_obstacle_shortening_per_m2 << "\n"
    << "  free_space_keeps_traversable: " << f.free_space_keeps_traversable << "\n"
    << "  pixel_stride: " << c.map.pixel_stride << "\n"
    << "  min_texture: " << c.map.min_texture << "\n"
    << "  subpixel_window_px: " << c.map.subpixel_window_px << "\n"
    << "  checkpoint_every_frames: " << c.map.checkpoint_every_frames << "\n";
  const RefinementOptions& r = c.refinement;
  y << "refinement:\n"
    << "  points_per_frame: " << r.points_per_frame << "\n"
    << "  min_points_per_frame: " << r.min_points_per_frame << "\n"
    << "  max_range_m: " << r.max_range_m << "\n"
    << "  min_frames: " << r.min_frames << "\n"
    << "  point_sigma_m: " << r.point_sigma_m << "\n"
    << "  point_sigma_range_m: " << r.point_sigma_range_m << "\n"
    << "  robust_loss: " << RobustLossName(r.robust_loss) << "\n"
    << "  loss_scale: " << r.loss_scale << "\n"
    << "  ground_reference: " << GroundReferenceName(r.ground_reference) << "\n"
    << "  terrain_tilt_sigma_deg: " << r.terrain_tilt_sigma_deg << "\n"
    << "  prior_sigma_deg: " << r.prior_sigma_deg << "\n"
    << "  max_sigma_ratio: " << r.max_sigma_ratio << "\n"
    << "  body_height_m: " << r.body_height_m << "\n"
    << "  terrain_height_sigma_m: " << r.terrain_height_sigma_m << "\n"
    << "  estimate_height: " << r.estimate_height << "\n"
    << "  height_prior_sigma_m: " << r.height_prior_sigma_m << "\n"
    << "  max_iterations: " << r.max_iterations << "\n"
    << "  online: " << r.online << "\n"
    << "  window_frames: " << r.window_frames << "\n"
    << "  solve_every_frames: " << r.solve_every_frames << "\n";
  return y.str();
}

}  // namespace ssta
