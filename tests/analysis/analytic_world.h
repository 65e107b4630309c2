#pragma once

// The analytic worlds of the analysis tests: regions of planes painted into an organized cloud
// with known segment ids, whose planes, slopes and steps are known in closed form.

#include <algorithm>
#include <cmath>

#include <Eigen/Core>

#include "ssta/analysis/frame_analysis.h"
#include "ssta/analysis/surface_analyzer.h"
#include "ssta/core/vehicle_options.h"
#include "ssta/core/image.h"

namespace ssta::testing {

/// The segment verdicts alone, which most of these tests check: steps against the dominant plane
/// (eq. 5), small obstacles flagged, and none of the label refinements.
inline AnalysisOptions PlanesOnly() {
  AnalysisOptions o;
  o.pixel_slopes = false;
  o.pixel_slope_window_px = 1;
  o.step_reference = StepReference::kDominantPlane;
  o.small_segments = SmallSegmentPolicy::kObstacles;
  o.ground_tolerance_px = 0.0;
  o.fragment_tolerance_px = 0.0;
  o.undecided_fill_radius_px = 0;
  o.undecided_height_fill = false;
  o.face_window_px = 0;
  o.face_columns_px = 1;
  o.face_grow_tolerance_px = 0.0;
  return o;
}

// An analytic world seen by a level camera 1 m above a floor (camera y points down, so up is
// -y). Regions are painted into an organized cloud with known segment ids; the analysis must
// recover planes, slopes, steps and classes in closed form.
class AnalyticWorld {
 public:
  AnalyticWorld(int width, int height) : cloud_(width, height, NanVector3f()), ids_(width, height, -1) {}

  /// Fills rows [v0, v1) x cols [u0, u1) with points of the plane through `origin` spanned by
  /// `a` and `b` (grid coordinates scaled by `step`), all in segment `id`.
  void Paint(int id, int v0, int v1, int u0, int u1, const Eigen::Vector3d& origin,
             const Eigen::Vector3d& a, const Eigen::Vector3d& b, double step = 0.02) {
    for (int v = v0; v < v1; ++v) {
      for (int u = u0; u < u1; ++u) {
        const Eigen::Vector3d p = origin + a * (u - u0) * step + b * (v - v0) * step;
        cloud_(v, u) = p.cast<float>();
        ids_(v, u) = id;
      }
    }
    num_segments_ = std::max(num_segments_, id + 1);
  }

  AnalysisResult Analyze(const VehicleOptions& vehicle = {}, AnalysisOptions options = PlanesOnly(),
                         const DepthNoise& noise = {}) const {
    return AnalyzeSurfaces(cloud_, ids_, num_segments_, kUp, vehicle, options, noise);
  }

  static inline const Eigen::Vector3d kUp{0, -1, 0};
  Image3f cloud_;
  ImageI32 ids_;
  int num_segments_ = 0;
};

// Floor 1 m below the camera, spanning x and z.
inline void PaintFloor(AnalyticWorld& w, int id, int v0, int v1, int u0, int u1, double height = 1.0) {
  w.Paint(id, v0, v1, u0, u1, {-1.0, height, 2.0}, {1, 0, 0}, {0, 0, 1});
}

// A ramp rising at `slope_deg` away from the camera.
inline void PaintRamp(AnalyticWorld& w, int id, int v0, int v1, int u0, int u1, double slope_deg) {
  const double s = slope_deg * M_PI / 180.0;
  w.Paint(id, v0, v1, u0, u1, {0.5, 1.0, 2.0}, {1, 0, 0}, {0, -std::sin(s), std::cos(s)});
}

}  // namespace ssta::testing
