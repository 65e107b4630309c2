#include "ssta/mount/mount_refiner.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <deque>
#include <memory>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include "mount/refinement_json.h"
#include "ssta/core/enum_table.h"
#include "ssta/core/error.h"
#include "ssta/core/units.h"

namespace ssta {
namespace {


/// Signed distance of one ground point to its frame's plane, over the point's sigma.
/// Parameters: correction (roll, pitch) [rad], height correction [m], and the frame's plane:
/// its tilt (about body x, y) [rad] and the body origin's height above it [m]. The plane is one
/// block so that the frames form an independent set for the Schur complement.
struct GroundPointResidual {
  GroundPointResidual(const Eigen::Vector3d& body_q, const Eigen::Vector3d& body_t, const Eigen::Matrix<double, 3, 2>& up_axes,
                      const Eigen::Vector3d& reference, const Eigen::Matrix<double, 3, 2>& reference_axes, double sigma)
      : q(body_q), t(body_t), correction_axes(up_axes), n_ref(reference), tilt_axes(reference_axes),
        inverse_sigma(1.0 / sigma) {}

  template <typename T>
  bool operator()(const T* correction, const T* height, const T* plane, T* residual) const {
    const T* tilt = plane;
    const T* offset = plane + 2;
    T w[3], tw[3];
    for (int k = 0; k < 3; ++k) {
      w[k] = correction[0] * correction_axes(k, 0) + correction[1] * correction_axes(k, 1);
      tw[k] = tilt[0] * tilt_axes(k, 0) + tilt[1] * tilt_axes(k, 1);
    }
    const T q_in[3] = {T(q.x()), T(q.y()), T(q.z())};
    T p[3];
    ceres::AngleAxisRotatePoint(w, q_in, p);
    p[0] += T(t.x());
    p[1] += T(t.y());
    p[2] += T(t.z()) + height[0];
    const T n_in[3] = {T(n_ref.x()), T(n_ref.y()), T(n_ref.z())};
    T n[3];
    ceres::AngleAxisRotatePoint(tw, n_in, n);
    residual[0] = (n[0] * p[0] + n[1] * p[1] + n[2] * p[2] + offset[0]) * T(inverse_sigma);
    return true;
  }

