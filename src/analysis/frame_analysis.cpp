#include "ssta/analysis/frame_analysis.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "analysis/hidden_drops.h"
#include "core/run_both.h"
#include "ssta/analysis/label_refinements.h"
#include "ssta/analysis/label_rule.h"
#include "ssta/analysis/surface_analyzer.h"
#include "ssta/core/error.h"
#include "ssta/core/units.h"
#include "ssta/stereo/stereo_matcher.h"

namespace ssta {

using internal::FindFramesHiddenDrops;
using internal::RunBoth;

FrameAnalyzer::FrameAnalyzer(const VehicleOptions& vehicle, const AnalysisOptions& options, double disparity_sigma_px,
                             int match_window_px, double hidden_drop_range_m)
    : vehicle_(vehicle), options_(options), disparity_sigma_px_(disparity_sigma_px), match_window_px_(match_window_px),
      hidden_drop_range_m_(hidden_drop_range_m) {
  SSTA_CHECK(match_window_px >= 1, "FrameAnalyzer: the match window must be at least 1 px");
  SSTA_CHECK(hidden_drop_range_m >= 0, "FrameAnalyzer: the hidden drops' range must not be negative");
  std::string error;
  if (!vehicle_.IsValid(&error)) throw Error("vehicle." + error);
  if (!options_.IsValid(&error)) throw Error("analysis." + error);
}

AnalysisResult FrameAnalyzer::Analyze(const FrameAnalysisInput& in) {
  SSTA_CHECK(in.geometry && in.disparity && in.cloud && in.normals && in.segment_ids,
             "FrameAnalyzer::Analyze: every input must be set");
  const RectifiedGeometry& g = *in.geometry;
  const Image3f& cloud = *in.cloud;
  const ImageI32& segment_ids = *in.segment_ids;
  const Eigen::Vector3d& up = in.up_rectified;
  const double focal_times_baseline = g.f * g.baseline_m;
  const AnalysisOptions& options = options_;
  // Four steps do their costly part on inputs the others do not change: the pixel slopes on
  // the normals, the face test on the disparity, the local steps and the lips on the cloud. Each
  // runs beside the steps before it:
  //   AnalyzeSurfaces                              | pixel slope classes, lips
  //   apply slopes, ground consistency, fragments  | face search, local step classes
  //   apply local steps, apply faces, consensus fill, height fill, apply lips
  // The slope classes and the lips are found before the quality check is known: on a frame it
  // leaves unjudged (all undecided) they are wasted, at most the time they take beyond
  // AnalyzeSurfaces.
  AnalysisResult a;
  const DepthNoise noise{disparity_sigma_px_ / focal_times_baseline, match_window_px_};
  RunBoth([&] { a = AnalyzeSurfaces(cloud, segment_ids, in.num_segments, up, vehicle_, options, noise); },
          [&] {
            if (options.pixel_slopes) {
              PixelSlopeClasses(*in.normals, up, vehicle_, &segment_ids, options.pixel_slope_window_px,
                                &slope_classes_);
            }
            if (options.hidden_drops) {
              lips_ = FindFramesHiddenDrops(cloud, up, noise.per_m2, vehicle_, hidden_drop_range_m_);
            }
          });
  // Each step's changes go to a.rules; only the first lambda and the steps after both touch it.
  LabelRuleTracker& track = rule_tracker_;
  // A frame the local rule judges although its plane holds too little of the view
  // (QualityCheck::judged) gets every refinement but those that read the plane.
  const bool judged = a.quality.judged;
  // The local steps' "above the camera" follows the frame's ground where the vehicle may stand
  // on it: up a slope the ground ahead rises above the camera's level.
  Eigen::Vector3d ground_up = up;
  if (a.ground.found) {
    const Eigen::Vector3d n = a.ground.plane.head<3>().normalized();
    if (n.dot(up) >= std::cos(DegToRad(vehicle_.max_slope_deg))) ground_up = n;
  }
  RunBoth(
      [&] {
        track.Begin(a.labels);
        if (options.pixel_slopes && judged) {
          // Under the local rule a segment's verdict is its slope's alone, so a gentler pixel may relax it.
          ApplyPixelSlopeClasses(slope_classes_, &a.labels, options.step_reference == StepReference::kLocal);
          track.Mark(a.labels, LabelRule::kPixelSlope, &a.rules);
        }
        RefineByGroundDisparity(cloud, segment_ids, focal_times_baseline, options, &a);
        track.Mark(a.labels, LabelRule::kGroundDisparity, &a.rules);
        RefineByFragmentPlanes(cloud, segment_ids, focal_times_baseline, options, &a);
        track.Mark(a.labels, LabelRule::kFragmentPlane, &a.rules);
      },
      [&] {
        // Only for a judged frame (known from here on): on the others the faces are not
        // applied, and the search would keep the chain waiting.
        if (options.face_window_px > 0 && judged) {
          FindDisparityFaces(*in.disparity, g.f, g.cu, g.cv, up, options, &faces_);
        }
        if (options.step_reference == StepReference::kLocal && judged) {
          LocalStepClasses(cloud, *in.normals, up, vehicle_, noise, &step_classes_, in.supported, &ground_up);
        }
      });
  if (judged) ApplyAfterBoth(in, &a);
  // The map takes the lips as they are (empty when off).
  a.lips = std::move(lips_);
  a.lips_range_m = hidden_drop_range_m_;
  return a;
}

void FrameAnalyzer::ApplyAfterBoth(const FrameAnalysisInput& in, AnalysisResult* a) {
  const AnalysisOptions& options = options_;
  LabelRuleTracker& track = rule_tracker_;
  const bool local_steps = options.step_reference == StepReference::kLocal;
  if (local_steps) {
    ApplyLocalStepClasses(step_classes_, &a->labels);
    track.Mark(a->labels, LabelRule::kLocalStep, &a->rules);
  }
  if (options.face_window_px > 0) {
    ApplyDisparityFaces(faces_, *in.disparity, options, &a->labels);
    // The tracker still holds the labels from before the faces.
    if (options.face_by_height) JudgeFacesByHeight(*in.cloud, in.up_rectified, vehicle_, track.Before(), &a->labels);
    track.Mark(a->labels, LabelRule::kDisparityFace, &a->rules);
  }
  FillUndecidedByConsensus(options, &a->labels, local_steps ? &step_classes_ : nullptr);
  track.Mark(a->labels, LabelRule::kConsensusFill, &a->rules);
  // Heights above the dominant plane are eq. 5's steps: the local rule has its own.
  if (!local_steps) {
    FillUndecidedByHeight(*in.cloud, in.geometry->f * in.geometry->baseline_m, vehicle_, options, a);
    track.Mark(a->labels, LabelRule::kHeightFill, &a->rules);
  }
  // Last, so that no fill spreads a lip's doubt.
  if (options.hidden_drops) {
    ApplyHiddenDrops(lips_, &a->labels);
    track.Mark(a->labels, LabelRule::kHiddenDrop, &a->rules);
  }
  // After every fill, which read these pixels as undecided; the map does too (their rule).
  if (local_steps && options.smeared_step_blocks) {
    ApplySmearedStepBand(step_classes_, &a->labels);
    track.Mark(a->labels, LabelRule::kSmearedStep, &a->rules);
  }
}

ImageU8 TexturedPixels(const ImageU8& left_rectified, const RectifiedGeometry& geometry, int block, double min_std) {
  return TextureMask(left_rectified, geometry.crop_u0, geometry.crop_v0, geometry.crop_width, geometry.crop_height,
                     block, min_std);
}

ImageU8 SupportedPixels(const ImageU8& left_rectified, const RectifiedGeometry& g, int block, double min_std,
                        const Eigen::Vector3d& up_rectified) {
  ImageU8 supported = TexturedPixels(left_rectified, g, block, min_std);
  for (int v = 0; v < g.crop_height; ++v) {
    std::uint8_t* row = supported.row(v);
    for (int u = 0; u < g.crop_width; ++u) {
      const Eigen::Vector3d ray((u - g.cu) / g.f, (v - g.cv) / g.f, 1.0);
      if (ray.dot(up_rectified) < 0.0) row[u] = 1;
    }
  }
  return supported;
}

namespace {

/// The texture a matcher can use at (u, v) of `image`: the grey-level standard deviation along
/// each row of the `block` x `block` window (clipped at the border), pooled over its rows. A
/// horizontal edge has a large standard deviation over the window but none along the epipolar
/// lines, where the matcher searches: it fixes no disparity.
double RowTexture(const ImageU8& image, int u, int v, int block) {
  const int r = block / 2;
  const int u0 = std::max(0, u - r), u1 = std::min(image.width() - 1, u + r);
  const int v0 = std::max(0, v - r), v1 = std::min(image.height() - 1, v + r);
  const int n = u1 - u0 + 1;
  if (n < 2) return 0.0;
  double sum_squares = 0.0;
  for (int y = v0; y <= v1; ++y) {
    const std::uint8_t* row = image.row(y);
    double sum = 0.0, sum_sq = 0.0;
    for (int x = u0; x <= u1; ++x) {
      sum += row[x];
      sum_sq += static_cast<double>(row[x]) * row[x];
    }
    sum_squares += sum_sq - sum * sum / n;
  }
  return std::sqrt(sum_squares / ((v1 - v0 + 1) * n));
}

}  // namespace

ImageU8 SupportedPixels(const ImageU8& left_rectified, const RectifiedGeometry& g, int block, double min_std,
                        const Eigen::Vector3d& up_rectified, const ImageF& disparity) {
  SSTA_CHECK(disparity.width() == g.crop_width && disparity.height() == g.crop_height,
             "SupportedPixels: the disparity must have the common area's size");
  const ImageU8 textured = TexturedPixels(left_rectified, g, block, min_std);
  ImageU8 supported(g.crop_width, g.crop_height, 0);
  // Column by column from the bottom up, against the closest valid pixel below (within
  // kMaxGapRows): a pixel without texture along its row that is nearer than it starts a floating
  // piece, which the pixels above on the same surface continue; a pixel without texture above
  // the horizon is supported when it continues a supported surface.
  constexpr int kMaxGapRows = 32;
  constexpr float kSameSurface = 0.1f;  // relative disparity (depth) difference within a piece
  constexpr float kMinJumpPx = 1.0f;    // least jump nearer that starts a piece [px]
  constexpr float kWallSurface = 0.05f; // relative disparity step of a wall's rows
  // A blank wall is kept where its depth is known to 5 % (20 times SGBM's 0.25 px noise); a
  // blank sky taking the disparity of the far ground or skyline below it is not.
  constexpr float kMinWallDisparityPx = 5.0f;
  for (int u = 0; u < g.crop_width; ++u) {
    float below_d = 0.0f;
    int below_v = -1;
    bool below_floating = false, below_supported = false;
    bool jumped = false;  // the current run of one surface began nearer than the pixel below it
    for (int v = g.crop_height - 1; v >= 0; --v) {
      const Eigen::Vector3d ray((u - g.cu) / g.f, (v - g.cv) / g.f, 1.0);
      const bool below_horizon = ray.dot(up_rectified) < 0.0;
      const bool has_texture = textured(v, u) != 0;
      const float d = disparity(v, u);
      if (!(d > 0.0f)) {
        supported(v, u) = has_texture || below_horizon;  // no point: nothing to label
        continue;
      }
      const bool near_below = below_v >= 0 && below_v - v <= kMaxGapRows;
      bool floating = false, ok = has_texture || below_horizon;
      const float tolerance = std::max(kMinJumpPx, kSameSurface * d);
      const bool same_surface = near_below && std::abs(d - below_d) <= tolerance;
      if (!same_surface) jumped = near_below && d > below_d + tolerance;
      if (same_surface && below_floating && below_horizon) {
        floating = true;
      } else if (jumped && below_horizon &&
                 RowTexture(left_rectified, u + g.crop_u0, v + g.crop_v0, block) < min_std) {
        floating = true;  // the first pixel of the run without texture along its row
      }
      if (near_below) {
        if (!ok && below_supported && d >= kMinWallDisparityPx &&
            std::abs(d - below_d) <= std::max(kMinJumpPx, kWallSurface * d)) {
          ok = true;
        }
      }
      if (floating) ok = false;
      supported(v, u) = ok;
      below_d = d;
      below_v = v;
      below_floating = floating;
      below_supported = ok;
    }
  }
  return supported;
}

}  // namespace ssta
