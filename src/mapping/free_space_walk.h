#pragma once

// Private: the voxels one frame's rays pass, which InsertFrame updates as free.

#include <cstdint>
#include <vector>

#include "mapping/trav_octree.h"
#include "mapping/voxel_containers.h"

namespace ssta::internal {

/// The set of voxels that one frame's rays pass, each once: one bit per voxel of the box the
/// rays to points span (FreeBitmap), and a CodeSet of Morton codes for the voxels outside it
/// (rare: the few voxels the open rays mark beyond it), or for all of them when the box is too
/// large for a bitmap.
/// The rays are walked in two halves side by side, each into its own bitmap and set, then
/// merged: a set of voxels, so the same for any split. Kept from frame to frame, so that a
/// frame allocates nothing once its buffers have grown.
class FreeSpaceWalk {
 public:
  /// Collects the voxels that the rays from `origin` to each of `ends` (keys `end_keys`,
  /// checked) pass: exactly those OcTreeBaseImpl::computeRayKeys gives (the end voxel
  /// excluded). None when `origin` lies outside the map. Once per frame, then TakeFreeVoxels.
  /// `open_ends` (keys `open_end_keys`): rays that ranged nothing (ClassifiedPoint::no_return).
  /// Each collects only the voxels `tree` holds, and stops before the first one whose occupancy
  /// log-odds is at least `stop_log_odds` (a surface the map is sure of).
  void Walk(const TravOcTree& tree, const octomap::point3d& origin,
            const std::vector<octomap::point3d>& ends, const std::vector<octomap::OcTreeKey>& end_keys,
            const std::vector<octomap::point3d>& open_ends = {},
            const std::vector<octomap::OcTreeKey>& open_end_keys = {}, float stop_log_odds = 0.0f);

  /// Calls emit(Morton code) once for every collected voxel that the frame's points did not
  /// hit, and empties the set. `hit_keys`: the keys of the hit voxels; `hits`: the frame's
  /// voxels by Morton code (an entry with a hit index >= 0 is hit).
  template <typename Emit>
  void TakeFreeVoxels(const std::vector<octomap::OcTreeKey>& hit_keys, const VoxelIndex& hits, Emit&& emit);

 private:
  FreeBitmap bitmap_, bitmap_2_;   ///< the voxels in the rays' box, of either half of the rays
  CodeSet overflow_, overflow_2_;  ///< the voxels outside it
  bool use_bitmap_ = false;        ///< the box fits a bitmap (else every voxel is in a CodeSet)
  bool bitmap_clean_ = true;  ///< false while bits may be set (an exception could leave some)
};

template <typename Emit>
void FreeSpaceWalk::TakeFreeVoxels(const std::vector<octomap::OcTreeKey>& hit_keys, const VoxelIndex& hits,
                                   Emit&& emit) {
  if (use_bitmap_) {
    for (const octomap::OcTreeKey& key : hit_keys) bitmap_.Unset(key);  // hits win
    bitmap_.Drain(emit);
  }
  bitmap_clean_ = true;
  overflow_.ForEach([&](std::uint64_t code) {
    const VoxelIndex::Entry* e = hits.Find(code);
    if (e == nullptr || e->hit < 0) emit(code);
  });
}

}  // namespace ssta::internal