  Eigen::Vector3d q;                           // R_BS * p_camera (initial mount rotation applied)
  Eigen::Vector3d t;                           // t_BS
  Eigen::Matrix<double, 3, 2> correction_axes; // body axes of the correction's two angles
  Eigen::Vector3d n_ref;                       // reference ground normal in the body
  Eigen::Matrix<double, 3, 2> tilt_axes;       // axes of the frame's two tilt angles
  double inverse_sigma;
};

/// (x[first + i] - mean[i]) / sigma[i] for the N components from `first` of an M-vector block.
template <int N, int M>
struct GaussianPrior {
  GaussianPrior(int first_component, const Eigen::Matrix<double, N, 1>& m, const Eigen::Matrix<double, N, 1>& sigma)
      : first(first_component), mean(m), inverse_sigma(sigma.cwiseInverse()) {}
  template <typename T>
  bool operator()(const T* x, T* residual) const {
    for (int i = 0; i < N; ++i) residual[i] = (x[first + i] - T(mean[i])) * T(inverse_sigma[i]);
    return true;
  }
  int first;
  Eigen::Matrix<double, N, 1> mean;
  Eigen::Matrix<double, N, 1> inverse_sigma;
};

/// A Gaussian prior on components [first, first + N) of a block of size M, one sigma for each.
template <int N, int M>
ceres::CostFunction* MakePrior(int first, const Eigen::Matrix<double, N, 1>& mean,
                               const Eigen::Matrix<double, N, 1>& sigma) {
  return new ceres::AutoDiffCostFunction<GaussianPrior<N, M>, N, M>(new GaussianPrior<N, M>(first, mean, sigma));
}

/// The same with one sigma for every component.
template <int N, int M>
ceres::CostFunction* MakePrior(int first, const Eigen::Matrix<double, N, 1>& mean, double sigma) {
  return MakePrior<N, M>(first, mean, Eigen::Matrix<double, N, 1>::Constant(sigma));
}

/// Sigma of a ground point about its plane [m]: point_sigma_m, growing with the range beyond
/// point_sigma_range_m.
double PointSigma(const Eigen::Vector3d& p_camera, const RefinementOptions& options) {
  return options.point_sigma_m * std::max(1.0, p_camera.norm() / options.point_sigma_range_m);
}

Eigen::Vector3d ReferenceNormal(const GroundEvidence& frame, GroundReference reference) {
  switch (reference) {
    case GroundReference::kBody: return Eigen::Vector3d::UnitZ();
    case GroundReference::kGravity: return frame.up_body.normalized();
    case GroundReference::kPath: return frame.path_up_body.normalized();
  }
  return Eigen::Vector3d::UnitZ();
}

/// Two unit axes perpendicular to the unit vector `up`, the rotations about which tilt it: for
/// up = body z they are body x (roll) and body y (pitch); otherwise body x (or y, when x is
/// nearly along up) made perpendicular to up, and up cross that.
Eigen::Matrix<double, 3, 2> TiltAxes(const Eigen::Vector3d& up) {
  const Eigen::Vector3d seed = std::abs(up.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  Eigen::Matrix<double, 3, 2> axes;
  axes.col(0) = (seed - seed.dot(up) * up).normalized();
  axes.col(1) = up.cross(axes.col(0));
  return axes;
}

/// The rotation by angles (a, b) [rad] about the two axes: AngleAxis of a * axis0 + b * axis1.
Eigen::Matrix3d TiltRotation(const Eigen::Matrix<double, 3, 2>& axes, double a, double b) {
  const Eigen::Vector3d w = a * axes.col(0) + b * axes.col(1);
  const double angle = w.norm();
  if (angle == 0.0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
}

/// Unknowns of one frame: its ground plane's tilt about body x and y [rad] and the body
/// origin's height above it [m].
struct FramePlane {
  double values[3] = {0.0, 0.0, 0.0};
  double* tilt() { return values; }
  const double* tilt() const { return values; }
  double& offset() { return values[2]; }
  double offset() const { return values[2]; }
};

double Median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const auto middle = values.begin() + values.size() / 2;
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

/// The least-squares problem over a window and its unknowns, where Ceres reads and writes them
/// (the problem keeps pointers to them: a MountProblem stays where it was built).
struct MountProblem {
  ceres::Problem problem;
  std::shared_ptr<ceres::ParameterBlockOrdering> ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  Eigen::Matrix<double, 3, 2> correction_axes;
  // Ceres orders the blocks of an elimination group by address, and that order is the order of
  // the reduced system's arithmetic: the height correction comes before the correction.
  double height[1] = {0.0};           // height correction [m]
  double correction[2] = {0.0, 0.0};  // about correction_axes: roll, pitch [rad]
  std::vector<FramePlane> blocks;     // one per frame of the window
};

/// The correction tilts about the two body axes perpendicular to the body's vertical: the body
/// axis nearest the window's mean reference normal (body z, or x for an IMU-style body whose x
/// is up). Rotation about the vertical is what ground cannot show on level ground, and it stays
/// as configured; a mount's pitch and roll error is a rotation about the other two, and stays
/// representable when the frames' mean reference leans (rolling ground seen from its foot).
Eigen::Matrix<double, 3, 2> CorrectionAxes(const std::deque<GroundEvidence>& window, GroundReference reference) {
  Eigen::Vector3d mean_up = Eigen::Vector3d::Zero();
  for (const GroundEvidence& f : window) mean_up += ReferenceNormal(f, reference);
  Eigen::Index axis = 2;
  mean_up.cwiseAbs().maxCoeff(&axis);
  Eigen::Vector3d vertical = Eigen::Vector3d::Zero();
  vertical[axis] = mean_up[axis] < 0.0 ? -1.0 : 1.0;
  return TiltAxes(vertical);
}

/// What one solve assumes about the noise: the 1-sigma of the frames' tilt prior [rad], whether
/// that prior sits under a Cauchy loss (frames weighed by their agreement), and the factor on
/// every point's sigma.
struct NoiseModel {
  Eigen::Vector2d tilt_sigma_rad = Eigen::Vector2d::Zero();  ///< about the frame's two tilt axes
  bool robust_frames = false;
  double point_sigma_scale = 1.0;
};

/// One frame's part of the problem: a residual per ground point under the shared `loss`, the
/// priors on its plane `block` (tilt, and height when body_height_m is known), and the block in
/// the Schur elimination group. The plane keeps its values (a warm start) unless `initialize`,
/// which puts it through the points' mean along the reference normal.
void AddFrame(const GroundEvidence& frame, const RefinementOptions& options, const Eigen::Isometry3d& body_T_camera,
              const NoiseModel& noise, bool initialize, ceres::LossFunction* loss, FramePlane* block,
              MountProblem* mount) {
  const Eigen::Matrix3d body_R_camera = body_T_camera.linear();
  const Eigen::Vector3d body_t_camera = body_T_camera.translation();
  ceres::Problem& problem = mount->problem;
  const Eigen::Vector3d n_ref = ReferenceNormal(frame, options.ground_reference);
  const Eigen::Matrix<double, 3, 2> tilt_axes = TiltAxes(n_ref);
  if (initialize) {
    double mean = 0.0;
    for (const auto& p : frame.camera_points) mean += n_ref.dot(body_R_camera * p + body_t_camera);
    block->offset() = -mean / static_cast<double>(frame.camera_points.size());
  }
  for (const Eigen::Vector3d& p : frame.camera_points) {
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<GroundPointResidual, 1, 2, 1, 3>(
            new GroundPointResidual(body_R_camera * p, body_t_camera, mount->correction_axes, n_ref, tilt_axes,
                                    noise.point_sigma_scale * PointSigma(p, options))),
        loss, mount->correction, mount->height, block->values);
  }
  // Each frame its own loss (Problem takes ownership of each).
  ceres::LossFunction* frame_loss = noise.robust_frames ? new ceres::CauchyLoss(options.frame_loss_scale) : nullptr;
  problem.AddResidualBlock(MakePrior<2, 3>(0, Eigen::Vector2d::Zero(), noise.tilt_sigma_rad), frame_loss,
                           block->values);
  if (options.body_height_m >= 0.0) {
    problem.AddResidualBlock(MakePrior<1, 3>(2, Eigen::Matrix<double, 1, 1>(options.body_height_m),
                                             options.terrain_height_sigma_m),
                             nullptr, block->values);
  }
  mount->ordering->AddElementToGroup(block->values, 0);
}

/// The whole problem: every frame's points and plane, then the priors on the correction and the
/// height correction (held constant unless estimate_height). Frame planes are eliminated first.
/// With `start`, the unknowns start from its solution (a warm start); otherwise from zero.
void BuildProblem(const std::deque<GroundEvidence>& window, const RefinementOptions& options,
                  const Eigen::Isometry3d& body_T_camera, const NoiseModel& noise, const MountProblem* start,
                  MountProblem* mount) {
  mount->correction_axes = CorrectionAxes(window, options.ground_reference);
  mount->blocks.resize(window.size());
  if (start) {
    mount->blocks = start->blocks;
    mount->correction[0] = start->correction[0];
    mount->correction[1] = start->correction[1];
    mount->height[0] = start->height[0];
  }
  // One loss shared by every point residual; the problem deletes it once.
  ceres::LossFunction* loss = options.robust_loss == RobustLoss::kHuber
                                  ? static_cast<ceres::LossFunction*>(new ceres::HuberLoss(options.loss_scale))
                                  : new ceres::CauchyLoss(options.loss_scale);
  for (std::size_t i = 0; i < window.size(); ++i) {
    AddFrame(window[i], options, body_T_camera, noise, start == nullptr, loss, &mount->blocks[i], mount);
  }
  ceres::Problem& problem = mount->problem;
  problem.AddResidualBlock(MakePrior<2, 2>(0, Eigen::Vector2d::Zero(), DegToRad(options.prior_sigma_deg)), nullptr,
                           mount->correction);
  problem.AddResidualBlock(MakePrior<1, 1>(0, Eigen::Matrix<double, 1, 1>::Zero(), options.height_prior_sigma_m),
                           nullptr, mount->height);
  if (!options.estimate_height) problem.SetParameterBlockConstant(mount->height);
  mount->ordering->AddElementToGroup(mount->correction, 1);
  mount->ordering->AddElementToGroup(mount->height, 1);
}

ceres::Solver::Summary RunSolver(const RefinementOptions& options, MountProblem* mount) {
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_SCHUR;
  solver_options.linear_solver_ordering = mount->ordering;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.num_threads = 1;
  solver_options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &mount->problem, &summary);
  return summary;
}

/// Per-frame planes and robust statistics at the solution [m], into `result` (whose
/// body_R_correction is the solved one): each point's distance to its frame's plane, the
/// outliers beyond the loss scale, each frame's tilt, height and weight under `noise`, their RMS
/// and median, the frames' tilt scatter and the points' sigma scale.
void MeasureFit(const std::deque<GroundEvidence>& window, const RefinementOptions& options,
                const Eigen::Isometry3d& body_T_camera, const MountProblem& mount, const NoiseModel& noise,
                MountRefinementResult* result) {
  const Eigen::Matrix3d body_R_camera = body_T_camera.linear();
  const Eigen::Vector3d body_t_camera = body_T_camera.translation();
  std::vector<double> distances, normalized;
  distances.reserve(result->points_used);
  normalized.reserve(result->points_used);
  double sum_sq = 0.0;
  result->frames.clear();
  result->outlier_points = 0;
  result->frames_downweighted = 0;
  result->ground_tilt_rms_deg = 0.0;
  for (std::size_t i = 0; i < window.size(); ++i) {
    const GroundEvidence& frame = window[i];
    const FramePlane& block = mount.blocks[i];
    const Eigen::Vector3d n_ref = ReferenceNormal(frame, options.ground_reference);
    const Eigen::Vector3d n = TiltRotation(TiltAxes(n_ref), block.tilt()[0], block.tilt()[1]) * n_ref;
    for (const Eigen::Vector3d& p : frame.camera_points) {
      const Eigen::Vector3d p_body =
          result->body_R_correction * (body_R_camera * p) + body_t_camera + Eigen::Vector3d(0, 0, mount.height[0]);
      const double d = std::abs(n.dot(p_body) + block.offset());
      distances.push_back(d);
      normalized.push_back(d / PointSigma(p, options));
      sum_sq += d * d;
      if (d > options.loss_scale * noise.point_sigma_scale * PointSigma(p, options)) ++result->outlier_points;
    }
    FrameGroundEstimate estimate;
    estimate.timestamp_ns = frame.timestamp_ns;
    estimate.points = static_cast<int>(frame.camera_points.size());
    estimate.tilt_deg = RadToDeg(std::acos(std::clamp(n.dot(n_ref), -1.0, 1.0)));
    if (noise.robust_frames) {
      // Ceres' CauchyLoss(a) on s = |tilt / sigma|^2: rho'(s) = 1 / (1 + s / a^2).
      const double a = options.frame_loss_scale;
      const Eigen::Vector2d s(block.tilt()[0] / noise.tilt_sigma_rad[0], block.tilt()[1] / noise.tilt_sigma_rad[1]);
      estimate.weight = 1.0 / (1.0 + s.squaredNorm() / (a * a));
    }
    if (estimate.weight < 0.5) ++result->frames_downweighted;
    result->ground_tilt_rms_deg += estimate.tilt_deg * estimate.tilt_deg;
    estimate.height_m = block.offset();
    result->frames.push_back(estimate);
  }
  result->ground_tilt_rms_deg = std::sqrt(result->ground_tilt_rms_deg / static_cast<double>(window.size()));
  // Each axis's scatter from its median |tilt| (|N(0, s^2)| has median 0.6745 s): the median
  // keeps the frames on a slope of their own out of it.
  for (int k = 0; k < 2; ++k) {
    std::vector<double> tilts;
    for (const FramePlane& block : mount.blocks) tilts.push_back(std::abs(block.tilt()[k]));
    result->tilt_scatter_axes_deg[k] =
        std::max(options.min_tilt_scatter_deg, RadToDeg(Median(tilts) / 0.6744897501960817));
  }
  result->tilt_scatter_deg = result->tilt_scatter_axes_deg.maxCoeff();
  if (!distances.empty()) {
    result->residual_rms_m = std::sqrt(sum_sq / static_cast<double>(distances.size()));
    result->residual_median_m = Median(distances);
    // |r| / sigma ~ |N(0, s^2)|: median 0.6745 s.
    result->point_sigma_scale = std::max(1e-3, Median(normalized) / 0.6744897501960817);
  }
}

/// Lag-1 correlation of the frames' tilts in window order (both axes pooled), clamped to
/// [0, max_rho]: consecutive frames see overlapping ground, so their tilts are not independent.
double TiltCorrelation(const MountProblem& mount, const MountRefinementResult& result) {
  constexpr double kMaxRho = 0.9;
  double num = 0.0, den = 0.0;
  for (std::size_t i = 0; i < mount.blocks.size(); ++i) {
    const double w = result.frames[i].weight;
    for (int k = 0; k < 2; ++k) {
      const double a = mount.blocks[i].tilt()[k];
      den += w * a * a;
      if (i + 1 < mount.blocks.size()) {
        num += std::sqrt(w * result.frames[i + 1].weight) * a * mount.blocks[i + 1].tilt()[k];
      }
    }
  }
  if (den <= 0.0) return 0.0;
  return std::clamp(num / den, 0.0, kMaxRho);
}

/// Posterior 1-sigma of the correction (and of the height correction when estimated) into
/// `result`; false when the covariance cannot be computed (rank deficient).
bool ComputeSigmas(const RefinementOptions& options, MountProblem* mount, MountRefinementResult* result) {
  ceres::Covariance::Options covariance_options;
  covariance_options.num_threads = 1;
  ceres::Covariance covariance(covariance_options);
  const double* correction = mount->correction;
  const double* height = mount->height;
  std::vector<std::pair<const double*, const double*>> wanted = {{correction, correction}};
  if (options.estimate_height) wanted.emplace_back(height, height);
  if (!covariance.Compute(wanted, &mount->problem)) return false;
  double c[4];
  covariance.GetCovarianceBlock(correction, correction, c);
  const double f = result->sigma_inflation;
  auto total = [&](double variance_rad2) {
    return std::hypot(f * RadToDeg(std::sqrt(std::max(0.0, variance_rad2))), options.systematic_sigma_deg);
  };
  result->roll_sigma_deg = total(c[0]);
  result->pitch_sigma_deg = total(c[3]);
  if (options.estimate_height) {
    double h = 0.0;
    covariance.GetCovarianceBlock(height, height, &h);
    result->height_sigma_m = f * std::sqrt(std::max(0.0, h));
  }
  return true;
}

/// Whether a solved correction is applied: its status and the sentence that says why.
struct Verdict {
  RefinementStatus status;
  std::string message;
};

/// A solution with its sigmas is applied unless it is not better determined than its prior or
/// the frames' ground planes scatter more than the terrain model allows.
Verdict JudgeSolution(const RefinementOptions& options, const MountRefinementResult& result) {
  // The prior first: a correction a tight prior holds at zero shows up as tilted frames too.
  const double limit_deg = options.max_sigma_ratio * options.prior_sigma_deg;
  if (std::max(result.pitch_sigma_deg, result.roll_sigma_deg) > limit_deg) {
    std::ostringstream m;
    m << std::setprecision(3) << "not better determined than its prior: posterior sigma pitch "
      << result.pitch_sigma_deg << " deg, roll " << result.roll_sigma_deg << " deg vs prior " << options.prior_sigma_deg
      << " deg (applied only below " << limit_deg << " deg); the configured mount is kept";
    return {RefinementStatus::kNotBetterThanPrior, m.str()};
  }
  if (result.tilt_scatter_deg > options.terrain_tilt_sigma_deg) {
    std::ostringstream m;
    m << std::setprecision(3) << "the ground is not flat enough: the frames' ground planes scatter by "
      << result.tilt_scatter_deg << " deg (1 sigma, the larger axis) about the reference, more than terrain_tilt_sigma_deg ("
      << options.terrain_tilt_sigma_deg << " deg); the configured mount is kept (drive on flatter ground)";
    return {RefinementStatus::kTerrainTooRough, m.str()};
  }
  return {RefinementStatus::kDetermined,
          "mount correction determined from " + std::to_string(result.frames_used) + " frames"};
}

}  // namespace

std::string RefinementStatusName(RefinementStatus status) {
  static const EnumTable<RefinementStatus> table("refinement status",
                                                 {{RefinementStatus::kDetermined, "determined"},
                                                  {RefinementStatus::kTooFewFrames, "too_few_frames"},
                                                  {RefinementStatus::kNotBetterThanPrior, "not_better_than_prior"},
                                                  {RefinementStatus::kTerrainTooRough, "terrain_too_rough"},
                                                  {RefinementStatus::kFailed, "failed"}});
  return table.Name(status);
}

MountRefiner::MountRefiner(const RefinementOptions& options, const Eigen::Isometry3d& body_T_camera)
    : options_(options), body_T_camera_(body_T_camera) {
  std::string error;
  if (!options_.IsValid(&error)) throw Error("refinement." + error);
}

void MountRefiner::AddFrame(GroundEvidence evidence) {
  SSTA_CHECK(evidence.usable, "MountRefiner::AddFrame needs usable evidence");
  window_.push_back(std::move(evidence));
}

void MountRefiner::DropOldest() {
  if (!window_.empty()) window_.pop_front();
}

MountRefinementResult MountRefiner::Solve() const {
  const auto start = std::chrono::steady_clock::now();
  MountRefinementResult result;
  result.prior_sigma_deg = options_.prior_sigma_deg;
  result.body_T_camera_initial = body_T_camera_;
  result.body_T_camera_refined = body_T_camera_;
  result.frames_used = NumFrames();
  for (const GroundEvidence& f : window_) result.points_used += static_cast<int>(f.camera_points.size());
  if (NumFrames() < options_.min_frames) {
    result.status = RefinementStatus::kTooFewFrames;
    result.message = std::to_string(NumFrames()) + " frame(s) with a usable ground plane, fewer than min_frames (" +
                     std::to_string(options_.min_frames) + "): the mount is not determined";
    return result;
  }

  result.reference = GroundReferenceName(options_.ground_reference);
  if (options_.ground_reference == GroundReference::kPath) {
    const bool any_path = std::any_of(window_.begin(), window_.end(), [](const GroundEvidence& f) {
      return !f.path_up_body.isApprox(Eigen::Vector3d::UnitZ());
    });
    if (!any_path) result.reference = "body";
  }

  // First solve: the configured tilt prior, the assumed point sigmas. Then solves whose noise
  // is what the last one measured: the frames' tilt scatter as their prior, under a Cauchy loss
  // that weighs each frame by its agreement with the others, and the points' actual scatter.
  constexpr int kReweightings = 3;
  NoiseModel noise;
  noise.tilt_sigma_rad = Eigen::Vector2d::Constant(DegToRad(options_.terrain_tilt_sigma_deg));
  auto mount = std::make_unique<MountProblem>();
  BuildProblem(window_, options_, body_T_camera_, noise, nullptr, mount.get());
  ceres::Solver::Summary summary = RunSolver(options_, mount.get());
  result.initial_cost = summary.initial_cost;
  int iterations = static_cast<int>(summary.iterations.size());
  auto take = [&](const MountProblem& m) {
    result.roll_correction_deg = RadToDeg(m.correction[0]);
    result.pitch_correction_deg = RadToDeg(m.correction[1]);
    result.height_correction_m = options_.estimate_height ? m.height[0] : 0.0;
    result.body_R_correction = TiltRotation(m.correction_axes, m.correction[0], m.correction[1]);
    MeasureFit(window_, options_, body_T_camera_, m, noise, &result);
  };
  take(*mount);
  for (int pass = 0; pass < kReweightings && summary.IsSolutionUsable(); ++pass) {
    noise.tilt_sigma_rad = DegToRad(1.0) * result.tilt_scatter_axes_deg;
    noise.robust_frames = true;
    noise.point_sigma_scale = result.point_sigma_scale;
    auto next = std::make_unique<MountProblem>();
    BuildProblem(window_, options_, body_T_camera_, noise, mount.get(), next.get());
    summary = RunSolver(options_, next.get());
    iterations += static_cast<int>(summary.iterations.size());
    mount = std::move(next);
    take(*mount);
  }
  result.final_cost = summary.final_cost;
  result.iterations = iterations;
  const double rho = TiltCorrelation(*mount, result);
  result.sigma_inflation = std::sqrt((1.0 + rho) / (1.0 - rho));

  auto finish = [&](RefinementStatus status, const std::string& message) {
    result.status = status;
    result.message = message;
    result.solve_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return result;
  };
  if (!summary.IsSolutionUsable()) return finish(RefinementStatus::kFailed, "solver failed: " + summary.message);
  if (!ComputeSigmas(options_, mount.get(), &result)) {
    return finish(RefinementStatus::kFailed, "the covariance of the correction could not be computed (rank deficient)");
  }
  const Verdict verdict = JudgeSolution(options_, result);
  if (verdict.status == RefinementStatus::kDetermined) {
    const Eigen::Matrix3d body_R_camera = body_T_camera_.linear();
    const Eigen::Vector3d body_t_camera = body_T_camera_.translation();
    result.body_T_camera_refined.linear() = result.body_R_correction * body_R_camera;
    result.body_T_camera_refined.translation() = body_t_camera + Eigen::Vector3d(0, 0, result.height_correction_m);
  }
  return finish(verdict.status, verdict.message);
}

namespace {

/// SolveAlongPath's solve: the points chosen through the configured mount, then again through
/// the refined one.
MountRefinementResult SolvePathRounds(const RefinementOptions& options, const Eigen::Isometry3d& body_T_camera,
                                      const std::vector<std::optional<Eigen::Isometry3d>>& world_T_body,
                                      const std::vector<GroundEvidence>& frames, int* frames_on_path) {
  RefinementOptions path_options = options;
  path_options.ground_reference = GroundReference::kPath;
  constexpr int kRounds = 2;
  Eigen::Isometry3d through = body_T_camera;  // the mount the points are chosen through
  MountRefinementResult result;
  for (int round = 0; round < kRounds; ++round) {
    MountRefiner refiner(path_options, body_T_camera);
    const Eigen::Vector3d body_z_in_camera = through.linear().transpose() * Eigen::Vector3d::UnitZ();
    int on_path = 0;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      if (!frames[i].usable) continue;
      const DrivenOverGround driven(world_T_body, i, through, options);
      std::vector<Eigen::Vector3d> kept;
      for (const Eigen::Vector3d& p : frames[i].camera_points) {
        if (driven.Contains(p)) kept.push_back(p);
      }
      if (static_cast<int>(kept.size()) < options.min_points_per_frame) continue;
      GroundEvidence e = frames[i];
      e.camera_points.clear();
      const std::size_t n = std::min<std::size_t>(kept.size(), static_cast<std::size_t>(options.points_per_frame));
      const double step = static_cast<double>(kept.size()) / static_cast<double>(n);
      for (std::size_t k = 0; k < n; ++k) e.camera_points.push_back(kept[static_cast<std::size_t>(k * step)]);
      // The plane the points should lie on if the ground were the later bodies' wheel planes,
      // and each point moved along body z by how far that ground bends away from it there: one
      // plane per frame then holds on curved ground, whatever weight each point gets.
      std::vector<double> bend;
      e.path_up_body = driven.ExpectedUp(e.camera_points, &bend);
      for (std::size_t k = 0; k < e.camera_points.size(); ++k) e.camera_points[k] -= bend[k] * body_z_in_camera;
      refiner.AddFrame(std::move(e));
      ++on_path;
    }
    if (frames_on_path) *frames_on_path = on_path;
    result = refiner.Solve();
    if (result.status == RefinementStatus::kTooFewFrames || result.status == RefinementStatus::kFailed) break;
    through.linear() = result.body_R_correction * body_T_camera.linear();
  }
  return result;
}

}  // namespace

