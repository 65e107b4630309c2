#include "ssta/pipeline/frame_pipeline.h"

#include <algorithm>
#include <chrono>

#include "core/run_both.h"
#include "ssta/analysis/frame_analysis.h"
#include "ssta/analysis/label_rule.h"
#include "ssta/geometry/normal_estimator.h"
#include "ssta/geometry/segmenter.h"
#include "ssta/stereo/rectifier.h"
#include "ssta/stereo/stereo_matcher.h"
#include "ssta/stereo/triangulator.h"

namespace ssta {
namespace {

using internal::RunBoth;

class Stopwatch {
 public:
  double LapMs() {
    const auto now = std::chrono::steady_clock::now();
    const double ms = std::chrono::duration<double, std::milli>(now - last_).count();
    last_ = now;
    return ms;
  }

 private:
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

Config Validated(const Config& config) {
  std::string error;
  if (!config.IsValid(&error)) throw Error("config: " + error);
  return config;
}

/// The stereo options with the search range resolved for the rig.
StereoMatcherOptions MatcherOptionsFor(const Config& config, const RectifiedGeometry& geometry,
                                       const Eigen::Isometry3d& body_T_camera) {
  StereoMatcherOptions o = config.stereo;
  if (o.auto_num_disparities) {
    const int room = 1024 - o.min_disparity;
    o.num_disparities = std::min(room / 16 * 16, AutoNumDisparities(geometry, body_T_camera, o.num_disparities));
  }
  return o;
}

}  // namespace

struct FramePipeline::Stages {
  Stages(const StereoCalibration& calibration, const Config& config)
      : rectifier(calibration, config.rectification),
        matcher(MatcherOptionsFor(config, rectifier.geometry(), calibration.left.body_T_camera)),
        normals(config.normals),
        segmenter(config.segmentation),
        analyzer(config.vehicle, config.analysis, config.stereo.disparity_sigma_px,
                 config.stereo.block_size * config.stereo.downscale,
                 // The frame's lips are searched within the map's range, so the map takes them.
                 config.map.FusionFor(rectifier.geometry().f * rectifier.geometry().baseline_m,
                                      config.stereo.disparity_sigma_px)
                     .max_range_m) {}
  Rectifier rectifier;
  StereoMatcher matcher;
  NormalEstimator normals;
  Segmenter segmenter;
  FrameAnalyzer analyzer;
};

int AutoNumDisparities(const RectifiedGeometry& g, const Eigen::Isometry3d& body_T_camera, int fallback) {
  const double height = body_T_camera.translation().z();
  if (!(height >= 0.1)) return fallback;
  const Eigen::Matrix3d body_R_rectified = body_T_camera.linear() * g.rectified_R_camera.transpose();
  double largest = 0.0;
  for (const double u : {0.0, 0.5 * (g.crop_width - 1), static_cast<double>(g.crop_width - 1)}) {
    // The ray through the bottom row (z = 1 in the rectified frame: its parameter is the depth).
    const Eigen::Vector3d ray = body_R_rectified * Eigen::Vector3d((u - g.cu) / g.f, (g.crop_height - 1 - g.cv) / g.f, 1.0);
    if (ray.z() < 0) largest = std::max(largest, g.f * g.baseline_m * -ray.z() / height);
  }
  if (largest <= 0) return fallback;
  const int needed = static_cast<int>(std::ceil(1.1 * largest / 16.0)) * 16;
  return std::max(fallback, std::min(needed, std::max(16, g.crop_width / 2 / 16 * 16)));
}

FramePipeline::FramePipeline(const StereoCalibration& calibration, const Config& config)
    : config_(Validated(config)), calibration_(calibration),
      stages_(std::make_unique<Stages>(calibration, config_)) {}

FramePipeline::~FramePipeline() = default;

const RectifiedGeometry& FramePipeline::geometry() const { return stages_->rectifier.geometry(); }

Eigen::Vector3d FramePipeline::UpInCamera(const Eigen::Vector3d& up_body) const {
  return (calibration_.left.body_T_camera.linear().transpose() * up_body).normalized();
}

FrameResult FramePipeline::Process(const ImageU8& left, const ImageU8& right,
                                   const Eigen::Vector3d& up_camera) {
  return Run(left, right, nullptr, up_camera);
}

FrameResult FramePipeline::ProcessWithDisparity(const ImageU8& left, const ImageU8& right, ImageF disparity,
                                                const Eigen::Vector3d& up_camera) {
  const RectifiedGeometry& g = stages_->rectifier.geometry();
  if (disparity.width() != g.crop_width || disparity.height() != g.crop_height) {
    throw Error("given disparity is " + std::to_string(disparity.width()) + "x" + std::to_string(disparity.height()) +
                ", the rectified common area " + std::to_string(g.crop_width) + "x" + std::to_string(g.crop_height));
  }
  return Run(left, right, &disparity, up_camera);
}

FrameResult FramePipeline::Run(const ImageU8& left, const ImageU8& right, const ImageF* disparity,
                               const Eigen::Vector3d& up_camera) {
  SSTA_CHECK(up_camera.allFinite() && up_camera.norm() > 1e-9, "up_camera must be finite and non-zero");
  FrameResult out;
  Stopwatch clock;
  const RectifiedGeometry& g = stages_->rectifier.geometry();

  RectifiedPair pair = stages_->rectifier.Rectify(left, right);
  out.timings.rectify_ms = clock.LapMs();

  out.disparity = disparity ? *disparity : stages_->matcher.Compute(pair.left, pair.right);
  out.timings.match_ms = clock.LapMs();

  out.cloud = Triangulate(out.disparity, g, config_.triangulation);
  const Image3f& cloud = out.cloud;
  out.timings.triangulate_ms = clock.LapMs();

  const Image3f& normals = stages_->normals.Compute(cloud);
  out.timings.normals_ms = clock.LapMs();

  const Segmentation& segmentation = stages_->segmenter.Compute(normals, &out.disparity);
  out.num_segments = segmentation.num_segments();
  out.segment_ids = segmentation.labels;
  out.timings.segment_ms = clock.LapMs();

  out.up_rectified = (g.rectified_R_camera * up_camera).normalized();
  // Both texture tests (the labels' here, the map's later) ask for texture beyond the camera's
  // own noise (texture_noise_multiple).
  const double noise_multiple = config_.analysis.texture_noise_multiple;
  if (noise_multiple > 0.0 && (config_.analysis.label_min_texture > 0.0 || config_.map.min_texture > 0.0)) {
    out.texture_noise_floor = noise_multiple * ImageNoiseSigma(pair.left_full);
  }
  // The texture test on the full rectified image (the block reaches past the common area's border
  // as the matcher's does), less the matcher's floating noise: such points stay out of the local
  // steps' grid and their labels are unknown.
  const double label_min_texture = TextureThreshold(config_.analysis.label_min_texture, out.texture_noise_floor);
  const bool masked = label_min_texture > 0.0;
  if (masked) {
    supported_ = SupportedPixels(pair.left_full, g, config_.stereo.block_size, label_min_texture, out.up_rectified,
                                 out.disparity);
  }
  out.analysis = stages_->analyzer.Analyze({&g, &out.disparity, &cloud, &normals, &segmentation.labels,
                                            out.num_segments, out.up_rectified, masked ? &supported_ : nullptr});
  if (masked) {
    const ImageU8& textured = supported_;
    ImageU8& labels = out.analysis.labels;
    ImageU8& rules = out.analysis.rules;
    for (std::size_t i = 0; i < labels.size(); ++i) {
      if (textured[i] == 0 && labels[i] != static_cast<std::uint8_t>(TravClass::kUnknown)) {
        labels[i] = static_cast<std::uint8_t>(TravClass::kUnknown);
        rules[i] = static_cast<std::uint8_t>(LabelRule::kTexture);
      }
    }
  }
  out.timings.analyze_ms = clock.LapMs();

  // Labels keep the full rectified size; outside the common area they stay unknown (0).
  out.labels = ImageU8(g.full_width, g.full_height, static_cast<std::uint8_t>(TravClass::kUnknown));
  out.rules = ImageU8(g.full_width, g.full_height, static_cast<std::uint8_t>(LabelRule::kOutside));
  for (int v = 0; v < g.crop_height; ++v) {
    const std::uint8_t* src = out.analysis.labels.row(v);
    std::copy(src, src + g.crop_width, out.labels.row(v + g.crop_v0) + g.crop_u0);
    const std::uint8_t* rule = out.analysis.rules.row(v);
    std::copy(rule, rule + g.crop_width, out.rules.row(v + g.crop_v0) + g.crop_u0);
  }
  out.left_rectified = std::move(pair.left_full);
  out.texture_block_px = config_.stereo.block_size;
  out.labels_min_texture = label_min_texture;
  out.depth_noise_per_m2 = config_.stereo.disparity_sigma_px / (g.f * g.baseline_m);
  // The map's points may be refined to sub-pixel disparity later (MapPointsOfFrame), off the
  // per-frame path; the classification keeps the matcher's disparity.
  if (disparity == nullptr && config_.map.subpixel_window_px > 0 && config_.stereo.subpixel_window_px == 0) {
    out.left_matched = std::move(pair.left);
    out.right_matched = std::move(pair.right);
  }
  const StageTimings& t = out.timings;
  out.timings.total_ms = t.rectify_ms + t.match_ms + t.triangulate_ms + t.normals_ms + t.segment_ms +
                         t.analyze_ms + clock.LapMs();
  return out;
}

}  // namespace ssta
