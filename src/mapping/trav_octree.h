#pragma once

// Private: the OctoMap node and tree types behind TraversabilityMap. Only src/mapping and the
// mapping tests include this header (it pulls in OctoMap).

#include <array>
#include <cmath>
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include <octomap/OccupancyOcTreeBase.h>
#include <octomap/OcTreeNode.h>

namespace ssta::internal {

class TravOcTree;

/// One voxel: OctoMap's occupancy log-odds (inherited `value`) plus the traversability payload.
/// Inner nodes carry the max child occupancy (OctoMap's rule); their payload is meaningful only
/// when the node is a pruned leaf, in which case it is the payload of all its voxels.
class TravNode : public octomap::OcTreeNode {
 public:
  friend class TravOcTree;

  TravNode() = default;
  /// Deep copy including the children, as TravNodes (OctoMap's own copy constructor would
  /// slice them to the base type).
  TravNode(const TravNode& rhs);
  TravNode& operator=(const TravNode&) = delete;

  /// Equal occupancy and payload (bitwise equal floats); the pruning criterion.
  bool operator==(const TravNode& rhs) const;

  /// Copies occupancy and payload, not the children (used by OctoMap's expand and prune).
  void copyData(const TravNode& from);

  /// Binary payload I/O for .ot files: value, L1..L3, slope, step, max step (float32),
  /// observations (uint32), last_seen_ns (int64), then (format 2 on) surface_z,
  /// surface_weight and surface_xy_sigma_m (float32); native byte order like OctoMap's own. readData reads the layout of
  /// the format ScopedNodeFormat names (the current one by default).
  std::istream& readData(std::istream& s);
  std::ostream& writeData(std::ostream& s) const;

  /// Class log-odds for classes 1..3 (index 0..2).
  std::array<float, 3> class_log_odds{};
  float slope_deg = 0.0f;   ///< running mean over the verdict frames [deg]
  float step_m = 0.0f;      ///< running mean (signed) [m]
  float max_step_m = 0.0f;  ///< largest |step| [m]
  std::uint32_t observations = 0;  ///< frames that gave a class verdict
  std::int64_t last_seen_ns = 0;   ///< last frame that hit the voxel [ns]
  /// The fused height of the surface in this voxel [m, world z]: the inverse-variance weighted
  /// mean of the frames' heights of their points in it.
  float surface_z = 0.0f;
  /// The sum of those frames' inverse height variances [1/m^2]; 0: no height fused.
  float surface_weight = 0.0f;
  /// The horizontal 1-sigma of the best-placed frame's points in this voxel [m]: how far off
  /// its column the fused height may belong (range noise smears far surfaces sideways).
  float surface_xy_sigma_m = 0.0f;
};

/// The map file format whose node layout TravNode::readData reads on this thread while it lives
/// (a map file's metadata names its format before its nodes are read).
class ScopedNodeFormat {
 public:
  explicit ScopedNodeFormat(int format);
  ~ScopedNodeFormat();
  ScopedNodeFormat(const ScopedNodeFormat&) = delete;
  ScopedNodeFormat& operator=(const ScopedNodeFormat&) = delete;

 private:
  int previous_;
};

/// Tree type "SstaTravOcTree", registered with OctoMap's factory so AbstractOcTree::read can
/// create it from a .ot file.
///
/// Pruning: lossless. Eight leaf children collapse only when occupancy and the whole payload
/// are identical (TravNode::operator==), which in practice is free space never hit (all
/// payload zero, occupancy at the lower clamp); expanding copies the payload back to the eight.
class TravOcTree : public octomap::OccupancyOcTreeBase<TravNode> {
 public:
  explicit TravOcTree(double resolution);

  TravOcTree* create() const override { return new TravOcTree(resolution); }
  std::string getTreeType() const override { return kTreeType; }
  bool isNodeCollapsible(const TravNode* node) const override;

  /// Finds or creates the leaf at `key` (expanding a pruned block on the way), calls
  /// `update(leaf)`, then on the way back up prunes or refreshes each ancestor's occupancy.
  /// `update` must not touch the tree structure.
  template <typename Update>
  void UpdateLeaf(const octomap::OcTreeKey& key, Update&& update);

