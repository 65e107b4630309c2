#include "mapping/trav_octree.h"

#include "ssta/mapping/traversability_map.h"

#include <cstring>
#include <istream>
#include <ostream>

namespace ssta::internal {
namespace {

template <typename T>
void ReadRaw(std::istream& s, T* v) {
  s.read(reinterpret_cast<char*>(v), sizeof(T));
}

bool SameBits(float a, float b) { return std::memcmp(&a, &b, sizeof(float)) == 0; }

/// The map file format whose node layout readData reads on this thread.
thread_local int node_format = kMapFormatVersion;

}  // namespace

ScopedNodeFormat::ScopedNodeFormat(int format) : previous_(node_format) { node_format = format; }
ScopedNodeFormat::~ScopedNodeFormat() { node_format = previous_; }

TravNode::TravNode(const TravNode& rhs) : octomap::OcTreeNode() {
  copyData(rhs);
  if (rhs.children != nullptr) {
    allocChildren();
    for (unsigned i = 0; i < 8; ++i) {
      if (rhs.children[i] != nullptr) {
        children[i] = new TravNode(*static_cast<const TravNode*>(rhs.children[i]));
      }
    }
  }
}

bool TravNode::operator==(const TravNode& rhs) const {
  // Bitwise float comparison: pruning must be lossless, and +0/-0 or NaN must not merge.
  return SameBits(value, rhs.value) && SameBits(class_log_odds[0], rhs.class_log_odds[0]) &&
         SameBits(class_log_odds[1], rhs.class_log_odds[1]) &&
         SameBits(class_log_odds[2], rhs.class_log_odds[2]) && SameBits(slope_deg, rhs.slope_deg) &&
         SameBits(step_m, rhs.step_m) && SameBits(max_step_m, rhs.max_step_m) &&
         observations == rhs.observations && last_seen_ns == rhs.last_seen_ns &&
         SameBits(surface_z, rhs.surface_z) && SameBits(surface_weight, rhs.surface_weight) &&
         SameBits(surface_xy_sigma_m, rhs.surface_xy_sigma_m);
}

void TravNode::copyData(const TravNode& from) {
  octomap::OcTreeNode::copyData(from);
  class_log_odds = from.class_log_odds;
  slope_deg = from.slope_deg;
  step_m = from.step_m;
  max_step_m = from.max_step_m;
  observations = from.observations;
  last_seen_ns = from.last_seen_ns;
  surface_z = from.surface_z;
  surface_weight = from.surface_weight;
  surface_xy_sigma_m = from.surface_xy_sigma_m;
}

std::istream& TravNode::readData(std::istream& s) {
  ReadRaw(s, &value);
  for (float& l : class_log_odds) ReadRaw(s, &l);
  ReadRaw(s, &slope_deg);
  ReadRaw(s, &step_m);
  ReadRaw(s, &max_step_m);
  ReadRaw(s, &observations);
  ReadRaw(s, &last_seen_ns);
  if (node_format >= 2) {
    ReadRaw(s, &surface_z);
    ReadRaw(s, &surface_weight);
    ReadRaw(s, &surface_xy_sigma_m);
  } else {
    surface_z = surface_weight = surface_xy_sigma_m = 0.0f;
  }
  return s;
}

std::ostream& TravNode::writeData(std::ostream& s) const {
  // The fields packed one after the other, then one write: a map holds millions of nodes.
  char bytes[sizeof(value) + sizeof(class_log_odds) + 6 * sizeof(float) + sizeof(observations) +
             sizeof(last_seen_ns)];
  char* at = bytes;
  const auto put = [&at](const auto& v) {
    std::memcpy(at, &v, sizeof(v));
    at += sizeof(v);
  };
  put(value);
  for (const float l : class_log_odds) put(l);
  put(slope_deg);
  put(step_m);
  put(max_step_m);
  put(observations);
  put(last_seen_ns);
  put(surface_z);
  put(surface_weight);
  put(surface_xy_sigma_m);
  SSTA_CHECK(at == bytes + sizeof(bytes), "TravNode::writeData: the fields do not fill the record");
  s.write(bytes, sizeof(bytes));
  return s;
}

TravOcTree::StaticMemberInitializer TravOcTree::registration_;

TravOcTree::StaticMemberInitializer::StaticMemberInitializer() {
  // OctoMap's factory keeps (and owns) one prototype per tree type.
  auto* prototype = new TravOcTree(0.1);
  prototype->clearKeyRays();
  octomap::AbstractOcTree::registerTreeType(prototype);
}

TravOcTree::TravOcTree(double resolution) : octomap::OccupancyOcTreeBase<TravNode>(resolution) {
  registration_.EnsureLinking();
}

void TravOcTree::CopySubtree(TravNode* into, const TravNode& from) {
  into->copyData(from);
  for (unsigned i = 0; i < 8; ++i) {
    if (nodeChildExists(&from, i)) CopySubtree(createNodeChild(into, i), *getNodeChild(&from, i));
  }
}

bool TravOcTree::isNodeCollapsible(const TravNode* node) const {
  // Same rule as OctoMap's, spelled out so that it visibly compares the whole payload.
  if (!nodeChildExists(node, 0)) return false;
  const TravNode* first = getNodeChild(node, 0);
  if (nodeHasChildren(first)) return false;
  for (unsigned i = 1; i < 8; ++i) {
    if (!nodeChildExists(node, i)) return false;
    const TravNode* child = getNodeChild(node, i);
    if (nodeHasChildren(child) || !(*child == *first)) return false;
  }
  return true;
}

}  // namespace ssta::internal
