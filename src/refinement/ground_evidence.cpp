#include "ssta/refinement/ground_evidence.h"

#include <cmath>

namespace ssta {

GroundEvidence ExtractGroundEvidence(const FrameResult& frame, const Eigen::Matrix3d& camera_R_rectified,
                                     const Eigen::Vector3d& up_body, const RefinementOptions& options) {
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
  // Candidates: the ground segment's finite points within range, in scan order.
  const float max_range_sq = static_cast<float>(options.max_range_m * options.max_range_m);
  std::vector<Eigen::Vector3f> candidates;
  for (int v = 0; v < frame.cloud.height(); ++v) {
    for (int u = 0; u < frame.cloud.width(); ++u) {
      if (frame.segment_ids(v, u) != ground.segment_id) continue;
      const Eigen::Vector3f& p = frame.cloud(v, u);
      if (p.allFinite() && p.squaredNorm() <= max_range_sq) candidates.push_back(p);
    }
  }
  if (static_cast<int>(candidates.size()) < options.min_points_per_frame) {
    evidence.reason = "ground plane has " + std::to_string(candidates.size()) + " points within " +
                      std::to_string(options.max_range_m) + " m, fewer than min_points_per_frame";
    return evidence;
  }
  // Even thinning: the i-th kept point is the candidate at i * step (step >= 1).
  const std::size_t kept = std::min<std::size_t>(candidates.size(), options.points_per_frame);
  const double step = static_cast<double>(candidates.size()) / static_cast<double>(kept);
  evidence.camera_points.reserve(kept);
  for (std::size_t i = 0; i < kept; ++i) {
    const auto index = static_cast<std::size_t>(std::floor(i * step));
    evidence.camera_points.push_back(camera_R_rectified * candidates[index].cast<double>());
  }
  evidence.usable = true;
  return evidence;
}

}  // namespace ssta