MountRefinementResult SolveAlongPath(const RefinementOptions& options, const Eigen::Isometry3d& body_T_camera,
                                     const std::vector<std::optional<Eigen::Isometry3d>>& world_T_body,
                                     const std::vector<GroundEvidence>& frames, int* frames_on_path) {
  SSTA_CHECK(frames.size() == world_T_body.size(), "SolveAlongPath: one pose per frame");
  int on_path = 0;
  const MountRefinementResult result = SolvePathRounds(options, body_T_camera, world_T_body, frames, &on_path);
  if (options.wheelbase_m > 0.0 || options.track_m > 0.0) {
    // The sag below the wheels' chords refines a model of ground that is smooth over a
    // wheelbase; it does not make one where the wheel planes alone determine nothing. A drive
    // the wheel planes find too rough, too short or no better than the prior is answered as they
    // answer it (on random 10 of the wide set, 5 frames over a 33 deg side slope, the sag would
    // otherwise settle on a mount 2.3 deg off with sigmas under 0.5 deg).
    RefinementOptions planes = options;
    planes.wheelbase_m = 0.0;
    planes.track_m = 0.0;
    int planes_on_path = 0;
    MountRefinementResult plain = SolvePathRounds(planes, body_T_camera, world_T_body, frames, &planes_on_path);
    if (!plain.applied()) {
      if (plain.status != RefinementStatus::kTooFewFrames) {
        plain.message += " (judged against the later bodies' wheel planes, without the sag below their chords)";
      }
      if (frames_on_path) *frames_on_path = planes_on_path;
      return plain;
    }
  }
  if (frames_on_path) *frames_on_path = on_path;
  return result;
}

