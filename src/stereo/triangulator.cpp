#include "ssta/stereo/triangulator.h"

#include <cmath>
#include <sstream>

#include "ssta/core/error.h"

namespace ssta {

const OptionFields<TriangulationOptions>& TriangulationOptions::Fields() {
  using O = TriangulationOptions;
  static const OptionFields<O> fields = [] {
    OptionFields<O> f;
    f.push_back(Real<O>("min_range_m", &O::min_range_m, AtLeast(0), "m", "nearer points (depth Z) are dropped"));
    f.push_back(Real<O>("max_range_m", &O::max_range_m, Above(0), "m", "farther points (depth Z) are dropped")
                    .Require([](const O& o) { return o.max_range_m > o.min_range_m; },
                             [](const O& o) {
                               return "must be greater than min_range_m (max_range_m " + ShortestDecimal(o.max_range_m) +
                                      ", min_range_m " + ShortestDecimal(o.min_range_m) + ")";
                             }));
    return f;
  }();
  return fields;
}

bool TriangulationOptions::IsValid(std::string* error) const { return CheckOptions(*this, Fields(), error); }

Image3f Triangulate(const ImageF& disparity, const RectifiedGeometry& geometry,
                    const TriangulationOptions& options) {
  SSTA_CHECK(disparity.width() == geometry.crop_width &&
                 disparity.height() == geometry.crop_height,
             "Triangulate: the disparity image must have the geometry's crop size");
  SSTA_CHECK(geometry.f > 0.0 && geometry.baseline_m > 0.0,
             "Triangulate: the geometry needs a positive focal length and baseline");
  std::string why;
  SSTA_CHECK(options.IsValid(&why), "Triangulate: " + why);

  const double fb = geometry.f * geometry.baseline_m;
  const double inv_f = 1.0 / geometry.f;
  Image3f points(disparity.width(), disparity.height(), NanVector3f());
  for (int v = 0; v < disparity.height(); ++v) {
    const float* d_row = disparity.row(v);
    Eigen::Vector3f* p_row = points.row(v);
    const double y_over_z = (v - geometry.cv) * inv_f;
    for (int u = 0; u < disparity.width(); ++u) {
      const double d = d_row[u];
      if (!(d > 0.0)) continue;  // also rejects NaN
      const double z = fb / d;
      if (!(z >= options.min_range_m && z <= options.max_range_m)) continue;
      p_row[u] = Eigen::Vector3f(static_cast<float>((u - geometry.cu) * inv_f * z),
                                 static_cast<float>(y_over_z * z), static_cast<float>(z));
    }
  }
  return points;
}

}  // namespace ssta
