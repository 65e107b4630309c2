#include <cmath>
#include <memory>
#include <random>
#include <sstream>
#include <vector>

#include <gtest/gtest.h>
#include <octomap/AbstractOcTree.h>

#include "map_test_util.h"

namespace ssta {
namespace {

using internal::TravNode;
using internal::TravOcTree;
using testing::OctoMapCarving;
using testing::Tree;

TEST(TravOcTree, InlineCoordToKeyCheckedIsOctoMapsOwn) {
  std::mt19937 rng(5);
  for (const double res : {0.1, 0.05, 0.25}) {
    MapOptions options = OctoMapCarving();
    options.resolution_m = res;
    const TraversabilityMap map(options);
    const TravOcTree& tree = Tree(map);
    const double edge = 32768 * res;  // the addressable cube is [-edge, edge)
    std::vector<double> coords = {0.0, -0.0, res, -res, 0.5 * res, edge, -edge, std::nextafter(edge, 0.0),
                                  std::nextafter(-edge, 0.0), std::nextafter(-edge, -1e9), 1e9, -1e9};
    std::uniform_real_distribution<double> near_edge(-1.01 * edge, 1.01 * edge);
    for (int i = 0; i < 20000; ++i) coords.push_back(near_edge(rng));
    for (const double c : coords) {
      for (int axis = 0; axis < 3; ++axis) {
        const double x = axis == 0 ? c : 1.0, y = axis == 1 ? c : -2.0, z = axis == 2 ? c : 0.3;
        octomap::OcTreeKey stock, own;
        const bool stock_ok = tree.coordToKeyChecked(x, y, z, stock);
        ASSERT_EQ(tree.CoordToKeyChecked(x, y, z, &own), stock_ok) << c << " res " << res;
        if (stock_ok) {
          ASSERT_EQ(own, stock) << c << " res " << res;
        }
      }
    }
  }
}

TEST(TravOcTree, WorldToKeyToWorldStaysWithinHalfAVoxel) {
  std::mt19937 rng(7);
  for (const double res : {0.1, 0.05, 0.25}) {
    MapOptions options = OctoMapCarving();
    options.resolution_m = res;
    const TraversabilityMap map(options);
    const TravOcTree& tree = Tree(map);
    const double extent = 0.99 * 32768 * res;  // inside the addressable cube
    std::uniform_real_distribution<double> coord(-extent, extent);
    for (int i = 0; i < 20000; ++i) {
      const Eigen::Vector3d p(coord(rng), coord(rng), coord(rng) * 0.01);
      const CellInfo cell = map.CellAt(p);
      ASSERT_FALSE(cell.observed);
      for (int a = 0; a < 3; ++a) {
        ASSERT_LE(std::abs(cell.center[a] - p[a]), 0.5 * res + 1e-9) << "axis " << a << " res " << res;
      }
      // The centre maps back to the same voxel.
      const octomap::OcTreeKey key = tree.coordToKey(p.x(), p.y(), p.z());
      const octomap::OcTreeKey again = tree.coordToKey(cell.center.x(), cell.center.y(), cell.center.z());
      ASSERT_EQ(key, again);
      ASSERT_EQ(map.CellAt(cell.center).center, cell.center);
    }
  }
}

TEST(TravOcTree, IsRegisteredWithOctoMapsFactory) {
  std::unique_ptr<octomap::AbstractOcTree> tree(octomap::AbstractOcTree::createTree("SstaTravOcTree", 0.2));
  ASSERT_NE(tree, nullptr);
  EXPECT_EQ(tree->getTreeType(), "SstaTravOcTree");
  EXPECT_NE(dynamic_cast<TravOcTree*>(tree.get()), nullptr);
  EXPECT_DOUBLE_EQ(tree->getResolution(), 0.2);
}

TravNode FilledNode() {
  TravNode node;
  node.setLogOdds(1.25f);
  node.class_log_odds = {-0.5f, 2.0f, 3.5f};
  node.slope_deg = 12.5f;
  node.step_m = -0.07f;
  node.max_step_m = 0.31f;
  node.observations = 42;
  node.last_seen_ns = 1403636580013555456LL;
  node.surface_z = -0.43f;
  node.surface_weight = 2500.0f;
  node.surface_xy_sigma_m = 0.03f;
  return node;
}

TEST(TravOcTree, NodePayloadRoundTripsThroughItsBinaryForm) {
  const TravNode node = FilledNode();
  std::stringstream s;
  node.writeData(s);
  EXPECT_EQ(s.str().size(), 4u * 7 + 4 + 8 + 4 * 3);
  TravNode read;
  read.readData(s);
  EXPECT_TRUE(s.good());
  EXPECT_TRUE(read == node);
  TravNode other = FilledNode();
  other.last_seen_ns += 1;
  EXPECT_FALSE(other == node);
}

TEST(TravOcTree, CollapsesOnlyIdenticalPayloads) {
  TravOcTree tree(0.1);
  const octomap::OcTreeKey base(32768, 32768, 32768);  // a 2x2x2 block: keys base + {0,1}^3
  auto set_all = [&](std::uint32_t observations_of_last) {
    for (int i = 0; i < 8; ++i) {
      const octomap::OcTreeKey key(base[0] + (i & 1), base[1] + ((i >> 1) & 1), base[2] + ((i >> 2) & 1));
      tree.UpdateLeaf(key, [&](TravNode& n) {
        n.setLogOdds(2.0f);
        n.class_log_odds = {1.0f, 0.0f, 0.0f};
        n.observations = i == 7 ? observations_of_last : 3;
      });
    }
  };
  set_all(4);  // one payload differs: no pruning
  EXPECT_EQ(tree.getNumLeafNodes(), 8u);
  set_all(3);  // all identical: the block collapses into one leaf carrying the payload
  EXPECT_EQ(tree.getNumLeafNodes(), 1u);
  const TravNode* block = tree.search(base);
  ASSERT_NE(block, nullptr);
  EXPECT_EQ(block->observations, 3u);
  EXPECT_FLOAT_EQ(block->class_log_odds[0], 1.0f);
  // Updating one voxel expands the block again; the other seven keep the payload.
  tree.UpdateLeaf(base, [](TravNode& n) { n.observations = 9; });
  EXPECT_EQ(tree.getNumLeafNodes(), 8u);
  const octomap::OcTreeKey neighbour(base[0] + 1, base[1], base[2]);
  EXPECT_EQ(tree.search(neighbour)->observations, 3u);
  EXPECT_EQ(tree.search(base)->observations, 9u);
}

TEST(TravOcTree, TreeCopyIsDeepAndKeepsEveryPayload) {
  // OctoMap's tree copy constructor copies the root with NODE's copy constructor; ours must
  // copy the children as TravNodes (OctoMap's own would slice them).
  TravOcTree tree(0.1);
  const octomap::OcTreeKey key(100, 200, 300);
  tree.UpdateLeaf(key, [](TravNode& n) {
    n.observations = 5;
    n.slope_deg = 7.5f;
    n.setLogOdds(1.0f);
  });
  const TravOcTree copy(tree);
  const TravNode* node = copy.search(key);
  ASSERT_NE(node, nullptr);
  EXPECT_NE(node, tree.search(key));
  EXPECT_EQ(node->observations, 5u);
  EXPECT_FLOAT_EQ(node->slope_deg, 7.5f);
  EXPECT_FLOAT_EQ(node->getLogOdds(), 1.0f);
  EXPECT_EQ(copy.size(), tree.size());
}

}  // namespace
}  // namespace ssta
