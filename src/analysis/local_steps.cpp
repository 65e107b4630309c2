// The step of docs/interfaces.md, section 3 on one frame's points (RefineByLocalSteps).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Geometry>

#include "ssta/analysis/label_refinements.h"
#include "ssta/core/error.h"

namespace ssta {
namespace {

constexpr auto kUndecided = static_cast<std::uint8_t>(TravClass::kUndecided);
constexpr auto kNon = static_cast<std::uint8_t>(TravClass::kNonTraversable);

/// A point in the levelled frame: east, north and up of the camera.
struct LevelledPoint {
  std::uint32_t pixel;
  float x, y, h;
  bool above_camera;     ///< out of the grid's heights (LocalStepClasses)
  float relative_sigma;  ///< 1-sigma of its depth over its depth: k Z
  float smear_squared;   ///< square of the 1-sigma of its error along its ray [m^2]: (k Z |p|)^2
};

/// The frame's points on a grid of horizontal cells in the levelled frame.
class HeightGrid {
 public:
  HeightGrid(const std::vector<LevelledPoint>& points, const Image3f& normals, const Eigen::Vector3d& up,
             double cell_m, double max_slope_deg)
      : cell_m_(static_cast<float>(cell_m)), per_cell_(1.0f / static_cast<float>(cell_m)) {
    const Eigen::Vector3d east = up.unitOrthogonal();
    const Eigen::Vector3d north = up.cross(east);
    Bounds(points);
    const std::size_t cells = static_cast<std::size_t>(nx_) * ny_;
    cell_of_.resize(points.size());
    std::vector<float> sum_h(cells, 0.0f), sum_var(cells, 0.0f);
    std::vector<Eigen::Vector3f> sum_normal(cells, Eigen::Vector3f::Zero());
    count_.assign(cells, 0);
    for (std::size_t k = 0; k < points.size(); ++k) {
      const LevelledPoint& p = points[k];
      const int c = CellOf(p.x, p.y);
      cell_of_[k] = c;
      // Above the camera lies nothing the wheels meet, and the sky's false matches lie there:
      // a surface's lower part below the camera tells its jump.
      if (c < 0 || p.above_camera) continue;
      const float sigma = p.relative_sigma * std::abs(p.h);  // the error along the ray, seen in height
      sum_h[c] += p.h;
      sum_var[c] += sigma * sigma;
      ++count_[c];
      const Eigen::Vector3f& n = normals[p.pixel];
      if (IsFinite(n)) sum_normal[c] += n;
    }
    const double min_up = std::cos(max_slope_deg * 3.14159265358979323846 / 180.0);
    height_.assign(cells, std::numeric_limits<float>::quiet_NaN());
    sigma_.assign(cells, 0.0f);
    gradient_.assign(cells, Eigen::Vector2f::Zero());
    for (std::size_t c = 0; c < cells; ++c) {
      if (count_[c] == 0) continue;
      height_[c] = sum_h[c] / static_cast<float>(count_[c]);
      // Neighbouring pixels' errors are correlated over the matcher's block: a cell's points
      // are worth a few independent measurements, not all of them.
      sigma_[c] = std::sqrt(sum_var[c] / static_cast<float>(count_[c]) / static_cast<float>(std::min(count_[c], 4)));
      const Eigen::Vector3d n = sum_normal[c].cast<double>().normalized();
      const double n_up = n.dot(up);
      if (sum_normal[c].squaredNorm() > 0 && n_up >= min_up) {
        gradient_[c] = Eigen::Vector2f(static_cast<float>(-n.dot(east) / n_up), static_cast<float>(-n.dot(north) / n_up));
      }
    }
  }

  /// The cell of the k-th point; -1 outside the grid.
  int CellOfPoint(std::size_t k) const { return cell_of_[k]; }

