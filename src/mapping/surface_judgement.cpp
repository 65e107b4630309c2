#include "ssta/mapping/surface_judgement.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

#include "ssta/core/units.h"

namespace ssta {
namespace {

/// P(X <= x) for X ~ N(mean, sigma^2).
double NormalCdf(double x, double mean, double sigma) {
  return 0.5 * std::erfc(-(x - mean) / (sigma * std::sqrt(2.0)));
}

/// Probabilities of the three classes of a quantity estimated as `value` +- `sigma` against the
/// thresholds `semi` and `max` (class 1 up to semi, 2 up to max, 3 beyond).
std::array<double, 3> ClassProbabilities(double value, double sigma, double semi, double max) {
  const double below_semi = NormalCdf(semi, value, sigma), below_max = NormalCdf(max, value, sigma);
  return {below_semi, std::max(0.0, below_max - below_semi), 1.0 - below_max};
}

/// The height jump within the disc that the local surface does not explain: each column's
/// height less what `gradient` (the local plane's, dh/dx and dh/dy) rises from `centre`, taken
/// one sigma towards the plane; the step is the (rank + 1)-th highest of these less the
/// (rank + 1)-th lowest, so that `rank` stray columns (voxels of noise above the ground) make no
/// step, while a jump has columns on both of its sides. Its sigma is the noise of those two.
void LargestJump(const Eigen::Vector2d& centre, const std::vector<SurfaceSample>& s, const Eigen::Vector2d& gradient,
                 std::size_t rank, double* step, double* sigma) {
  struct Level {
    double value;
    double sigma;
  };
  std::vector<Level> upper, lower;
  for (const SurfaceSample& sample : s) {
    const double residual = sample.height_m - gradient.dot(sample.xy - centre);
    upper.push_back({residual - sample.sigma_m, sample.sigma_m});
    lower.push_back({residual + sample.sigma_m, sample.sigma_m});
  }
  const auto by_value = [](const Level& a, const Level& b) { return a.value > b.value; };
  std::nth_element(upper.begin(), upper.begin() + rank, upper.end(), by_value);
  std::nth_element(lower.begin(), lower.begin() + rank, lower.end(),
                   [](const Level& a, const Level& b) { return a.value < b.value; });
  *step = std::max(0.0, upper[rank].value - lower[rank].value);
  *sigma = std::hypot(upper[rank].sigma, lower[rank].sigma);
}

/// Weighted least-squares plane h = a + b dx + c dy through `s` (dx, dy from `centre`), with
/// Huber reweighting of the residuals. Returns false when the samples do not span a plane.
bool FitPlane(const Eigen::Vector2d& centre, const std::vector<SurfaceSample>& s, Eigen::Vector3d* plane,
              Eigen::Matrix3d* covariance) {
  std::vector<double> robust(s.size(), 1.0);
  for (int iteration = 0; iteration < 4; ++iteration) {
    Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
    Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < s.size(); ++i) {
      const Eigen::Vector3d row(1.0, s[i].xy.x() - centre.x(), s[i].xy.y() - centre.y());
      const double w = robust[i] / (s[i].sigma_m * s[i].sigma_m);
      normal += w * row * row.transpose();
      rhs += w * s[i].height_m * row;
    }
    const Eigen::LDLT<Eigen::Matrix3d> solver(normal);
    if (solver.info() != Eigen::Success || !(normal.determinant() > 1e-12 * normal.trace() * normal.trace())) {
      return false;
    }
    *plane = solver.solve(rhs);
    *covariance = normal.inverse();
    for (std::size_t i = 0; i < s.size(); ++i) {
      const Eigen::Vector3d row(1.0, s[i].xy.x() - centre.x(), s[i].xy.y() - centre.y());
      const double scale = 1.5 * std::max(s[i].sigma_m, 0.02);
      const double r = std::abs(s[i].height_m - row.dot(*plane));
      robust[i] = r <= scale ? 1.0 : scale / r;
    }
  }
  return plane->allFinite();
}

/// JudgeSurface over `samples`, the columns whose centres lie in `region`; heights smeared
/// sideways are judged too when `judge_smeared` (JudgeSmearedSurface).
SurfaceVerdict JudgeRegion(const Eigen::Vector2d& centre, const std::vector<SurfaceSample>& samples, double spacing_m,
                           const SurfaceRegion& region, const VehicleOptions& vehicle, bool judge_smeared) {
  SurfaceVerdict v;
  // Most of the region must be seen: a few far columns between unobserved ones do not show a
  // surface's slope or steps.
  const double cells_in_region = kPi * region.along_m * region.across_m / (spacing_m * spacing_m);
  // The columns of the region, counted as SurfaceAround visits them: lattice offsets within it.
  const int reach = static_cast<int>(std::floor(std::max(region.along_m, region.across_m) / spacing_m + 1e-9));
  int columns = 0;
  for (int dj = -reach; dj <= reach; ++dj) {
    for (int di = -reach; di <= reach; ++di) columns += region.Contains(Eigen::Vector2d(di, dj) * spacing_m);
  }
  v.coverage = std::min(1.0, static_cast<double>(samples.size()) / columns);
  if (samples.size() < 4 || samples.size() < 0.5 * cells_in_region) return v;
  // Heights that may belong a step radius away from their columns show no step or slope there.
  std::vector<double> xy_sigmas;
  for (const SurfaceSample& s : samples) xy_sigmas.push_back(s.xy_sigma_m);
  std::nth_element(xy_sigmas.begin(), xy_sigmas.begin() + xy_sigmas.size() / 2, xy_sigmas.end());
  v.xy_sigma_m = xy_sigmas[xy_sigmas.size() / 2];
  v.smeared = v.xy_sigma_m > 0.5 * vehicle.step_radius_m;
  if (v.smeared && !judge_smeared) return v;
  // The slope: a plane through the columns that lie on the centre column's side of any jump
  // (within what the steepest drivable slope rises from it), so a curb does not tilt it.
  const SurfaceSample* own = &samples.front();
  for (const SurfaceSample& s : samples) {
    if ((s.xy - centre).squaredNorm() < (own->xy - centre).squaredNorm()) own = &s;
  }
  const double tan_max = std::tan(DegToRad(vehicle.max_slope_deg));
  std::vector<SurfaceSample> smooth;
  for (const SurfaceSample& s : samples) {
    const double allowed = (s.xy - own->xy).norm() * tan_max + 2.0 * std::hypot(s.sigma_m, own->sigma_m);
    if (std::abs(s.height_m - own->height_m) <= allowed) smooth.push_back(s);
  }
  Eigen::Vector3d plane;
  Eigen::Matrix3d covariance;
  if (smooth.size() < 4 || !FitPlane(centre, smooth, &plane, &covariance)) return v;
  const double gradient = plane.tail<2>().norm();
  v.slope_deg = RadToDeg(std::atan(gradient));
  // sigma of |gradient| along its direction, to degrees through d(atan g)/dg = 1 / (1 + g^2).
  const Eigen::Vector2d direction = gradient > 1e-9 ? Eigen::Vector2d(plane.tail<2>() / gradient) : Eigen::Vector2d(1, 0);
  const double gradient_sigma = std::sqrt(std::max(0.0, direction.dot(covariance.bottomRightCorner<2, 2>() * direction)));
  v.slope_sigma_deg = std::max(0.5, RadToDeg(gradient_sigma / (1.0 + gradient * gradient)));
  v.determined = true;
  // The step: height differences within the disc that the local plane does not explain.
  const std::size_t rank = judge_smeared ? std::max<std::size_t>(1, samples.size() / 8) : 1;
  LargestJump(centre, samples, plane.tail<2>(), rank, &v.step_m, &v.step_sigma_m);

  const std::array<double, 3> slope =
      ClassProbabilities(v.slope_deg, v.slope_sigma_deg, vehicle.semi_slope_deg, vehicle.max_slope_deg);
  const std::array<double, 3> step = ClassProbabilities(v.step_m, std::max(0.01, v.step_sigma_m),
                                                        vehicle.semi_step_m, vehicle.max_step_m);
  v.probability = WorseOfClasses(slope, step);
  return v;
}

}  // namespace

