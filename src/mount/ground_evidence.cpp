#include "ssta/mount/ground_evidence.h"

#include <cmath>

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
    : half_length_(options.path_half_length_m), half_width_(options.path_half_width_m) {
  if (frame >= world_T_body.size() || !world_T_body[frame]) return;
  for (std::size_t j = frame + 1; j < world_T_body.size(); ++j) {
    if (!world_T_body[j]) continue;
    const Eigen::Isometry3d later_T_body = world_T_body[j]->inverse() * *world_T_body[frame];
    later_T_camera_.push_back(later_T_body * body_T_camera);
    up_.push_back(later_T_body.linear().transpose() * Eigen::Vector3d::UnitZ());
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

}  // namespace ssta