  /// The step of every cell: the largest height difference within `radius_m`, beyond the
  /// cell's gradient and one sigma of each side's noise.
  std::vector<float> Steps(double radius_m) const {
    const int reach = static_cast<int>(std::floor(radius_m / cell_m_ + 1e-6));
    std::vector<Eigen::Vector2i> disc;
    for (int dj = -reach; dj <= reach; ++dj) {
      for (int di = -reach; di <= reach; ++di) {
        if ((di * di + dj * dj) * static_cast<double>(cell_m_) * cell_m_ <= radius_m * radius_m + 1e-6 * radius_m) {
          disc.emplace_back(di, dj);
        }
      }
    }
    std::vector<float> step(height_.size(), 0.0f);
    for (int j = 0; j < ny_; ++j) {
      for (int i = 0; i < nx_; ++i) {
        const int c = j * nx_ + i;
        if (count_[c] == 0) continue;
        float hi = -std::numeric_limits<float>::infinity(), lo = -hi;
        for (const Eigen::Vector2i& d : disc) {
          const int ii = i + d.x(), jj = j + d.y();
          if (ii < 0 || jj < 0 || ii >= nx_ || jj >= ny_) continue;
          const int q = jj * nx_ + ii;
          if (count_[q] == 0) continue;
          const float residual = height_[q] - height_[c] - cell_m_ * (gradient_[c].x() * d.x() + gradient_[c].y() * d.y());
          hi = std::max(hi, residual - sigma_[q]);
          lo = std::min(lo, residual + sigma_[q]);
        }
        step[c] = std::max(0.0f, hi - lo);
      }
    }
    return step;
  }

 private:
  int CellOf(float x, float y) const {
    const int i = static_cast<int>(std::floor((x - x0_) * per_cell_));
    const int j = static_cast<int>(std::floor((y - y0_) * per_cell_));
    if (i < 0 || j < 0 || i >= nx_ || j >= ny_) return -1;
    return j * nx_ + i;
  }

  void Bounds(const std::vector<LevelledPoint>& points) {
    constexpr float kLimitM = 200.0f;  // a point farther than this sideways is not on a map
    float x0 = kLimitM, y0 = kLimitM, x1 = -kLimitM, y1 = -kLimitM;
    for (const LevelledPoint& p : points) {
      x0 = std::min(x0, p.x);
      y0 = std::min(y0, p.y);
      x1 = std::max(x1, p.x);
      y1 = std::max(y1, p.y);
    }
    x0_ = std::max(x0, -kLimitM);
    y0_ = std::max(y0, -kLimitM);
    nx_ = x1 >= x0_ ? static_cast<int>(std::floor((std::min(x1, kLimitM) - x0_) / cell_m_)) + 1 : 0;
    ny_ = y1 >= y0_ ? static_cast<int>(std::floor((std::min(y1, kLimitM) - y0_) / cell_m_)) + 1 : 0;
  }

