#pragma once

// A classified frame as the map takes it: its labelled pixels as points in the world frame.

#include <vector>

#include <Eigen/Geometry>

#include "ssta/analysis/frame_result.h"
#include "ssta/core/vehicle_options.h"
#include "ssta/mapping/map_options.h"
#include "ssta/mapping/map_types.h"
#include "ssta/stereo/rectifier.h"

namespace ssta {

/// The classified points of one frame in the world frame, every `stride`-th pixel of the
/// common area with a 3D point and a class: class (a pixel labelled 0, without depth or
/// untextured under analysis.label_min_texture, is never emitted), the slope and step of its
/// segment. `world_T_rectified` maps the rectified cam0 frame into the world. With `keep`
/// (the common area's size), pixels where it is 0 are left out. With `point_disparity` (the
/// common area's size), each point moves along its ray to that disparity where both it and the
/// frame's are positive (a refined disparity: MapPointsOfFrame). With `lip` (the common area's
/// size), the points of labelled pixels where it is non-zero are non-traversable, with that
/// value / 255 as their vote_weight.
std::vector<ClassifiedPoint> ClassifiedPointsInWorld(const FrameResult& frame,
                                                     const Eigen::Isometry3d& world_T_rectified, int stride,
                                                     const ImageU8* keep = nullptr,
                                                     const ImageF* point_disparity = nullptr,
                                                     const ImageU8* lip = nullptr);
/// The same into `*points` (cleared first; its capacity is reused from frame to frame).
void ClassifiedPointsInWorld(const FrameResult& frame, const Eigen::Isometry3d& world_T_rectified, int stride,
                             const ImageU8* keep, std::vector<ClassifiedPoint>* points,
                             const ImageF* point_disparity = nullptr, const ImageU8* lip = nullptr);

/// Appends to `*points` a ray that ranged nothing (ClassifiedPoint::no_return) for every
/// `stride`-th pixel (in u and v) of the common area that the texture test left without a label
/// (LabelRule::kTexture) and that looks above the horizon (frame.up_rectified): blank sky, or a
/// blank wall, in whose direction the map clears free space up to the first surface it is sure
/// of (MapOptions::free_space_no_return_stop_prob).
void AppendNoReturnRays(const FrameResult& frame, const Eigen::Isometry3d& world_T_rectified,
                        const RectifiedGeometry& geometry, int stride, std::vector<ClassifiedPoint>* points);

/// Gauss-Newton steps of the map's sub-pixel refinement (map.subpixel_window_px): one moved the
/// yard, drop-off and forest maps as two did (0.866 / 0.971 / 0.895 against 0.865 / 0.971 /
/// 0.896, refined across outlines) at half the cost.
inline constexpr int kMapSubpixelSteps = 1;

/// The points build-map inserts for a frame: ClassifiedPointsInWorld at options.pixel_stride,
/// without the untextured pixels (options.min_texture over the frame's texture_block_px windows;
/// not computed again when the frame's labels_min_texture, the same test on the labels, is at
/// least as strict). It
/// keeps noise matches out of the map. With map.subpixel_window_px, and a frame that kept the
/// matcher's images (FrameResult::left_matched, right_matched), the points sit at the disparity refined to
/// sub-pixel precision (RefineDisparitySubpixel) instead of the matcher's. With
/// options.hidden_drops, the lips of drop-offs whose foot the frame cannot see are
/// non-traversable (the edges FindHiddenDrops finds for `vehicle`, src/analysis/hidden_drops.h):
/// the frame's own (AnalysisResult::lips, searched for the frame's vehicle) when it searched
/// them within this map's range and the stride is 1, else searched here.
/// With options.no_return_stride_px, the rays of the blank sky follow (AppendNoReturnRays).
std::vector<ClassifiedPoint> MapPointsOfFrame(const FrameResult& frame, const Eigen::Isometry3d& world_T_rectified,
                                              const MappingOptions& options, const RectifiedGeometry& geometry,
                                              const VehicleOptions& vehicle);
/// The same into `*points` (cleared first; its capacity is reused from frame to frame).
void MapPointsOfFrame(const FrameResult& frame, const Eigen::Isometry3d& world_T_rectified,
                      const MappingOptions& options, const RectifiedGeometry& geometry, const VehicleOptions& vehicle,
                      std::vector<ClassifiedPoint>* points);

}  // namespace ssta