double SurfaceDiscRadius(double step_radius_m, double spacing_m) { return step_radius_m + 0.5 * spacing_m; }

bool SurfaceRegion::Contains(const Eigen::Vector2d& offset) const {
  const double along = offset.dot(axis) / along_m;
  const double across = (offset.y() * axis.x() - offset.x() * axis.y()) / across_m;
  return along * along + across * across <= 1.0 + 1e-9;
}

SurfaceVerdict JudgeSurface(const Eigen::Vector2d& centre, const std::vector<SurfaceSample>& samples,
                            double spacing_m, const VehicleOptions& vehicle) {
  const double radius = SurfaceDiscRadius(vehicle.step_radius_m, spacing_m);
  return JudgeRegion(centre, samples, spacing_m, {Eigen::Vector2d::UnitX(), radius, radius}, vehicle, false);
}

SurfaceRegion SmearedRegion(double step_radius_m, double spacing_m, double xy_sigma_m, const Eigen::Vector2d& ray) {
  SurfaceRegion region;
  region.across_m = SurfaceDiscRadius(step_radius_m, spacing_m);
  region.along_m = SurfaceDiscRadius(step_radius_m + std::min(xy_sigma_m, step_radius_m), spacing_m);
  if (ray.norm() > 1e-9) {
    region.axis = ray.normalized();
  } else {
    region.across_m = region.along_m;  // no direction known: widened every way
  }
  return region;
}

SurfaceVerdict JudgeSmearedSurface(const Eigen::Vector2d& centre, const std::vector<SurfaceSample>& samples,
                                   double spacing_m, const SurfaceRegion& region, const VehicleOptions& vehicle) {
  // Kept per thread: far columns are judged one after another, each from a few dozen samples.
  thread_local std::vector<SurfaceSample> within;
  within.clear();
  for (const SurfaceSample& s : samples) {
    if (region.Contains(s.xy - centre)) within.push_back(s);
  }
  return JudgeRegion(centre, within, spacing_m, region, vehicle, true);
}

std::array<double, 3> WorseOfClasses(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  const double at_most_trav = a[0] * b[0];
  const double at_most_semi = (a[0] + a[1]) * (b[0] + b[1]);
  return {at_most_trav, std::max(0.0, at_most_semi - at_most_trav), std::max(0.0, 1.0 - at_most_semi)};
}

}  // namespace ssta
