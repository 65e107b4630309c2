// The free space of one frame: OctoMap's ray walk written out, each voxel it passes recorded
// once in a bitmap of the rays' box.

#include "mapping/free_space_walk.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>

#include "core/parallel_pair.h"

namespace ssta::internal {
namespace {

/// Calls visit(key) with the key (int[3]) of exactly the voxels OcTreeBaseImpl::computeRayKeys
/// (origin, end) puts in its KeyRay, in the same order: the same Amanatides-Woo walk written
/// out with the same types and arithmetic (keys wrap around at 16 bits like OcTreeKey's).
/// `key_origin`, `key_end`: the checked keys of origin and end. The walk stops early where
/// visit returns false.
template <typename Visit>
void WalkRay(const TravOcTree& tree, const octomap::point3d& origin, const octomap::point3d& end,
             const octomap::OcTreeKey& key_origin, const octomap::OcTreeKey& key_end, Visit&& visit) {
  if (key_origin == key_end) return;
  int key[3] = {key_origin[0], key_origin[1], key_origin[2]};
  const int last[3] = {key_end[0], key_end[1], key_end[2]};
  if (!visit(key)) return;

  octomap::point3d direction = (end - origin);
  const float length = static_cast<float>(direction.norm());
  direction /= length;
  const double resolution = tree.getResolution();
  int step[3];
  double t_max[3];
  double t_delta[3];
  for (unsigned i = 0; i < 3; ++i) {
    if (direction(i) > 0.0) {
      step[i] = 1;
    } else if (direction(i) < 0.0) {
      step[i] = -1;
    } else {
      step[i] = 0;
    }
    if (step[i] != 0) {
      double voxel_border = tree.keyToCoord(key_origin[i]);
      voxel_border += static_cast<float>(step[i] * resolution * 0.5);
      t_max[i] = (voxel_border - origin(i)) / direction(i);
      t_delta[i] = resolution / std::fabs(direction(i));
    } else {
      t_max[i] = std::numeric_limits<double>::max();
      t_delta[i] = std::numeric_limits<double>::max();
    }
  }
  // The step, without a branch on the axis (which a ray's voxels alternate unpredictably):
  // the axis is computeRayKeys' choice, x if t_max x < y and x < z, else y if y < z, else z,
  // and adding 0 leaves a t_max as it was.
  double t0 = t_max[0], t1 = t_max[1], t2 = t_max[2];
  for (;;) {
    const bool x_before_y = t0 < t1;
    const bool before_z = (x_before_y ? t0 : t1) < t2;
    const bool sx = x_before_y && before_z, sy = !x_before_y && before_z, sz = !before_z;
    key[0] = (key[0] + (sx ? step[0] : 0)) & 0xFFFF;
    key[1] = (key[1] + (sy ? step[1] : 0)) & 0xFFFF;
    key[2] = (key[2] + (sz ? step[2] : 0)) & 0xFFFF;
    t0 += sx ? t_delta[0] : 0.0;
    t1 += sy ? t_delta[1] : 0.0;
    t2 += sz ? t_delta[2] : 0.0;
    if (key[0] == last[0] && key[1] == last[1] && key[2] == last[2]) return;
    // computeRayKeys: min(t_max) > length; the t are never NaN, so: all of them are.
    if ((t0 > length) & (t1 > length) & (t2 > length)) return;
    if (!visit(key)) return;
  }
}

/// The box [*lo, *hi] (inclusive keys) of the voxels of the origin and the rays' ends, one
/// voxel wider (a walk may overshoot by one in float) within the key range.
void RayBox(const octomap::OcTreeKey& key_origin, const std::vector<octomap::OcTreeKey>& end_keys,
            std::array<int, 3>* lo, std::array<int, 3>* hi) {
  for (int i = 0; i < 3; ++i) (*lo)[i] = (*hi)[i] = key_origin[i];
  for (const octomap::OcTreeKey& k : end_keys) {
    for (int i = 0; i < 3; ++i) {
      (*lo)[i] = std::min((*lo)[i], static_cast<int>(k[i]));
      (*hi)[i] = std::max((*hi)[i], static_cast<int>(k[i]));
    }
  }
  for (int i = 0; i < 3; ++i) {
    (*lo)[i] = std::max((*lo)[i] - 1, 0);
    (*hi)[i] = std::min((*hi)[i] + 1, 0xFFFF);
  }
}

/// The Morton code of the key (x, y, z) that WalkRay visits.
std::uint64_t CodeOf(const int* k) {
  return TravOcTree::MortonCode(octomap::OcTreeKey(static_cast<octomap::key_type>(k[0]),
                                                   static_cast<octomap::key_type>(k[1]),
                                                   static_cast<octomap::key_type>(k[2])));
}

/// What a tree holds at voxels asked one after the other along a ray: nothing (never
/// observed), a voxel, or a surface it is sure of (occupancy log-odds at least a threshold).
/// Consecutive voxels of a ray share most of their path from the root: each lookup starts from
/// the deepest node the previous one shares with it, and a voxel in the block that decided the
/// previous answer (an unobserved block, or a pruned one) gets that answer without a lookup.
/// Read-only: two probes may read one tree side by side.
class VoxelProbe {
 public:
  enum Held { kNothing, kVoxel, kSureSurface };

  VoxelProbe(const TravOcTree& tree, float threshold)
      : tree_(tree), threshold_(threshold), depth_(tree.getTreeDepth()) {
    path_[0] = tree.getRoot();
  }

