#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ssta/analysis/frame_result.h"
#include "ssta/refinement/refinement_options.h"

namespace ssta {

/// What one frame tells about the mount: thinned inlier points of its dominant ground segment,
/// in the ORIGINAL (not rectified) cam0 frame, so they stay valid whatever mount is estimated
/// later (the online window re-solves with the same evidence), and up in the body frame.
struct GroundEvidence {
  std::int64_t timestamp_ns = 0;
  std::vector<Eigen::Vector3d> camera_points;  ///< cam0 frame (x right, y down, z fwd) [m]
  /// Unit up vector in the body frame at this frame (IMU-corrected attitude); used by
  /// GroundReference::kGravity.
  Eigen::Vector3d up_body = Eigen::Vector3d::UnitZ();
  bool usable = false;
  std::string reason;  ///< why the frame is not usable; empty when usable
};

/// Takes the ground evidence out of a processed frame: the pixels of the dominant ground
/// segment with a finite point within `options.max_range_m`, thinned evenly to at most
/// `options.points_per_frame`, rotated from the rectified into the original cam0 frame by
/// `camera_R_rectified` (the transpose of RectifiedGeometry::rectified_R_camera). Not usable,
/// with a reason, when the frame has no ground plane, failed the quality check, or keeps fewer
/// than `options.min_points_per_frame` points. Precondition: `options` is valid.
GroundEvidence ExtractGroundEvidence(const FrameResult& frame, const Eigen::Matrix3d& camera_R_rectified,
                                     const Eigen::Vector3d& up_body, const RefinementOptions& options);

}  // namespace ssta
