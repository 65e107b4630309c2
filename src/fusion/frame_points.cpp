#include "ssta/fusion/frame_points.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

#include "core/run_both.h"
#include "analysis/hidden_drops.h"
#include "ssta/analysis/frame_analysis.h"
#include "ssta/analysis/label_rule.h"
#include "ssta/core/error.h"
#include "ssta/stereo/stereo_matcher.h"

namespace ssta {
namespace {

// Where frames feed the map, the map's parallel steps (its free-space walk) run on OpenCV's
// thread pool with the frame's, so that one thread setting (`ssta --threads`) caps them all.
// A program that links this file calls MapPointsOfFrame before InsertFrame.
const bool kMapStepsOnOpenCvThreads = [] {
  internal::SetPairRunner(&internal::RunPairOnOpenCv);
  return true;
}();

/// 1-sigma of the height at a map column of a point `q` (rectified camera frame, depth q.z())
/// whose depth errs by `per_m2` q.z()^2: its error along its ray, seen vertically, and its
/// horizontal part through the surface's `gradient` (rise over run), at least 5 mm.
float HeightSigma(const Eigen::Vector3f& q, const Eigen::Matrix3f& world_R_rectified, float per_m2, float gradient,
                  float* horizontal_sigma) {
  // Along the ray the error is k Z^2 |q| / Z = k Z |q|; its vertical part k Z |q . up| and its
  // horizontal part k Z sqrt(|q|^2 - (q . up)^2), without dividing by |q|.
  const float scale = per_m2 * q.z();
  const float up = world_R_rectified.row(2).dot(q);
  const float across_squared = std::max(0.0f, q.squaredNorm() - up * up);
  *horizontal_sigma = scale * std::sqrt(across_squared);
  // sqrt(vertical^2 + (gradient horizontal)^2), both far below overflow.
  return std::max(0.005f, scale * std::sqrt(up * up + gradient * gradient * across_squared));
}

/// The gradient (rise over run) of a surface of `slope_deg`, at most 1: a face's height is its
/// own, not its foot's. 0 for no slope (NaN).
float Gradient(float slope_deg) {
  return std::isfinite(slope_deg) ? std::tan(std::min(slope_deg, 45.0f) * 0.0174532925f) : 0.0f;
}

}  // namespace

void AppendNoReturnRays(const FrameResult& frame, const Eigen::Isometry3d& world_T_rectified,
                        const RectifiedGeometry& geometry, int stride, std::vector<ClassifiedPoint>* points) {
  SSTA_CHECK(stride >= 1, "stride must be at least 1");
  SSTA_CHECK(points != nullptr, "points must not be null");
  // The lattice's phase, one of stride^2, from the frame's timestamp (mixed, as consecutive
  // timestamps share their low bits): over frames the rays cover every pixel.
  std::uint64_t mixed = static_cast<std::uint64_t>(frame.timestamp_ns) + 0x9E3779B97F4A7C15ull;
  mixed = (mixed ^ (mixed >> 30)) * 0xBF58476D1CE4E5B9ull;
  mixed = (mixed ^ (mixed >> 27)) * 0x94D049BB133111EBull;
  mixed ^= mixed >> 31;
  const auto phases = static_cast<std::uint64_t>(stride);
  const int u0 = static_cast<int>(mixed % phases), v0 = static_cast<int>((mixed / phases) % phases);
  const ImageU8& rules = frame.analysis.rules;
  const auto texture = static_cast<std::uint8_t>(LabelRule::kTexture);
  const Eigen::Isometry3f transform = world_T_rectified.cast<float>();
  const Eigen::Vector3f up = frame.up_rectified.cast<float>();
  const auto f = static_cast<float>(geometry.f);
  for (int v = v0; v < rules.height(); v += stride) {
    const std::uint8_t* row = rules.row(v);
    const auto y = static_cast<float>((v - geometry.cv) / geometry.f);
    for (int u = u0; u < rules.width(); u += stride) {
      if (row[u] != texture) continue;
      // Below the horizon a blank patch is ground the frame could not range, not a view into
      // the open.
      const Eigen::Vector3f ray(static_cast<float>(u - geometry.cu) / f, y, 1.0f);
      if (ray.dot(up) <= 0.0f) continue;
      ClassifiedPoint p;
      p.world_p = transform * ray;  // 1 m deep along the ray: only its direction counts
      p.no_return = true;
      points->push_back(p);
    }
  }
}

namespace {

/// The rule behind each of `analysis`' labels; null for a result built without them (by hand),
/// whose labels then all count as they are.
const ImageU8* LabelRulesOf(const AnalysisResult& analysis) {
  const ImageU8& rules = analysis.rules;
  const bool known = rules.width() == analysis.labels.width() && rules.height() == analysis.labels.height();
  return known ? &rules : nullptr;
}

/// No rule known (a result built by hand): the label counts as it is.
constexpr std::uint8_t kNoRule = 255;

/// The class a pixel votes for in the map: its label, but undecided where the frame's obstacle
/// is one the map should not count. `rule`: the pixel's LabelRule (kNoRule: unknown);
/// `segment`: its segment, or null.
TravClass VoteClass(std::uint8_t label, std::uint8_t rule, const SegmentResult* segment) {
  const auto cls = static_cast<TravClass>(label);
  if (cls != TravClass::kNonTraversable) return cls;
  // Far ground in a few matching windows tilts so, and frames that see it alike would pile
  // such votes into a false obstacle.
  const bool slope_of_noise = rule == static_cast<std::uint8_t>(LabelRule::kSmallSegment) && segment != nullptr &&
                              ObstacleBySlopeWithinNoise(*segment);
  // The frame blocks it for want of knowing which side of a jump's band it lies on; frames
  // that place it better decide.
  const bool band_unplaced = rule == static_cast<std::uint8_t>(LabelRule::kSmearedStep);
  // Either is a surface seen, without a class.
  return slope_of_noise || band_unplaced ? TravClass::kUndecided : cls;
}

}  // namespace

void ClassifiedPointsInWorld(const FrameResult& frame, const Eigen::Isometry3d& world_T_rectified, int stride,
                             const ImageU8* keep, std::vector<ClassifiedPoint>* points,
                             const ImageF* point_disparity, const ImageU8* lip) {
  SSTA_CHECK(stride >= 1, "stride must be at least 1");
  SSTA_CHECK(points != nullptr, "points must not be null");
  const Image3f& cloud = frame.cloud;
  SSTA_CHECK(keep == nullptr || (keep->width() == cloud.width() && keep->height() == cloud.height()),
             "the keep mask must have the size of the common area");
  SSTA_CHECK(point_disparity == nullptr ||
                 (point_disparity->width() == cloud.width() && point_disparity->height() == cloud.height() &&
                  frame.disparity.width() == cloud.width() && frame.disparity.height() == cloud.height()),
             "the point disparity and the frame's disparity must have the size of the common area");
  SSTA_CHECK(lip == nullptr || (lip->width() == cloud.width() && lip->height() == cloud.height()),
             "the lip mask must have the size of the common area");
  const ImageU8& labels = frame.analysis.labels;
  const ImageU8* rules = LabelRulesOf(frame.analysis);
  // Each segment's (slope, step) once, as the points carry them: a small flat table instead
  // of a SegmentResult (with its plane and statistics) read per point.
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  const auto& segments = frame.analysis.segments;
  std::vector<std::pair<float, float>> segment_values(segments.size());
  std::vector<float> segment_gradients(segments.size());
  for (std::size_t i = 0; i < segments.size(); ++i) {
    const SegmentResult& s = segments[i];
    segment_values[i] = {s.has_plane ? static_cast<float>(s.slope_deg) : kNaN, static_cast<float>(s.step_m)};
    segment_gradients[i] = Gradient(segment_values[i].first);
  }
  const bool has_ground = frame.analysis.ground.found && frame.analysis.quality.passed;
  const auto gradient = [&](int id) { return id >= 0 ? segment_gradients[static_cast<std::size_t>(id)] : 0.0f; };
  const auto per_m2 = static_cast<float>(frame.depth_noise_per_m2);
  const Eigen::Vector4f ground = frame.analysis.ground.plane.cast<float>();
  points->clear();
  points->reserve(cloud.size() / (stride * stride) + 1);
  const Eigen::Isometry3f transform = world_T_rectified.cast<float>();
  const Eigen::Matrix3f world_R_rectified = transform.linear();
  for (int v = 0; v < cloud.height(); v += stride) {
    for (int u = 0; u < cloud.width(); u += stride) {
      const Eigen::Vector3f& p = cloud(v, u);
      if (!IsFinite(p) || labels(v, u) == static_cast<std::uint8_t>(TravClass::kUnknown) ||
          (keep != nullptr && (*keep)(v, u) == 0)) {
        continue;
      }
      ClassifiedPoint out;
      Eigen::Vector3f q = p;
      if (point_disparity != nullptr) {
        // The same ray at the other disparity: Z' = f b / d' = Z d / d'.
        const float d = frame.disparity(v, u), refined = (*point_disparity)(v, u);
        if (refined > 0.0f && d > 0.0f) q = p * (d / refined);
      }
      out.world_p = transform * q;
      if (has_ground) out.height_m = ground.head<3>().dot(q) + ground.w();
      if (frame.depth_noise_per_m2 > 0) {
        out.height_sigma_m = HeightSigma(q, world_R_rectified, per_m2, gradient(frame.segment_ids(v, u)),
                                         &out.horizontal_sigma_m);
      }
      const int id = frame.segment_ids(v, u);
      out.cls = VoteClass(labels(v, u), rules != nullptr ? (*rules)(v, u) : kNoRule,
                          id >= 0 ? &segments[static_cast<std::size_t>(id)] : nullptr);
      if (lip != nullptr && (*lip)(v, u) != 0 && out.cls != TravClass::kNonTraversable) {
        out.cls = TravClass::kNonTraversable;
        out.vote_weight = static_cast<float>((*lip)(v, u)) / 255.0f;
      }
      if (id >= 0) {
        out.slope_deg = segment_values[static_cast<std::size_t>(id)].first;
        out.step_m = segment_values[static_cast<std::size_t>(id)].second;
      } else {
        out.slope_deg = out.step_m = kNaN;
      }
      points->push_back(out);
    }
  }
}

std::vector<ClassifiedPoint> ClassifiedPointsInWorld(const FrameResult& frame,
                                                     const Eigen::Isometry3d& world_T_rectified, int stride,
                                                     const ImageU8* keep, const ImageF* point_disparity,
                                                     const ImageU8* lip) {
  std::vector<ClassifiedPoint> points;
  ClassifiedPointsInWorld(frame, world_T_rectified, stride, keep, &points, point_disparity, lip);
  return points;
}

void MapPointsOfFrame(const FrameResult& frame, const Eigen::Isometry3d& world_T_rectified,
                      const MappingOptions& options, const RectifiedGeometry& geometry, const VehicleOptions& vehicle,
                      std::vector<ClassifiedPoint>* points) {
  // Sub-pixel disparity for the points (map.subpixel_window_px), when the frame kept the
  // matcher's images for it.
  thread_local ImageF refined_of_thread;  // kept between frames; a worker may write it
  ImageF& refined = refined_of_thread;
  const bool refine = options.subpixel_window_px > 0 && !frame.right_matched.empty();
  // The labels are 0 where the texture is below analysis.label_min_texture, and such pixels are
  // never emitted: a map threshold no stricter than that needs no mask of its own.
  const double min_texture = TextureThreshold(options.min_texture, frame.texture_noise_floor);
  const bool mask = min_texture > 0.0 && frame.labels_min_texture < min_texture;
  ImageU8 keep, lip;
  // The range the map keeps points to: FusionFor with the frame's rig, whose f b / sigma_d is
  // 1 / depth_noise_per_m2. The frame's analysis searched its lips within it (FramePipeline), so
  // they are taken as they are.
  const double range = options.FusionFor(1.0, frame.depth_noise_per_m2).max_range_m;
  const ImageU8& found = frame.analysis.lips;
  const bool take_found = options.pixel_stride == 1 && found.width() == frame.cloud.width() &&
                          found.height() == frame.cloud.height() &&
                          std::abs(frame.analysis.lips_range_m - range) <= 1e-6 * range;
  // The refinement, the texture mask and the lips are independent: they run side by side.
  internal::RunBoth(
      [&] {
        if (!refine) return;
        refined = frame.disparity;
        // Only inside one segment: a window across an obstacle's outline would blend its depth
        // with the ground's behind it where the two lie less than 1 px of disparity apart.
        RefineDisparitySubpixel(frame.left_matched, frame.right_matched, options.subpixel_window_px,
                                kMapSubpixelSteps, &refined, &frame.segment_ids);
      },
      [&] {
        if (mask) {
          keep = SupportedPixels(frame.left_rectified, geometry, frame.texture_block_px, min_texture,
                                 frame.up_rectified);
        }
        if (options.hidden_drops && !take_found) {
          lip = internal::FindHiddenDrops(frame.cloud, world_T_rectified, frame.depth_noise_per_m2, vehicle, range,
                                          options.pixel_stride);
        }
      });
  const ImageU8* lips = options.hidden_drops ? (take_found ? &found : &lip) : nullptr;
  ClassifiedPointsInWorld(frame, world_T_rectified, options.pixel_stride, mask ? &keep : nullptr, points,
                          refine ? &refined : nullptr, lips);
  if (options.no_return_stride_px > 0) {
    AppendNoReturnRays(frame, world_T_rectified, geometry, options.no_return_stride_px, points);
  }
}

std::vector<ClassifiedPoint> MapPointsOfFrame(const FrameResult& frame, const Eigen::Isometry3d& world_T_rectified,
                                              const MappingOptions& options, const RectifiedGeometry& geometry,
                                              const VehicleOptions& vehicle) {
  std::vector<ClassifiedPoint> points;
  MapPointsOfFrame(frame, world_T_rectified, options, geometry, vehicle, &points);
  return points;
}

}  // namespace ssta