  /// What the tree holds at the voxel of key `k` (x, y, z).
  Held At(const int* k) {
    // In the block that decided the last answer (its keys agree above the block's size): the
    // same answer, without the Morton code. Most of an open ray runs through unobserved blocks.
    const unsigned shift = depth_ - decided_by_;
    if (decided_by_ > 0 && ((k[0] ^ last_key_[0]) >> shift) == 0 && ((k[1] ^ last_key_[1]) >> shift) == 0 &&
        ((k[2] ^ last_key_[2]) >> shift) == 0) {
      return answer_;
    }
    last_key_ = {k[0], k[1], k[2]};
    const std::uint64_t code = CodeOf(k);
    unsigned start = 0;  // the depth to descend from: digits 0..start-1 are the last code's
    if (decided_by_ > 0) {
      // Fewer than decided_by_ digits are shared (the test above), so the codes differ.
      const std::uint64_t diff = code ^ last_code_;
      start = depth_ - 1 - (63 - static_cast<unsigned>(__builtin_clzll(diff))) / 3;
    }
    last_code_ = code;
    const TravNode* node = path_[start];
    unsigned d = start;
    for (;;) {
      if (node == nullptr) {  // an empty tree
        answer_ = kNothing;
        decided_by_ = d;
        break;
      }
      if (!tree_.nodeHasChildren(node)) {  // a voxel, or a pruned block of equal voxels
        answer_ = node->getLogOdds() >= threshold_ ? kSureSurface : kVoxel;
        decided_by_ = d;
        break;
      }
      const auto pos = static_cast<unsigned>((code >> (3 * (depth_ - 1 - d))) & 7u);
      if (!tree_.nodeChildExists(node, pos)) {
        answer_ = kNothing;
        decided_by_ = d + 1;
        break;
      }
      node = tree_.getNodeChild(node, pos);
      path_[++d] = node;
    }
    return answer_;
  }

 private:
  const TravOcTree& tree_;
  float threshold_;
  unsigned depth_;
  std::array<const TravNode*, 17> path_{};  ///< path_[d]: the last lookup's node at depth d
  std::uint64_t last_code_ = 0;
  std::array<int, 3> last_key_{};  ///< the key of last_code_
  unsigned decided_by_ = 0;  ///< the last answer holds for every code sharing this many digits
  Held answer_ = kNothing;
};

}  // namespace

void FreeSpaceWalk::Walk(const TravOcTree& tree, const octomap::point3d& origin,
                         const std::vector<octomap::point3d>& ends, const std::vector<octomap::OcTreeKey>& end_keys,
                         const std::vector<octomap::point3d>& open_ends,
                         const std::vector<octomap::OcTreeKey>& open_end_keys, float stop_log_odds) {
  octomap::OcTreeKey key_origin;
  const bool origin_ok = tree.coordToKeyChecked(origin, key_origin);  // the float origin's key
  overflow_.Clear();
  overflow_2_.Clear();
  if (!bitmap_clean_) {
    bitmap_.ClearAll();
    bitmap_2_.ClearAll();
  }
  bitmap_clean_ = false;
  use_bitmap_ = false;
  if (!origin_ok) return;
  std::array<int, 3> lo{}, hi{};
  // The box of the rays to points only: the open rays mark few voxels (those the tree holds),
  // and those outside it go to the sets.
  RayBox(key_origin, end_keys, &lo, &hi);
  use_bitmap_ = bitmap_.Reset(lo, hi);
  if (use_bitmap_) bitmap_2_.Reset(lo, hi);
  // Rays [first, last) into `marks`, or into `outside` where they leave its box (all of them
  // without a bitmap).
  auto walk = [&](std::size_t first, std::size_t last, FreeBitmap* marks, CodeSet* outside) {
    for (std::size_t r = first; r < last; ++r) {
      if (use_bitmap_) {
        WalkRay(tree, origin, ends[r], key_origin, end_keys[r], [&](const int* k) {
          if (!marks->Set(k)) outside->Insert(CodeOf(k));
          return true;
        });
      } else {
        WalkRay(tree, origin, ends[r], key_origin, end_keys[r], [&](const int* k) {
          outside->Insert(CodeOf(k));
          return true;
        });
      }
    }
  };
  // The open rays up to the first sure surface, marking only the voxels the tree holds: each
  // voxel is looked up first.
  auto walk_open = [&](std::size_t first, std::size_t last, FreeBitmap* marks, CodeSet* outside) {
    VoxelProbe probe(tree, stop_log_odds);
    for (std::size_t r = first; r < last; ++r) {
      WalkRay(tree, origin, open_ends[r], key_origin, open_end_keys[r], [&](const int* k) {
        const VoxelProbe::Held held = probe.At(k);
        if (held == VoxelProbe::kSureSurface) return false;
        if (held == VoxelProbe::kVoxel && (!use_bitmap_ || !marks->Set(k))) outside->Insert(CodeOf(k));
        return true;
      });
    }
  };
  const std::size_t half = ends.size() / 2, open_half = open_ends.size() / 2;
  RunPair([&](int part) {
    if (part == 0) {
      walk(0, half, &bitmap_, &overflow_);
      walk_open(0, open_half, &bitmap_, &overflow_);
    } else {
      walk(half, ends.size(), &bitmap_2_, &overflow_2_);
      walk_open(open_half, open_ends.size(), &bitmap_2_, &overflow_2_);
    }
  });
  if (use_bitmap_) bitmap_.TakeBitsOf(&bitmap_2_);
  overflow_2_.ForEach([&](std::uint64_t code) { overflow_.Insert(code); });
}

}  // namespace ssta::internal
