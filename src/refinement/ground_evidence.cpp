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
  // Candidates: the ground segment's finite points within range, in scan order. Counted first,
  // then walked again to keep the thinned ones, so no frame-sized buffer is built.
  const float max_range_sq = static_cast<float>(options.max_range_m * options.max_range_m);
  auto for_each_candidate = [&](auto&& visit) {
    for (int v = 0; v < frame.cloud.height(); ++v) {
      for (int u = 0; u < frame.cloud.width(); ++u) {
        if (frame.segment_ids(v, u) != ground.segment_id) continue;
        const Eigen::Vector3f& p = frame.cloud(v, u);
        if (p.allFinite() && p.squaredNorm() <= max_range_sq) visit(p);
      }
    }
  };
  std::size_t count = 0;
  for_each_candidate([&](const Eigen::Vector3f&) { ++count; });
  if (static_cast<int>(count) < options.min_points_per_frame) {
    evidence.reason = "ground plane has " + std::to_string(count) + " points within " +
                      std::to_string(options.max_range_m) + " m, fewer than min_points_per_frame";
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

}  // namespace ssta
