#include "ssta/mount/ground_evidence.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>

namespace ssta {

GroundEvidence ExtractGroundEvidence(const FrameResult& frame, const Eigen::Matrix3d& camera_R_rectified,
                                     const Eigen::Vector3d& up_body, const RefinementOptions& options,
                                     const std::function<bool(const Eigen::Vector3d&)>& keep,
                                     const std::string& keep_reason) {
  GroundEvidence evidence;
  evidence.timestamp_ns = frame.timestamp_ns;
  evidence.up_body = up_body.normalized();
  const GroundPlane& ground = frame.analysis.ground;
  if (!ground.found) {
    evidence.reason = "no dominant ground plane";
    return evidence;
  }
  if (!frame.analysis.quality.passed) {
    evidence.reason = "ground plane failed the quality check: " + frame.analysis.quality.reason;
    return evidence;
  }
  // Candidates: the ground segment's finite points within range, in scan order. Counted first,
  // then walked again to keep the thinned ones, so no frame-sized buffer is built.
  const float max_range_sq = static_cast<float>(options.max_range_m * options.max_range_m);
  auto for_each_candidate = [&](auto&& visit) {
    for (int v = 0; v < frame.cloud.height(); ++v) {
      for (int u = 0; u < frame.cloud.width(); ++u) {
        if (frame.segment_ids(v, u) != ground.segment_id) continue;
        const Eigen::Vector3f& p = frame.cloud(v, u);
        if (!p.allFinite() || p.squaredNorm() > max_range_sq) continue;
        if (keep && !keep(camera_R_rectified * p.cast<double>())) continue;
        visit(p);
      }
    }
  };
  std::size_t count = 0;
  for_each_candidate([&](const Eigen::Vector3f&) { ++count; });
  if (static_cast<int>(count) < options.min_points_per_frame) {
    evidence.reason = "ground plane has " + std::to_string(count) + " points within " +
                      std::to_string(options.max_range_m) + " m" + (keep_reason.empty() ? "" : " " + keep_reason) +
                      ", fewer than min_points_per_frame";
    return evidence;
  }
  // Even thinning: the i-th kept point is the candidate at floor(i * step) (step >= 1).
  const std::size_t kept = std::min<std::size_t>(count, options.points_per_frame);
  const double step = static_cast<double>(count) / static_cast<double>(kept);
  evidence.camera_points.reserve(kept);
  std::size_t index = 0, next = 0;  // next: the candidate index the kept point i wants
  for_each_candidate([&](const Eigen::Vector3f& p) {
    if (evidence.camera_points.size() < kept && index == next) {
      evidence.camera_points.push_back(camera_R_rectified * p.cast<double>());
      next = static_cast<std::size_t>(std::floor(evidence.camera_points.size() * step));
    }
    ++index;
  });
  evidence.usable = true;
  return evidence;
}

DrivenOverGround::DrivenOverGround(const std::vector<std::optional<Eigen::Isometry3d>>& world_T_body,
                                   std::size_t frame, const Eigen::Isometry3d& body_T_camera,
                                   const RefinementOptions& options)
    : half_length_(options.path_half_length_m), half_width_(options.path_half_width_m), body_T_camera_(body_T_camera) {
  if (frame >= world_T_body.size() || !world_T_body[frame]) return;
  for (std::size_t j = frame + 1; j < world_T_body.size(); ++j) {
    if (!world_T_body[j]) continue;
    const Eigen::Isometry3d later_T_body = world_T_body[j]->inverse() * *world_T_body[frame];
    later_T_camera_.push_back(later_T_body * body_T_camera);
    up_.push_back(later_T_body.linear().transpose() * Eigen::Vector3d::UnitZ());
    origin_.push_back(later_T_body.inverse().translation());
  }
  // The shape of the way at each later body, from how the bodies about half a wheelbase behind
  // and ahead of it (a chord's scale, steadier than neighbouring poses) turn per metre driven:
  // their pitch gives its curvature (a crest turns the body z forward: curvature < 0), their
  // roll its twist (a side slope that steepens along the way). Then how each of those changes
  // over the same span. Four contacts span a plane through the mean of the front and the rear
  // axle: the ground under a body at x ahead and y to the side leaves that plane by
  //   curvature (x^2 - w^2/4) / 2 + twist x y
  //   + curvature' x (x^2 - w^2/4) / 6 + twist' y (x^2 - w^2/4) / 2,
  // w the wheelbase: to the third order along the way (docs/mount_calibration.md, The evidence).
  half_wheelbase_m_ = 0.5 * options.wheelbase_m;
  half_track_m_ = 0.5 * options.track_m;
  const std::size_t n = origin_.size();
  curvature_.assign(n, 0.0);
  twist_.assign(n, 0.0);
  curvature_rate_.assign(n, 0.0);
  twist_rate_.assign(n, 0.0);
  if (half_wheelbase_m_ <= 0.0) return;
  std::vector<double> s(n, 0.0);  // distance driven from the first later body [m]
  for (std::size_t j = 1; j < n; ++j) s[j] = s[j - 1] + (origin_[j] - origin_[j - 1]).norm();
  // The bodies each span runs between; equal where the way around a body is too short.
  std::vector<std::size_t> behind(n, 0), ahead(n, 0);
  std::size_t a = 0, b = 0;
  for (std::size_t j = 0; j < n; ++j) {
    while (a < j && s[j] - s[a + 1] >= half_wheelbase_m_) ++a;
    b = std::max(b, j);
    while (b + 1 < n && s[b] - s[j] < half_wheelbase_m_) ++b;
    const double ds = s[b] - s[a];
    if (ds < half_wheelbase_m_) continue;  // too little of the way around it: no curvature
    behind[j] = a;
    ahead[j] = b;
    const Eigen::Vector3d forward = (origin_[b] - origin_[a]).normalized();
    curvature_[j] = -(up_[b] - up_[a]).dot(forward) / ds;
    if (half_track_m_ > 0.0) twist_[j] = -(up_[b] - up_[a]).dot(up_[j].cross(forward).normalized()) / ds;
  }
  auto known = [&](std::size_t j) { return ahead[j] > behind[j]; };
  for (std::size_t j = 0; j < n; ++j) {
    if (!known(j) || !known(behind[j]) || !known(ahead[j])) continue;
    const double ds = s[ahead[j]] - s[behind[j]];
    curvature_rate_[j] = (curvature_[ahead[j]] - curvature_[behind[j]]) / ds;
    twist_rate_[j] = (twist_[ahead[j]] - twist_[behind[j]]) / ds;
  }
}

int DrivenOverGround::Find(const Eigen::Vector3d& p_camera) const {
  int best = -1;
  double best_x = half_length_;
  for (std::size_t j = 0; j < later_T_camera_.size(); ++j) {
    const Eigen::Vector3d q = later_T_camera_[j] * p_camera;
    if (std::abs(q.x()) <= best_x && std::abs(q.y()) <= half_width_) {
      best = static_cast<int>(j);
      best_x = std::abs(q.x());
    }
  }
  return best;
}

Eigen::Vector3d DrivenOverGround::MeanUp(const std::vector<Eigen::Vector3d>& points) const {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : points) {
    const int j = Find(p);
    if (j >= 0) sum += up_[static_cast<std::size_t>(j)];
  }
  return sum.norm() > 0.0 ? Eigen::Vector3d(sum.normalized()) : Eigen::Vector3d::UnitZ();
}

