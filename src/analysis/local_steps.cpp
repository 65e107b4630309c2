// The step of docs/interfaces.md, section 3 on one frame's points (RefineByLocalSteps).

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Geometry>

#include "ssta/analysis/label_refinements.h"
#include "ssta/core/error.h"

namespace ssta {
namespace {

/// The frame's points on a grid of horizontal cells in the levelled frame.
class HeightGrid {
 public:
  HeightGrid(const Image3f& cloud, const Image3f& normals, const Eigen::Vector3d& up, double cell_m,
             const DepthNoise& noise, double max_slope_deg)
      : up_(up), cell_m_(cell_m) {
    east_ = up.unitOrthogonal();
    north_ = up.cross(east_);
    Bounds(cloud);
    const std::size_t cells = static_cast<std::size_t>(nx_) * ny_;
    sum_h_.assign(cells, 0.0f);
    sum_var_.assign(cells, 0.0f);
    count_.assign(cells, 0);
    sum_normal_.assign(cells, Eigen::Vector3f::Zero());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      const Eigen::Vector3f& p = cloud[i];
      if (!IsFinite(p)) continue;
      const double h = up.dot(p.cast<double>());
      // Above the camera lies nothing the wheels meet, and the sky's false matches lie there
      // (rays above the horizon): a surface's lower part below the camera tells its jump.
      if (h > 0.0) continue;
      const int c = CellOf(p.cast<double>());
      if (c < 0) continue;
      const double sigma = noise.per_m2 * p.z() * std::abs(h);
      sum_h_[c] += static_cast<float>(h);
      sum_var_[c] += static_cast<float>(sigma * sigma);
      ++count_[c];
      if (IsFinite(normals[i])) sum_normal_[c] += normals[i];
    }
    const double min_up = std::cos(max_slope_deg * 3.14159265358979323846 / 180.0);
    height_.assign(cells, std::numeric_limits<float>::quiet_NaN());
    sigma_.assign(cells, 0.0f);
    gradient_.assign(cells, Eigen::Vector2f::Zero());
    for (std::size_t c = 0; c < cells; ++c) {
      if (count_[c] == 0) continue;
      height_[c] = sum_h_[c] / static_cast<float>(count_[c]);
      // Neighbouring pixels' errors are correlated over the matcher's block: a cell's points
      // are worth a few independent measurements, not all of them.
      sigma_[c] = std::sqrt(sum_var_[c] / static_cast<float>(count_[c]) / static_cast<float>(std::min(count_[c], 4)));
      const Eigen::Vector3d n = sum_normal_[c].cast<double>().normalized();
      const double n_up = n.dot(up);
      if (sum_normal_[c].squaredNorm() > 0 && n_up >= min_up) {
        gradient_[c] = Eigen::Vector2f(static_cast<float>(-n.dot(east_) / n_up), static_cast<float>(-n.dot(north_) / n_up));
      }
    }
  }

  /// The cell of a point; -1 outside the grid.
  int CellOf(const Eigen::Vector3d& p) const {
    const int i = static_cast<int>(std::floor((east_.dot(p) - x0_) / cell_m_));
    const int j = static_cast<int>(std::floor((north_.dot(p) - y0_) / cell_m_));
    if (i < 0 || j < 0 || i >= nx_ || j >= ny_) return -1;
    return j * nx_ + i;
  }

  /// The step of every cell: the largest height difference within `radius_m`, beyond the
  /// cell's gradient and one sigma of each side's noise.
  std::vector<float> Steps(double radius_m) const {
    const int reach = static_cast<int>(std::floor(radius_m / cell_m_ + 1e-9));
    std::vector<Eigen::Vector2i> disc;
    for (int dj = -reach; dj <= reach; ++dj) {
      for (int di = -reach; di <= reach; ++di) {
        if ((di * di + dj * dj) * cell_m_ * cell_m_ <= radius_m * radius_m + 1e-12) disc.emplace_back(di, dj);
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
          const float residual = height_[q] - height_[c] -
                                 static_cast<float>(cell_m_) * (gradient_[c].x() * d.x() + gradient_[c].y() * d.y());
          hi = std::max(hi, residual - sigma_[q]);
          lo = std::min(lo, residual + sigma_[q]);
        }
        step[c] = std::max(0.0f, hi - lo);
      }
    }
    return step;
  }

 private:
  void Bounds(const Image3f& cloud) {
    constexpr double kLimitM = 200.0;  // a point farther than this sideways is not on a map
    double x0 = kLimitM, y0 = kLimitM, x1 = -kLimitM, y1 = -kLimitM;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      const Eigen::Vector3f& p = cloud[i];
      if (!IsFinite(p)) continue;
      const double x = east_.dot(p.cast<double>()), y = north_.dot(p.cast<double>());
      x0 = std::min(x0, x);
      y0 = std::min(y0, y);
      x1 = std::max(x1, x);
      y1 = std::max(y1, y);
    }
    x0_ = std::max(x0, -kLimitM);
    y0_ = std::max(y0, -kLimitM);
    nx_ = x1 >= x0_ ? static_cast<int>(std::floor((std::min(x1, kLimitM) - x0_) / cell_m_)) + 1 : 0;
    ny_ = y1 >= y0_ ? static_cast<int>(std::floor((std::min(y1, kLimitM) - y0_) / cell_m_)) + 1 : 0;
  }

  Eigen::Vector3d up_, east_, north_;
  double cell_m_;
  double x0_ = 0, y0_ = 0;
  int nx_ = 0, ny_ = 0;
  std::vector<float> sum_h_, sum_var_;
  std::vector<int> count_;
  std::vector<Eigen::Vector3f> sum_normal_;
  std::vector<float> height_, sigma_;
  std::vector<Eigen::Vector2f> gradient_;
};

}  // namespace

void RefineByLocalSteps(const Image3f& cloud, const Image3f& normals, const Eigen::Vector3d& up_camera,
                        const VehicleOptions& vehicle, const DepthNoise& noise, ImageU8* labels) {
  SSTA_CHECK(labels != nullptr && labels->width() == cloud.width() && labels->height() == cloud.height() &&
                 normals.width() == cloud.width() && normals.height() == cloud.height(),
             "RefineByLocalSteps: cloud, normals and labels differ in size");
  const HeightGrid grid(cloud, normals, up_camera, 0.5 * vehicle.step_radius_m, noise, vehicle.max_slope_deg);
  const std::vector<float> steps = grid.Steps(vehicle.step_radius_m);
  constexpr auto kUndecided = static_cast<std::uint8_t>(TravClass::kUndecided);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    std::uint8_t& label = (*labels)[i];
    if (label == 0 || label > kUndecided || !IsFinite(cloud[i])) continue;
    // A point whose depth error smears it sideways over the step radius cannot tell which side
    // of a jump it lies on: its label stays as the segment's.
    const Eigen::Vector3f& p = cloud[i];
    if (noise.per_m2 * p.z() * p.norm() > vehicle.step_radius_m) continue;
    const int c = grid.CellOf(p.cast<double>());
    if (c < 0) continue;
    const TravClass step = vehicle.ClassifyStep(steps[static_cast<std::size_t>(c)]);
    if (label == kUndecided) {
      if (step == TravClass::kNonTraversable) label = static_cast<std::uint8_t>(step);
    } else {
      label = static_cast<std::uint8_t>(Worse(static_cast<TravClass>(label), step));
    }
  }
}

}  // namespace ssta
