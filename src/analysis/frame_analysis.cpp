#include "ssta/analysis/frame_analysis.h"

#include <algorithm>
#include <cmath>

#include "core/run_both.h"
#include "ssta/analysis/label_refinements.h"
#include "ssta/analysis/label_rule.h"
#include "ssta/analysis/surface_analyzer.h"
#include "ssta/core/error.h"
#include "ssta/stereo/stereo_matcher.h"

namespace ssta {

using internal::RunBoth;

const OptionFields<AnalysisOptions>& AnalysisOptions::Fields() {
  using O = AnalysisOptions;
  static const OptionFields<O> fields = [] {
    OptionFields<O> f;
    f.push_back(Real<O>("inliers_min_ratio", &O::inliers_min_ratio, ClosedOpen(0, 1), "",
                        "inliers_min = ratio * width * height (eq. 4): smaller segments are small"));
    f.push_back(Flag<O>("pixel_slopes", &O::pixel_slopes,
                        "a traversable or semi pixel whose own normal is steeper takes that slope class "
                        "(smooth hillsides have no segment boundary), and with step_reference local a semi "
                        "pixel whose normal is gentler becomes traversable; false: the paper"));
    f.push_back(Integer<O>("pixel_slope_window_px", &O::pixel_slope_window_px, Closed(1, 255), "px",
                           "that normal is the mean over a box this wide within the pixel's segment; 1: its own")
                    .Require([](const O& o) { return o.pixel_slope_window_px % 2 == 1; }, "must be odd"));
    f.push_back(Choice<O, StepReference>("step_reference", &O::step_reference, StepReferenceNames(),
                          "dominant_plane: centroid distance to the ground plane (eq. 5) | reachable: class "
                          "of the best way from the ground across segment boundaries | reachable_large: "
                          "eq. 5, but a large segment that eq. 5 calls non-traversable takes its reachable class | "
                          "local: the largest height jump within step_radius_m of each point (the class rule "
                          "of docs/interfaces.md, section 3)"));
    f.push_back(Choice<O, SmallSegmentPolicy>("small_segments", &O::small_segments, SmallSegmentPolicyNames(),
                          "what segments below inliers_min get: paper (undecided) | obstacles (non-traversable "
                          "when off the ground by more than max_step_m or steeper than max_slope_deg) | all "
                          "(obstacles, and any with min_plane_points points gets its class)"));
    f.push_back(Integer<O>("min_plane_points", &O::min_plane_points, AtLeast(3), "points",
                           "fewest points for the slope of a small segment to count"));
    f.push_back(Real<O>("min_ground_share", &O::min_ground_share, Closed(0, 1), "",
                        "quality check: least share of the depth pixels on the ground plane"));
    f.push_back(Real<O>("max_ground_rms_m", &O::max_ground_rms_m, Above(0), "m",
                        "quality check: largest RMS of the ground plane fit"));
    f.push_back(Real<O>("ground_tolerance_px", &O::ground_tolerance_px, Closed(0, 16), "px",
                        "a small segment whose disparities lie this close to the ground plane's is ground "
                        "(disparity noise does not grow with range); 0: off"));
    f.push_back(Real<O>("ground_consistent_share", &O::ground_consistent_share, OpenClosed(0, 1), "",
                        "share of a small segment's points that must be that close"));
    f.push_back(Real<O>("fragment_tolerance_px", &O::fragment_tolerance_px, Closed(0, 16), "px",
                        "a small segment whose points lie within this of a large neighbour's plane, in "
                        "disparity along their rays, is a piece of it and takes its verdict; 0: off"));
    f.push_back(Real<O>("fragment_consistent_share", &O::fragment_consistent_share, OpenClosed(0, 1), "",
                        "share of the small segment's points that must be that close"));
    f.push_back(Integer<O>("fragment_host_min_points", &O::fragment_host_min_points, AtLeast(3), "points",
                           "fewest points of a segment whose plane takes in fragments (and more than twice "
                           "the fragment's)"));
    f.push_back(Integer<O>("undecided_fill_radius_px", &O::undecided_fill_radius_px, Closed(0, 64), "px",
                           "an undecided pixel takes the class that undecided_fill_share of the decided pixels "
                           "within this radius hold; 0: off"));
    f.push_back(Real<O>("undecided_fill_share", &O::undecided_fill_share, OpenClosed(0.5, 1), "",
                        "share of the window's decided pixels that must agree"));
    f.push_back(Flag<O>("undecided_height_fill", &O::undecided_height_fill,
                        "an undecided pixel left then takes the step class of its own height above the "
                        "ground plane where that is drivable"));
    f.push_back(Real<O>("label_min_texture", &O::label_min_texture, ClosedOpen(0, 128), "grey levels",
                        "pixels above the horizon whose left-image standard deviation over the stereo block "
                        "is lower are labelled unknown: the sky, where matching finds noise (below the "
                        "horizon a blank surface is a surface); 0: off"));
    f.push_back(Real<O>("texture_noise_multiple", &O::texture_noise_multiple, Closed(0, 10), "",
                        "the texture tests (label_min_texture, map.min_texture) ask for at least this many "
                        "times the image's sensor noise, estimated from the image itself, where that is more "
                        "than their grey levels: a noisy camera's sky has no texture to match; 0: off"));
    f.push_back(OddOrOff<O>("face_window_px", &O::face_window_px, Closed(3, 63), "px",
                            "thin vertical faces (a curb's front): the disparity fitted along the image column "
                            "over this many rows gives the surface's rise along the column; 0: off"));
    f.push_back(Integer<O>("face_columns_px", &O::face_columns_px, Closed(1, 63), "px",
                           "the column fits of this many neighbouring columns are pooled; 1: each alone")
                    .Require([](const O& o) { return o.face_columns_px % 2 == 1; }, "must be odd"));
    f.push_back(Real<O>("face_min_slope_deg", &O::face_min_slope_deg, Open(0, 90), "deg",
                        "a pixel rising steeper than this along its column is on a face: non-traversable"));
    f.push_back(Real<O>("face_grow_tolerance_px", &O::face_grow_tolerance_px, Closed(0, 5), "px",
                        "rows within the window whose disparity is a face's within this join it; 0: off"));
    return f;
  }();
  return fields;
}

bool AnalysisOptions::IsValid(std::string* error) const { return CheckOptions(*this, Fields(), error); }

FrameAnalyzer::FrameAnalyzer(const VehicleOptions& vehicle, const AnalysisOptions& options, double disparity_sigma_px)
    : vehicle_(vehicle), options_(options), disparity_sigma_px_(disparity_sigma_px) {
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
  // Three steps do their costly part on inputs the others do not change: the pixel slopes on
  // the normals, the face test on the disparity, the local steps on the cloud. Each runs beside
  // the steps before it:
  //   AnalyzeSurfaces                              | pixel slope classes
  //   apply slopes, ground consistency, fragments  | face search, local step classes
  //   apply local steps, apply faces, consensus fill, height fill
  // The slope classes are computed before the quality check is known: on a frame that fails it
  // (all undecided) they are wasted, at most the time they take beyond AnalyzeSurfaces.
  AnalysisResult a;
  const DepthNoise noise{disparity_sigma_px_ / focal_times_baseline};
  RunBoth([&] { a = AnalyzeSurfaces(cloud, segment_ids, in.num_segments, up, vehicle_, options, noise); },
          [&] {
            if (options.pixel_slopes) {
              PixelSlopeClasses(*in.normals, up, vehicle_, &segment_ids, options.pixel_slope_window_px,
                                &slope_classes_);
            }
          });
  // Each step's changes go to a.rules; only the first lambda and the steps after both touch it.
  LabelRuleTracker& track = rule_tracker_;
  RunBoth(
      [&] {
        track.Begin(a.labels);
        if (options.pixel_slopes && a.quality.passed) {
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
        // Only for a frame that passed the quality check (known from here on): on the others
        // the faces are not applied, and the search would keep the chain waiting.
        if (options.face_window_px > 0 && a.quality.passed) {
          FindDisparityFaces(*in.disparity, g.f, g.cu, g.cv, up, options, &faces_);
        }
        if (options.step_reference == StepReference::kLocal && a.quality.passed) {
          LocalStepClasses(cloud, *in.normals, up, vehicle_, noise, &step_classes_, in.supported);
        }
      });
  if (options.step_reference == StepReference::kLocal && a.quality.passed) {
    ApplyLocalStepClasses(step_classes_, &a.labels);
    track.Mark(a.labels, LabelRule::kLocalStep, &a.rules);
  }
  if (a.quality.passed) {
    if (options.face_window_px > 0) {
      ApplyDisparityFaces(faces_, *in.disparity, options, &a.labels);
      track.Mark(a.labels, LabelRule::kDisparityFace, &a.rules);
    }
    FillUndecidedByConsensus(options, &a.labels);
    track.Mark(a.labels, LabelRule::kConsensusFill, &a.rules);
    // Heights above the dominant plane are eq. 5's steps: the local rule has its own.
    if (options.step_reference != StepReference::kLocal) {
      FillUndecidedByHeight(cloud, focal_times_baseline, vehicle_, options, &a);
      track.Mark(a.labels, LabelRule::kHeightFill, &a.rules);
    }
  }
  return a;
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