  float cell_m_;
  float per_cell_;  // 1 / cell_m_
  float x0_ = 0, y0_ = 0;
  int nx_ = 0, ny_ = 0;
  std::vector<int> cell_of_;
  std::vector<int> count_;
  std::vector<float> height_, sigma_;
  std::vector<Eigen::Vector2f> gradient_;
};

}  // namespace

void LocalStepClasses(const Image3f& cloud, const Image3f& normals, const Eigen::Vector3d& up_camera,
                      const VehicleOptions& vehicle, const DepthNoise& noise, ImageU8* step_classes,
                      const ImageU8* supported, const Eigen::Vector3d* ground_up) {
  SSTA_CHECK(step_classes != nullptr && normals.width() == cloud.width() && normals.height() == cloud.height(),
             "LocalStepClasses: cloud and normals differ in size");
  SSTA_CHECK(supported == nullptr || (supported->width() == cloud.width() && supported->height() == cloud.height()),
             "LocalStepClasses: supported pixels and cloud differ in size");
  if (step_classes->width() != cloud.width() || step_classes->height() != cloud.height()) {
    *step_classes = ImageU8(cloud.width(), cloud.height(), 0);
  } else {
    step_classes->Fill(0);
  }
  // The grid holds the points whose depth error along their ray stays within twice the step
  // radius: beyond it a point could lie in any of the cells around.
  const float radius = static_cast<float>(vehicle.step_radius_m);
  const Eigen::Vector3f up = up_camera.cast<float>();
  const Eigen::Vector3f east = up_camera.unitOrthogonal().cast<float>();
  const Eigen::Vector3f north = up.cross(east);
  const auto max_step = static_cast<float>(vehicle.max_step_m);
  const Eigen::Vector3f ceiling = ground_up != nullptr ? ground_up->cast<float>() : up;
  const auto per_m2 = static_cast<float>(noise.per_m2);
  thread_local std::vector<LevelledPoint> points;  // kept between frames
  points.clear();
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3f& p = cloud[i];
    if (!IsFinite(p) || (supported != nullptr && (*supported)[i] == 0)) continue;
    const float relative_sigma = per_m2 * p.z();
    const float smear_squared = relative_sigma * relative_sigma * p.squaredNorm();
    if (smear_squared > 4.0f * radius * radius) continue;
    const float h = up.dot(p);
    // Above the camera's level, but up a slope what lies clearly below the plane through the
    // camera parallel to its ground counts (the margin: that plane's error at range).
    const bool above_camera = h > 0.0f && (smear_squared > radius * radius || ceiling.dot(p) + max_step > 0.0f);
    points.push_back({static_cast<std::uint32_t>(i), east.dot(p), north.dot(p), h, above_camera, relative_sigma,
                      smear_squared});
  }
  const HeightGrid grid(points, normals, up_camera, 0.5 * vehicle.step_radius_m, vehicle.max_slope_deg);
  const std::vector<float> steps = grid.Steps(vehicle.step_radius_m);
  std::vector<std::uint8_t> cell_class(steps.size());
  for (std::size_t c = 0; c < steps.size(); ++c) cell_class[c] = static_cast<std::uint8_t>(vehicle.ClassifyStep(steps[c]));
  for (std::size_t k = 0; k < points.size(); ++k) {
    // A point whose depth error smears it sideways over the step radius cannot tell which side
    // of a jump it lies on: beside one (its cell's step is non-traversable) it is undecided,
    // elsewhere it gets no step class.
    const int c = grid.CellOfPoint(k);
    if (c < 0) continue;
    const std::uint8_t cls = cell_class[static_cast<std::size_t>(c)];
    if (points[k].smear_squared > radius * radius) {
      if (cls == kNon) (*step_classes)[points[k].pixel] = kUndecided;
      continue;
    }
    (*step_classes)[points[k].pixel] = cls;
  }
}

void ApplyLocalStepClasses(const ImageU8& step_classes, ImageU8* labels) {
  SSTA_CHECK(labels != nullptr && labels->width() == step_classes.width() && labels->height() == step_classes.height(),
             "ApplyLocalStepClasses: step classes and labels differ in size");
  for (std::size_t i = 0; i < labels->size(); ++i) {
    std::uint8_t& label = (*labels)[i];
    const std::uint8_t step = step_classes[i];
    if (step == 0 || label == 0 || label > kUndecided) continue;
    if (step == kUndecided) {
      if (label != kNon) label = kUndecided;
    } else if (label == kUndecided) {
      if (step == kNon) label = kNon;
    } else {
      label = static_cast<std::uint8_t>(Worse(static_cast<TravClass>(label), static_cast<TravClass>(step)));
    }
  }
}

void ApplySmearedStepBand(const ImageU8& step_classes, ImageU8* labels) {
  SSTA_CHECK(labels != nullptr && labels->width() == step_classes.width() && labels->height() == step_classes.height(),
             "ApplySmearedStepBand: step classes and labels differ in size");
  for (std::size_t i = 0; i < labels->size(); ++i) {
    if ((*labels)[i] == kUndecided && step_classes[i] == kUndecided) (*labels)[i] = kNon;
  }
}

void RefineByLocalSteps(const Image3f& cloud, const Image3f& normals, const Eigen::Vector3d& up_camera,
                        const VehicleOptions& vehicle, const DepthNoise& noise, ImageU8* labels) {
  SSTA_CHECK(labels != nullptr && labels->width() == cloud.width() && labels->height() == cloud.height(),
             "RefineByLocalSteps: cloud and labels differ in size");
  ImageU8 step_classes;
  LocalStepClasses(cloud, normals, up_camera, vehicle, noise, &step_classes);
  ApplyLocalStepClasses(step_classes, labels);
}

}  // namespace ssta
