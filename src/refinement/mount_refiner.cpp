#include "ssta/refinement/mount_refiner.h"

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

#include "refinement/refinement_json.h"
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

/// (x[first + i] - mean[i]) / sigma for the N components from `first` of an M-vector block.
template <int N, int M>
struct GaussianPrior {
  GaussianPrior(int first_component, const Eigen::Matrix<double, N, 1>& m, double sigma)
      : first(first_component), mean(m), inverse_sigma(1.0 / sigma) {}
  template <typename T>
  bool operator()(const T* x, T* residual) const {
    for (int i = 0; i < N; ++i) residual[i] = (x[first + i] - T(mean[i])) * T(inverse_sigma);
    return true;
  }
  int first;
  Eigen::Matrix<double, N, 1> mean;
  double inverse_sigma;
};

/// A Gaussian prior on components [first, first + N) of a block of size M.
template <int N, int M>
ceres::CostFunction* MakePrior(int first, const Eigen::Matrix<double, N, 1>& mean, double sigma) {
  return new ceres::AutoDiffCostFunction<GaussianPrior<N, M>, N, M>(new GaussianPrior<N, M>(first, mean, sigma));
}

/// Sigma of a ground point about its plane [m]: point_sigma_m, growing with the range beyond
/// point_sigma_range_m.
double PointSigma(const Eigen::Vector3d& p_camera, const RefinementOptions& options) {
  return options.point_sigma_m * std::max(1.0, p_camera.norm() / options.point_sigma_range_m);
}

Eigen::Vector3d ReferenceNormal(const GroundEvidence& frame, GroundReference reference) {
  return reference == GroundReference::kBody ? Eigen::Vector3d::UnitZ() : frame.up_body.normalized();
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

/// The correction tilts about two axes perpendicular to the window's mean reference normal
/// (body x and y for the body reference): rotation about the ground normal is unobservable.
Eigen::Matrix<double, 3, 2> CorrectionAxes(const std::deque<GroundEvidence>& window, GroundReference reference) {
  Eigen::Vector3d mean_up = Eigen::Vector3d::Zero();
  for (const GroundEvidence& f : window) mean_up += ReferenceNormal(f, reference);
  return TiltAxes(mean_up.normalized());
}

/// One frame's part of the problem: a residual per ground point under the shared `loss`, the
/// priors on its plane `block` (tilt, and height when body_height_m is known), and the block in
/// the Schur elimination group. The plane starts through the points' mean along the reference
/// normal.
void AddFrame(const GroundEvidence& frame, const RefinementOptions& options, const Eigen::Isometry3d& body_T_camera,
              ceres::LossFunction* loss, FramePlane* block, MountProblem* mount) {
  const Eigen::Matrix3d body_R_camera = body_T_camera.linear();
  const Eigen::Vector3d body_t_camera = body_T_camera.translation();
  ceres::Problem& problem = mount->problem;
  const Eigen::Vector3d n_ref = ReferenceNormal(frame, options.ground_reference);
  const Eigen::Matrix<double, 3, 2> tilt_axes = TiltAxes(n_ref);
  // Start each plane through the points' mean along the reference normal.
  double mean = 0.0;
  for (const auto& p : frame.camera_points) mean += n_ref.dot(body_R_camera * p + body_t_camera);
  block->offset() = -mean / static_cast<double>(frame.camera_points.size());
  for (const Eigen::Vector3d& p : frame.camera_points) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<GroundPointResidual, 1, 2, 1, 3>(
                                 new GroundPointResidual(body_R_camera * p, body_t_camera, mount->correction_axes,
                                                         n_ref, tilt_axes, PointSigma(p, options))),
                             loss, mount->correction, mount->height, block->values);
  }
  problem.AddResidualBlock(MakePrior<2, 3>(0, Eigen::Vector2d::Zero(), DegToRad(options.terrain_tilt_sigma_deg)),
                           nullptr, block->values);
  if (options.body_height_m >= 0.0) {
    problem.AddResidualBlock(MakePrior<1, 3>(2, Eigen::Matrix<double, 1, 1>(options.body_height_m),
                                             options.terrain_height_sigma_m),
                             nullptr, block->values);
  }
  mount->ordering->AddElementToGroup(block->values, 0);
}