  /// The same tree as UpdateLeaf(key of codes[i], leaf -> update(leaf, i)) for every i, in any
  /// order, but each inner node on the way is visited, pruned and refreshed once per batch
  /// instead of once per key. Preconditions: `codes` are MortonCode values, distinct and sorted
  /// ascending. `unchanged(block, first, last)` may return true when the updates of
  /// codes[first..last) would leave every voxel of the pruned block `block` as it is; the block
  /// is then not expanded (expanding, updating to the same values and pruning again gives the
  /// same tree).
  template <typename Update, typename Unchanged>
  void UpdateLeaves(const std::vector<std::uint64_t>& codes, Update&& update, Unchanged&& unchanged);

  /// Adds the voxels of `from` (a tree of the same resolution) to this tree: where only one
  /// tree holds a voxel, the result holds it as that tree has it; where both do,
  /// `combine(into_voxel, from_voxel)` sets the result's payload and occupancy. A pruned block
  /// meets the other tree's finer nodes voxel by voxel (it is combined with each of them), so
  /// the result does not depend on how either tree was pruned. Visited inner nodes are pruned
  /// or refreshed on the way back up, as UpdateLeaves does. `combine` must not touch the tree
  /// structure. Memory: the nodes this tree gains; `from` is only read.
  template <typename Combine>
  void MergeFrom(const TravOcTree& from, Combine&& combine);

  /// MergeFrom with the other tree's nodes read one at a time, in OctoMap's stream order
  /// (depth first), instead of from a tree: `read(&node, depth)` fills `node`'s occupancy and
  /// payload and returns its child mask (MapFileReader::ReadNode). The same tree results as
  /// from MergeFrom on the tree those nodes make, and memory holds only this tree's nodes.
  template <typename Read, typename Combine>
  void MergeFromNodes(Read&& read, Combine&& combine);

  /// coordToKeyChecked(x, y, z, key) with the same arithmetic, inline: the per-point loop of
  /// InsertFrame would otherwise pay a call and a store-to-load stall on the key per point.
  bool CoordToKeyChecked(double x, double y, double z, octomap::OcTreeKey* key) const {
    const int kx = CoordToScaledKey(x), ky = CoordToScaledKey(y), kz = CoordToScaledKey(z);
    const auto limit = static_cast<int>(2 * tree_max_val);
    if ((kx < 0) | (kx >= limit) | (ky < 0) | (ky >= limit) | (kz < 0) | (kz >= limit)) return false;
    *key = octomap::OcTreeKey(static_cast<octomap::key_type>(kx), static_cast<octomap::key_type>(ky),
                              static_cast<octomap::key_type>(kz));
    return true;
  }

  /// The key's position along the Z-order curve that matches the tree's child order (bit
  /// depth of x, y, z from the most significant level down): sorting keys by it groups every
  /// subtree's keys together.
  static std::uint64_t MortonCode(const octomap::OcTreeKey& key);

  static constexpr const char* kTreeType = "SstaTravOcTree";

 private:
  /// Child `pos` of `node` for an update, created if missing; a pruned block (a leaf that was not
  /// just created) is expanded instead, so that its eight voxels keep its payload.
  /// `*child_created`: the child is new.
  TravNode* ChildForUpdate(TravNode* node, unsigned pos, bool just_created, bool* child_created) {
    *child_created = false;
    if (!nodeChildExists(node, pos)) {
      if (!nodeHasChildren(node) && !just_created) {
        expandNode(node);
      } else {
        createNodeChild(node, pos);
        *child_created = true;
      }
    }
    return getNodeChild(node, pos);
  }
  /// MergeFrom below `into`, whose region `from` covers node for node.
  template <typename Combine>
  void MergeNodeRecurs(TravNode* into, const TravNode& from, Combine& combine);
  /// MergeFrom below `into`, whose whole region the pruned block `block` covers uniformly.
  template <typename Combine>
  void MergeBlockRecurs(TravNode* into, const TravNode& block, Combine& combine);
  /// MergeFromNodes below `into`, whose region the next node read covers.
  template <typename Read, typename Combine>
  void MergeReadRecurs(TravNode* into, unsigned depth, Read& read, Combine& combine);
  /// Gives `into` (a new node) the payload and the subtree of the next node read.
  template <typename Read>
  void ReadSubtree(TravNode* into, unsigned depth, Read& read);
  /// Gives `into` (a node without children) the payload and the subtree of `from`.
  void CopySubtree(TravNode* into, const TravNode& from);
  /// OctoMap's floor(resolution_factor * c) + tree_max_val, or -1 when that lies outside
  /// [-tree_max_val, tree_max_val) (where OctoMap's int conversion could overflow).
  int CoordToScaledKey(double c) const {
    const double scaled = std::floor(resolution_factor * c);
    const auto half = static_cast<double>(tree_max_val);
    if (!(scaled >= -half && scaled < half)) return -1;
    return static_cast<int>(scaled) + static_cast<int>(tree_max_val);
  }
  template <typename Update, typename Unchanged>
  void UpdateBatchRecurs(TravNode* node, bool just_created, const std::vector<std::uint64_t>& codes,
                         std::size_t first, std::size_t last, unsigned depth, Update& update,
                         Unchanged& unchanged);