std::string MountRefinementResult::BriefReport() const {
  std::ostringstream r;
  r << std::fixed << std::setprecision(3);
  r << "mount refinement: " << RefinementStatusName(status) << " (" << message << ")\n";
  const bool solved = status != RefinementStatus::kTooFewFrames;
  if (solved) {
    r << "  pitch correction " << pitch_correction_deg << " +- " << pitch_sigma_deg << " deg, roll correction "
      << roll_correction_deg << " +- " << roll_sigma_deg << " deg (1 sigma; prior " << prior_sigma_deg << " deg)";
    if (std::isfinite(height_sigma_m)) r << ", height " << height_correction_m << " +- " << height_sigma_m << " m";
    r << "\n  evidence: " << frames_used << " frames, " << points_used << " ground points (reference " << reference
      << "); residual rms " << residual_rms_m << " m, median " << residual_median_m << " m, " << outlier_points
      << " beyond the loss scale (point sigma x " << point_sigma_scale << ")\n  ground tilt: rms "
      << ground_tilt_rms_deg << " deg, scatter " << tilt_scatter_deg << " deg, " << frames_downweighted
      << " frames down-weighted; sigma x " << sigma_inflation << " for correlated frames\n";
    r << "  solver: cost " << initial_cost << " -> " << final_cost << " in " << iterations << " iterations, "
      << solve_ms << " ms\n";
  } else {
    r << "  evidence: " << frames_used << " frames, " << points_used << " ground points; not solved\n";
  }
  const Eigen::Matrix4d m = body_T_camera_refined.matrix();
  r << "  T_BS (cam0" << (applied() ? ", refined" : ", unchanged") << "):\n" << std::setprecision(6);
  for (int i = 0; i < 4; ++i) {
    r << "    [" << m(i, 0) << ", " << m(i, 1) << ", " << m(i, 2) << ", " << m(i, 3) << "]\n";
  }
  return r.str();
}