/// The whole problem: every frame's points and plane, then the priors on the correction and the
/// height correction (held constant unless estimate_height). Frame planes are eliminated first.
void BuildProblem(const std::deque<GroundEvidence>& window, const RefinementOptions& options,
                  const Eigen::Isometry3d& body_T_camera, MountProblem* mount) {
  mount->correction_axes = CorrectionAxes(window, options.ground_reference);
  mount->blocks.resize(window.size());
  // One loss shared by every point residual; the problem deletes it once.
  ceres::LossFunction* loss = options.robust_loss == RobustLoss::kHuber
                                  ? static_cast<ceres::LossFunction*>(new ceres::HuberLoss(options.loss_scale))
                                  : new ceres::CauchyLoss(options.loss_scale);
  for (std::size_t i = 0; i < window.size(); ++i) {
    AddFrame(window[i], options, body_T_camera, loss, &mount->blocks[i], mount);
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
/// outliers beyond the loss scale, each frame's tilt and height, their RMS and median.
void MeasureFit(const std::deque<GroundEvidence>& window, const RefinementOptions& options,
                const Eigen::Isometry3d& body_T_camera, const MountProblem& mount, MountRefinementResult* result) {
  const Eigen::Matrix3d body_R_camera = body_T_camera.linear();
  const Eigen::Vector3d body_t_camera = body_T_camera.translation();
  std::vector<double> distances;
  distances.reserve(result->points_used);
  double sum_sq = 0.0;
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
      sum_sq += d * d;
      if (d > options.loss_scale * PointSigma(p, options)) ++result->outlier_points;
    }
    FrameGroundEstimate estimate;
    estimate.timestamp_ns = frame.timestamp_ns;
    estimate.points = static_cast<int>(frame.camera_points.size());
    estimate.tilt_deg = RadToDeg(std::acos(std::clamp(n.dot(n_ref), -1.0, 1.0)));
    result->ground_tilt_rms_deg += estimate.tilt_deg * estimate.tilt_deg;
    estimate.height_m = block.offset();
    result->frames.push_back(estimate);
  }
  result->ground_tilt_rms_deg = std::sqrt(result->ground_tilt_rms_deg / static_cast<double>(window.size()));
  if (!distances.empty()) {
    result->residual_rms_m = std::sqrt(sum_sq / static_cast<double>(distances.size()));
    result->residual_median_m = Median(distances);
  }
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
  result->roll_sigma_deg = RadToDeg(std::sqrt(std::max(0.0, c[0])));
  result->pitch_sigma_deg = RadToDeg(std::sqrt(std::max(0.0, c[3])));
  if (options.estimate_height) {
    double h = 0.0;
    covariance.GetCovarianceBlock(height, height, &h);
    result->height_sigma_m = std::sqrt(std::max(0.0, h));
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
  // Two tilt angles per frame, each N(0, sigma^2) under the model: RMS tilt ~ sqrt(2) sigma.
  const double tilt_limit_deg = std::sqrt(2.0) * options.terrain_tilt_sigma_deg;
  if (result.ground_tilt_rms_deg > tilt_limit_deg) {
    std::ostringstream m;
    m << std::setprecision(3) << "the ground is not flat enough: the frames' ground planes tilt by "
      << result.ground_tilt_rms_deg << " deg RMS about the reference, more than terrain_tilt_sigma_deg allows ("
      << tilt_limit_deg << " deg); the configured mount is kept (drive on flatter ground)";
    return {RefinementStatus::kTerrainTooRough, m.str()};
  }
  return {RefinementStatus::kDetermined,
          "mount correction determined from " + std::to_string(result.frames_used) + " frames"};
}

}  // namespace

std::string RefinementStatusName(RefinementStatus status) {
  switch (status) {
    case RefinementStatus::kDetermined: return "determined";
    case RefinementStatus::kTooFewFrames: return "too_few_frames";
    case RefinementStatus::kNotBetterThanPrior: return "not_better_than_prior";
    case RefinementStatus::kTerrainTooRough: return "terrain_too_rough";
    case RefinementStatus::kFailed: return "failed";
  }
  return "failed";
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

  MountProblem mount;
  BuildProblem(window_, options_, body_T_camera_, &mount);
  const ceres::Solver::Summary summary = RunSolver(options_, &mount);
  result.initial_cost = summary.initial_cost;
  result.final_cost = summary.final_cost;
  result.iterations = static_cast<int>(summary.iterations.size());
  result.roll_correction_deg = RadToDeg(mount.correction[0]);
  result.pitch_correction_deg = RadToDeg(mount.correction[1]);
  result.height_correction_m = options_.estimate_height ? mount.height[0] : 0.0;
  result.body_R_correction = TiltRotation(mount.correction_axes, mount.correction[0], mount.correction[1]);
  MeasureFit(window_, options_, body_T_camera_, mount, &result);

  auto finish = [&](RefinementStatus status, const std::string& message) {
    result.status = status;
    result.message = message;
    result.solve_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return result;
  };
  if (!summary.IsSolutionUsable()) return finish(RefinementStatus::kFailed, "solver failed: " + summary.message);
  if (!ComputeSigmas(options_, &mount, &result)) {
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

std::string MountRefinementResult::BriefReport() const {
  std::ostringstream r;
  r << std::fixed << std::setprecision(3);
  r << "mount refinement: " << RefinementStatusName(status) << " (" << message << ")\n";
  const bool solved = status != RefinementStatus::kTooFewFrames;
  if (solved) {
    r << "  pitch correction " << pitch_correction_deg << " +- " << pitch_sigma_deg << " deg, roll correction "
      << roll_correction_deg << " +- " << roll_sigma_deg << " deg (1 sigma; prior " << prior_sigma_deg << " deg)";
    if (std::isfinite(height_sigma_m)) r << ", height " << height_correction_m << " +- " << height_sigma_m << " m";
    r << "\n  evidence: " << frames_used << " frames, " << points_used << " ground points; residual rms "
      << residual_rms_m << " m, median " << residual_median_m << " m, " << outlier_points
      << " beyond the loss scale; ground tilt rms " << ground_tilt_rms_deg << " deg\n";
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
      {"initial_cost", r.initial_cost},
      {"final_cost", r.final_cost},                     {"solve_ms", r.solve_ms}};
  for (const auto& [key, value] : numbers) {
    json->Key(key);
    json->Number(value);
  }
  json->Key("frames_used");
  json->Integer(r.frames_used);
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
    json->EndObject();
  }
  json->EndArray();
  json->EndObject();
}

}  // namespace internal
}  // namespace ssta