double DrivenOverGround::CurvatureAcross(const std::vector<Eigen::Vector3d>& points,
                                         const std::vector<int>& body) const {
  // z = a + b x + c y + d x^2 + e x y + f y^2 over the points a body stands on, in this frame's
  // body about their mean (for conditioning): the curvature across is 2 f. A small tilt of the
  // mount turns the points but leaves their curvature as it is. One curvature for the stretch:
  // one that changes along it as well costs more in the far points' noise than it finds
  // (docs/mount_calibration.md, What limits it).
  std::vector<Eigen::Vector3d> q;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < points.size(); ++k) {
    if (body[k] < 0) continue;
    q.push_back(body_T_camera_ * points[k]);
    mean += q.back();
  }
  constexpr int kUnknowns = 6;
  if (q.size() < 2 * kUnknowns) return 0.0;
  mean /= static_cast<double>(q.size());
  using Vector6d = Eigen::Matrix<double, kUnknowns, 1>;
  using Matrix6d = Eigen::Matrix<double, kUnknowns, kUnknowns>;
  Matrix6d normal = Matrix6d::Zero();
  Vector6d rhs = Vector6d::Zero();
  for (const Eigen::Vector3d& p : q) {
    const Eigen::Vector3d d = p - mean;
    Vector6d row;
    row << 1.0, d.x(), d.y(), d.x() * d.x(), d.x() * d.y(), d.y() * d.y();
    normal += row * row.transpose();
    rhs += row * d.z();
  }
  // Points in a strip along the way (or across it) span no quadratic: no curvature to tell.
  const double n = static_cast<double>(q.size());
  const Eigen::LDLT<Matrix6d> ldlt(normal / n);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 1e-8)) return 0.0;
  return 2.0 * ldlt.solve(rhs / n)[5];
}