std::string MountRefinementResult::Json() const {
  internal::JsonWriter json;
  internal::WriteRefinementJson(*this, &json);
  return json.Take();
}

namespace internal {

void WriteSkippedFramesJson(const std::vector<SkippedFrame>& frames, JsonWriter* json) {
  json->BeginArray();
  for (const SkippedFrame& s : frames) {
    json->BeginObject();
    json->Key("timestamp_ns");
    json->Integer(s.timestamp_ns);
    json->Key("reason");
    json->String(s.reason);
    json->EndObject();
  }
  json->EndArray();
}

void WriteRefinementJson(const MountRefinementResult& r, JsonWriter* json) {
  json->BeginObject();
  json->Key("status");
  json->String(RefinementStatusName(r.status));
  json->Key("applied");
  json->Bool(r.applied());
  json->Key("message");
  json->String(r.message);
  const std::pair<const char*, double> numbers[] = {
      {"pitch_correction_deg", r.pitch_correction_deg}, {"roll_correction_deg", r.roll_correction_deg},
      {"height_correction_m", r.height_correction_m},   {"pitch_sigma_deg", r.pitch_sigma_deg},
      {"roll_sigma_deg", r.roll_sigma_deg},             {"height_sigma_m", r.height_sigma_m},
      {"prior_sigma_deg", r.prior_sigma_deg},           {"residual_rms_m", r.residual_rms_m},
      {"residual_median_m", r.residual_median_m},       {"ground_tilt_rms_deg", r.ground_tilt_rms_deg},
      {"tilt_scatter_deg", r.tilt_scatter_deg},
      {"tilt_scatter_roll_deg", r.tilt_scatter_axes_deg[0]}, {"tilt_scatter_pitch_deg", r.tilt_scatter_axes_deg[1]},
      {"point_sigma_scale", r.point_sigma_scale},
      {"sigma_inflation", r.sigma_inflation},
      {"initial_cost", r.initial_cost},
      {"final_cost", r.final_cost},                     {"solve_ms", r.solve_ms}};
  for (const auto& [key, value] : numbers) {
    json->Key(key);
    json->Number(value);
  }
  json->Key("reference");
  json->String(r.reference);
  json->Key("frames_used");
  json->Integer(r.frames_used);
  json->Key("frames_downweighted");
  json->Integer(r.frames_downweighted);
  json->Key("points_used");
  json->Integer(r.points_used);
  json->Key("outlier_points");
  json->Integer(r.outlier_points);
  json->Key("iterations");
  json->Integer(r.iterations);
  json->Key("body_T_camera_initial");
  json->MatrixRows(r.body_T_camera_initial.matrix());
  json->Key("body_T_camera_refined");
  json->MatrixRows(r.body_T_camera_refined.matrix());
  json->Key("frames");
  json->BeginArray();
  for (const FrameGroundEstimate& f : r.frames) {
    json->BeginObject();
    json->Key("timestamp_ns");
    json->Integer(f.timestamp_ns);
    json->Key("points");
    json->Integer(f.points);
    json->Key("tilt_deg");
    json->Number(f.tilt_deg);
    json->Key("height_m");
    json->Number(f.height_m);
    json->Key("weight");
    json->Number(f.weight);
    json->EndObject();
  }
  json->EndArray();
  json->EndObject();
}

}  // namespace internal
}  // namespace ssta
