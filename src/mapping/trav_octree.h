#pragma once

// Private: the OctoMap node and tree types behind TraversabilityMap. Only src/mapping and the
// mapping tests include this header (it pulls in OctoMap).

#include <array>
#include <cstdint>
#include <iosfwd>
#include <string>

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
  /// observations (uint32), last_seen_ns (int64), native byte order like OctoMap's own.
  std::istream& readData(std::istream& s);
  std::ostream& writeData(std::ostream& s) const;

  /// Class log-odds for classes 1..3 (index 0..2).
  std::array<float, 3> class_log_odds{};
  float slope_deg = 0.0f;   ///< running mean over the verdict frames [deg]
  float step_m = 0.0f;      ///< running mean (signed) [m]
  float max_step_m = 0.0f;  ///< largest |step| [m]
  std::uint32_t observations = 0;  ///< frames that gave a class verdict
  std::int64_t last_seen_ns = 0;   ///< last frame that hit the voxel [ns]
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

  static constexpr const char* kTreeType = "SstaTravOcTree";

 private:
  template <typename Update>
  void UpdateRecurs(TravNode* node, bool just_created, const octomap::OcTreeKey& key,
                    unsigned depth, Update& update);

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
  bool created_root = false;
  if (root == nullptr) {
    root = new TravNode();
    ++tree_size;
    created_root = true;
  }
  UpdateRecurs(root, created_root, key, 0, update);
}

template <typename Update>
void TravOcTree::UpdateRecurs(TravNode* node, bool just_created, const octomap::OcTreeKey& key,
                              unsigned depth, Update& update) {
  if (depth == tree_depth) {
    update(*node);
    return;
  }
  const unsigned pos = octomap::computeChildIdx(key, static_cast<int>(tree_depth - 1 - depth));
  bool child_created = false;
  if (!nodeChildExists(node, pos)) {
    if (!nodeHasChildren(node) && !just_created) {
      expandNode(node);  // a pruned block: its eight voxels get its payload
    } else {
      createNodeChild(node, pos);
      child_created = true;
    }
  }
  UpdateRecurs(getNodeChild(node, pos), child_created, key, depth + 1, update);
  if (!pruneNode(node)) node->updateOccupancyChildren();
}

}  // namespace ssta::internal