  /// Registers the prototype with OctoMap's factory once, at static initialisation.
  class StaticMemberInitializer {
   public:
    StaticMemberInitializer();
    void EnsureLinking() {}
  };
  static StaticMemberInitializer registration_;
};

template <typename Update>
void TravOcTree::UpdateLeaf(const octomap::OcTreeKey& key, Update&& update) {
  // A batch of one: the same walk, so one code path builds every tree.
  UpdateLeaves({MortonCode(key)}, [&](TravNode& leaf, std::size_t) { update(leaf); },
               [](const TravNode&, std::size_t, std::size_t) { return false; });
}

inline std::uint64_t TravOcTree::MortonCode(const octomap::OcTreeKey& key) {
  // Spreads the 16 bits of v to every third bit.
  auto spread = [](std::uint64_t v) {
    v = (v | (v << 16)) & 0x0000FF0000FFull;
    v = (v | (v << 8)) & 0x00F00F00F00Full;
    v = (v | (v << 4)) & 0x0C30C30C30C3ull;
    v = (v | (v << 2)) & 0x249249249249ull;
    return v;
  };
  // computeChildIdx: x is bit 0, y bit 1, z bit 2 of each level's child index.
  return spread(key[0]) | (spread(key[1]) << 1) | (spread(key[2]) << 2);
}

template <typename Update, typename Unchanged>
void TravOcTree::UpdateLeaves(const std::vector<std::uint64_t>& codes, Update&& update,
                              Unchanged&& unchanged) {
  if (codes.empty()) return;
  bool created_root = false;
  if (root == nullptr) {
    root = new TravNode();
    ++tree_size;
    created_root = true;
  }
  UpdateBatchRecurs(root, created_root, codes, 0, codes.size(), 0, update, unchanged);
}

template <typename Update, typename Unchanged>
void TravOcTree::UpdateBatchRecurs(TravNode* node, bool just_created,
                                   const std::vector<std::uint64_t>& codes, std::size_t first,
                                   std::size_t last, unsigned depth, Update& update,
                                   Unchanged& unchanged) {
  if (depth == tree_depth) {
    update(*node, first);  // distinct keys: one per leaf
    return;
  }
  if (!just_created && !nodeHasChildren(node) && unchanged(*node, first, last)) return;
  // The child index at this depth is the code's 3-bit digit of this level (see MortonCode).
  const unsigned shift = 3 * (tree_depth - 1 - depth);
  std::size_t begin = first;
  while (begin < last) {
    const auto pos = static_cast<unsigned>((codes[begin] >> shift) & 7u);
    std::size_t end = begin + 1;
    while (end < last && static_cast<unsigned>((codes[end] >> shift) & 7u) == pos) ++end;
    bool child_created = false;
    TravNode* child = ChildForUpdate(node, pos, just_created, &child_created);
    UpdateBatchRecurs(child, child_created, codes, begin, end, depth + 1, update, unchanged);
    begin = end;
  }
  if (!pruneNode(node)) node->updateOccupancyChildren();
}

template <typename Combine>
void TravOcTree::MergeFrom(const TravOcTree& from, Combine&& combine) {
  if (from.root == nullptr) return;
  if (root == nullptr) {
    root = new TravNode();
    ++tree_size;
    size_changed = true;
    CopySubtree(root, *from.root);
    return;
  }
  MergeNodeRecurs(root, *from.root, combine);
}

template <typename Combine>
void TravOcTree::MergeNodeRecurs(TravNode* into, const TravNode& from, Combine& combine) {
  if (!nodeHasChildren(&from)) {
    MergeBlockRecurs(into, from, combine);
    return;
  }
  // `from` is finer here: a pruned block of this tree is split so that each of its voxels
  // meets its counterpart (expandNode copies the block's payload to the eight children).
  if (!nodeHasChildren(into)) expandNode(into);
  for (unsigned i = 0; i < 8; ++i) {
    if (!nodeChildExists(&from, i)) continue;
    const TravNode& from_child = *getNodeChild(&from, i);
    if (nodeChildExists(into, i)) {
      MergeNodeRecurs(getNodeChild(into, i), from_child, combine);
    } else {
      CopySubtree(createNodeChild(into, i), from_child);
    }
  }
  if (!pruneNode(into)) into->updateOccupancyChildren();
}

template <typename Combine>
void TravOcTree::MergeBlockRecurs(TravNode* into, const TravNode& block, Combine& combine) {
  if (!nodeHasChildren(into)) {
    combine(*into, block);
    return;
  }
  for (unsigned i = 0; i < 8; ++i) {
    if (nodeChildExists(into, i)) {
      MergeBlockRecurs(getNodeChild(into, i), block, combine);
    } else {
      createNodeChild(into, i)->copyData(block);  // unobserved here: the block's voxels as they are
    }
  }
  if (!pruneNode(into)) into->updateOccupancyChildren();
}

template <typename Read, typename Combine>
void TravOcTree::MergeFromNodes(Read&& read, Combine&& combine) {
  if (root == nullptr) {
    root = new TravNode();
    ++tree_size;
    size_changed = true;
    ReadSubtree(root, 0, read);
    return;
  }
  MergeReadRecurs(root, 0, read, combine);
}

template <typename Read, typename Combine>
void TravOcTree::MergeReadRecurs(TravNode* into, unsigned depth, Read& read, Combine& combine) {
  TravNode from;
  const unsigned children = read(&from, depth);
  if (children == 0) {
    MergeBlockRecurs(into, from, combine);
    return;
  }
  // As MergeNodeRecurs: an inner node's own payload means nothing, its children are read next.
  if (!nodeHasChildren(into)) expandNode(into);
  for (unsigned i = 0; i < 8; ++i) {
    if (((children >> i) & 1u) == 0) continue;
    if (nodeChildExists(into, i)) {
      MergeReadRecurs(getNodeChild(into, i), depth + 1, read, combine);
    } else {
      ReadSubtree(createNodeChild(into, i), depth + 1, read);
    }
  }
  if (!pruneNode(into)) into->updateOccupancyChildren();
}

template <typename Read>
void TravOcTree::ReadSubtree(TravNode* into, unsigned depth, Read& read) {
  const unsigned children = read(into, depth);
  for (unsigned i = 0; i < 8; ++i) {
    if ((children >> i) & 1u) ReadSubtree(createNodeChild(into, i), depth + 1, read);
  }
}

/// Calls fn(key) for every full-resolution voxel of a leaf at `depth` whose lowest voxel is
/// `base` (a pruned leaf covers 2^(tree_depth - depth) voxels along each axis).
template <typename Fn>
void ForEachVoxelOfLeaf(const octomap::OcTreeKey& base, unsigned tree_depth, unsigned depth, Fn&& fn) {
  const unsigned n = 1u << (tree_depth - depth);
  for (unsigned i = 0; i < n; ++i) {
    for (unsigned j = 0; j < n; ++j) {
      for (unsigned k = 0; k < n; ++k) {
        fn(octomap::OcTreeKey(static_cast<octomap::key_type>(base[0] + i), static_cast<octomap::key_type>(base[1] + j),
                              static_cast<octomap::key_type>(base[2] + k)));
      }
    }
  }
}

}  // namespace ssta::internal
