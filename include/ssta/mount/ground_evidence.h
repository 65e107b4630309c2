#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <optional>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "ssta/analysis/frame_result.h"
#include "ssta/mount/refinement_options.h"

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
  /// Unit normal the ground under camera_points is expected along, in the body frame at this
  /// frame: the mean body z of the later poses that stand on those points (GroundReference::kPath;
  /// body z when the path is not known).
  Eigen::Vector3d path_up_body = Eigen::Vector3d::UnitZ();
  bool usable = false;
  std::string reason;  ///< why the frame is not usable; empty when usable
};

/// Takes the ground evidence out of a processed frame: the pixels of the dominant ground
/// segment with a finite point within `options.max_range_m`, thinned evenly to at most
/// `options.points_per_frame`, rotated from the rectified into the original cam0 frame by
/// `camera_R_rectified` (the transpose of RectifiedGeometry::rectified_R_camera). Not usable,
/// with a reason, when the frame has no ground plane, failed the quality check, or keeps fewer
/// than `options.min_points_per_frame` points. `keep`, when given, chooses the points before the
/// thinning (argument: the point in the original cam0 frame [m]); `keep_reason` then names what it
/// keeps in the reason of a frame left with too few points. Precondition: `options` is valid.
GroundEvidence ExtractGroundEvidence(const FrameResult& frame, const Eigen::Matrix3d& camera_R_rectified,
                                     const Eigen::Vector3d& up_body, const RefinementOptions& options,
                                     const std::function<bool(const Eigen::Vector3d&)>& keep = {},
                                     const std::string& keep_reason = "");

/// The ground the vehicle drives over later, seen from one frame (GroundReference::kPath): for a
/// point in that frame's original cam0 frame, the later frame whose body stands on it (within
/// path_half_length_m along that body's x and path_half_width_m along its y; the nearest along
/// x), and the ground that body stands on, in this frame's body.
class DrivenOverGround {
 public:
  /// `world_T_body`: the pose of every frame of the drive, in order (nullopt: none); `frame`
  /// the index of this one; `body_T_camera` the mount the points are mapped through.
  DrivenOverGround(const std::vector<std::optional<Eigen::Isometry3d>>& world_T_body, std::size_t frame,
                   const Eigen::Isometry3d& body_T_camera, const RefinementOptions& options);

  /// Whether a later body stands on `p_camera` (original cam0 frame) [m].
  bool Contains(const Eigen::Vector3d& p_camera) const { return Find(p_camera) >= 0; }
  /// Mean body z, in this frame's body, of the later bodies standing on `points`; body z when
  /// none does (unit).
  Eigen::Vector3d MeanUp(const std::vector<Eigen::Vector3d>& points) const;
  /// The normal, in this frame's body, of the plane a least-squares fit through `points` finds
  /// if the ground under each point is the wheel plane of the later body standing on it:
  /// parallel to that body's x-y plane, as far below its origin as the points lie in the median
  /// over all bodies, less the sag of curving ground below the chords the wheels span
  /// (RefinementOptions::wheelbase_m along the way, with its curvature from the later bodies'
  /// pitch; RefinementOptions::track_m across it, with its curvature from the points' shape),
  /// and the twist of a side slope that turns along the way (from the later bodies' roll), each
  /// with how it changes along the way.
  /// On curved ground one plane over a long stretch tilts by how its points spread, not by the
  /// mean of the bodies' tilts; this is the normal to compare it with. MeanUp when fewer than
  /// 3 points have a body or they span no plane (a strip under 1 cm wide, in the RMS). `bend`,
  /// when given, receives per point how far that ground lies above the fitted plane along this
  /// frame's body z [m] (0 for a point no body stands on).
  Eigen::Vector3d ExpectedUp(const std::vector<Eigen::Vector3d>& points, std::vector<double>* bend = nullptr) const;

 private:
  int Find(const Eigen::Vector3d& p_camera) const;
  /// The ground's curvature across the way [1/m], one for the stretch, from the shape of the
  /// `points` whose `body` index is not negative; 0 when they span no quadratic surface.
  double CurvatureAcross(const std::vector<Eigen::Vector3d>& points, const std::vector<int>& body) const;
  double half_length_, half_width_;
  Eigen::Isometry3d body_T_camera_ = Eigen::Isometry3d::Identity();
  std::vector<Eigen::Isometry3d> later_T_camera_;
  std::vector<Eigen::Vector3d> up_;      ///< later body z in this frame's body
  std::vector<Eigen::Vector3d> origin_;  ///< later body origin in this frame's body [m]
  std::vector<double> curvature_;        ///< the way's curvature at each later body [1/m]
  std::vector<double> twist_;            ///< how its side slope turns per metre driven there [1/m]
  std::vector<double> curvature_rate_;   ///< how the curvature changes per metre driven [1/m^2]
  std::vector<double> twist_rate_;       ///< how the twist changes per metre driven [1/m^2]
  double half_wheelbase_m_ = 0.0;
  double half_track_m_ = 0.0;
};

}  // namespace ssta
