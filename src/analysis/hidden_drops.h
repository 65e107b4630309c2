#pragma once

// Drop-offs that a frame cannot see the foot of: the lip of a cliff, the near edge of a ditch.

#include <Eigen/Geometry>

#include "ssta/core/vehicle_options.h"
#include "ssta/core/image.h"

namespace ssta::internal {

/// Marks the pixels of a lip: the ground within `vehicle.step_radius_m` (horizontally, in every
/// direction) of an edge where the view passes over the edge and lands lower. Up each image
/// column (away from the camera), a point A on a surface (the point before it in the column
/// lies within `vehicle.semi_step_m`, beyond noise, of A's height) whose next point B lies
/// farther from the camera and lower than A by more than `vehicle.max_step_m` plus three sigmas
/// of the two heights' stereo noise is an edge: whatever joins A to B is hidden below the ray
/// over A. So is a point A whose next point B lies lower by less, but by more than
/// `vehicle.semi_step_m` beyond the noise, on a face that rises towards B's neighbours more
/// steeply than `vehicle.max_slope_deg`: the far wall of a pit, whose floor lies below the ray,
/// deeper than the wall shows. Where that wall rises back to A's height, give or take the noise,
/// it drops to the same floor, so B is an edge too (the pit's far rim). So is a point A with
/// nothing beyond it in its column whose ray, had a floor lain within max_step_m below A, would
/// have met it before `range_m` (the map's range; 0: never). A ray that descends more steeply than
/// `vehicle.max_slope_deg` hides a drop no wheel may take; a flatter one may hide a drivable
/// slope (the far side of a ramp's crest), which nearer views show.
/// The points of the edge's column within the step radius of it, and from each of them the
/// points of its row within the step radius of the same edge point (so the band keeps its width
/// beside an edge the columns cross obliquely, as along the sides of a pit), get
/// 255 min(1, tan(ray) / tan(max_slope)) (at least 5), the weight of the suspicion; 0 elsewhere.
/// `cloud`: the frame's organized cloud (rectified cam0 frame, non-finite where no depth);
/// `world_T_rectified` puts it in the world (z up); `depth_noise_per_m2`: the depth sigma per
/// square metre of depth (FrameResult::depth_noise_per_m2); columns every `stride` pixels.
ImageU8 FindHiddenDrops(const Image3f& cloud, const Eigen::Isometry3d& world_T_rectified, double depth_noise_per_m2,
                        const VehicleOptions& vehicle, double range_m, int stride);

/// FindHiddenDrops for the frame's own labels, every column: heights and ranges in the frame
/// levelled by `up_camera` (unit, the rectified camera frame), from the camera. The same marks
/// as the map's search in the world at the same `range_m` (0: a column with nothing beyond its
/// last point marks nothing).
ImageU8 FindFramesHiddenDrops(const Image3f& cloud, const Eigen::Vector3d& up_camera, double depth_noise_per_m2,
                              const VehicleOptions& vehicle, double range_m);

}  // namespace ssta::internal