Eigen::Vector3d DrivenOverGround::ExpectedUp(const std::vector<Eigen::Vector3d>& points,
                                             std::vector<double>* bend) const {
  if (bend) bend->assign(points.size(), 0.0);
  // Each point's body, and its height above that body's ground: the later bodies' origins
  // stand the median of those heights above the ground under them.
  std::vector<int> body(points.size(), -1);
  std::vector<double> heights;
  heights.reserve(points.size());
  for (std::size_t k = 0; k < points.size(); ++k) {
    body[k] = Find(points[k]);
    if (body[k] >= 0) heights.push_back(-(later_T_camera_[static_cast<std::size_t>(body[k])] * points[k]).z());
  }
  if (heights.size() < 3) return MeanUp(points);
  std::nth_element(heights.begin(), heights.begin() + heights.size() / 2, heights.end());
  const double origin_height = heights[heights.size() / 2];
  const double across = half_track_m_ > 0.0 ? CurvatureAcross(points, body) : 0.0;
  // Normal equations of z = a + b x + c y over (x, y) centred on their mean, for conditioning.
  std::vector<Eigen::Vector3d> samples;  // (x, y, z of the body's ground plane there) in this frame's body
  samples.reserve(heights.size());
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  for (std::size_t k = 0; k < points.size(); ++k) {
    if (body[k] < 0) continue;
    const Eigen::Vector3d& n = up_[static_cast<std::size_t>(body[k])];
    if (n.z() < 0.1) {  // a body on its side has no ground plane to speak of
      body[k] = -1;
      continue;
    }
    const auto j = static_cast<std::size_t>(body[k]);
    const Eigen::Vector3d ground = origin_[j] - origin_height * n;
    const Eigen::Vector3d q = body_T_camera_ * points[k];
    const Eigen::Vector3d in_later = later_T_camera_[j] * points[k];
    const double ahead = in_later.x(), side = in_later.y();
    const double chord_x = ahead * ahead - half_wheelbase_m_ * half_wheelbase_m_;
    const double sag = -0.5 * curvature_[j] * chord_x + 0.5 * across * (half_track_m_ * half_track_m_ - side * side) -
                       twist_[j] * ahead * side -
                       (curvature_rate_[j] * ahead / 6.0 + 0.5 * twist_rate_[j] * side) * chord_x;
    samples.emplace_back(q.x(), q.y(),
                         ground.z() - sag - (n.x() * (q.x() - ground.x()) + n.y() * (q.y() - ground.y())) / n.z());
    centre += q.head<2>();
  }
  if (samples.size() < 3) return MeanUp(points);
  centre /= static_cast<double>(samples.size());
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& s : samples) {
    const Eigen::Vector3d row(1.0, s.x() - centre.x(), s.y() - centre.y());
    normal += row * row.transpose();
    rhs += row * s.z();
  }
  // A strip whose width or length is nearly zero has no slope that way.
  const double sxx = normal(1, 1), syy = normal(2, 2), sxy = normal(1, 2);
  const double smallest = 0.5 * (sxx + syy - std::sqrt((sxx - syy) * (sxx - syy) + 4.0 * sxy * sxy));
  if (!(smallest / static_cast<double>(samples.size()) > 1e-4)) return MeanUp(points);  // [m^2]
  const Eigen::Vector3d abc = normal.ldlt().solve(rhs);
  if (bend) {
    std::size_t i = 0;
    for (std::size_t k = 0; k < points.size(); ++k) {
      if (body[k] < 0) continue;
      const Eigen::Vector3d& s = samples[i++];
      (*bend)[k] = s.z() - (abc[0] + abc[1] * (s.x() - centre.x()) + abc[2] * (s.y() - centre.y()));
    }
  }
  return Eigen::Vector3d(-abc[1], -abc[2], 1.0).normalized();
}

}  // namespace ssta
