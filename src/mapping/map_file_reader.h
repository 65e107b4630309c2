#pragma once

// Private: a map file read node by node instead of whole (map_file.cpp), for MergeMaps, whose
// memory must be the merged map's and not also each input's.

#include <cstdint>
#include <fstream>
#include <memory>
#include <streambuf>
#include <string>

#include "mapping/map_impl.h"

namespace ssta::internal {

/// Opens a map file as TraversabilityMap::Load checks it (the end marker's byte count and hash
/// over the whole file, the header, the metadata), in two passes over the file with a fixed
/// buffer, then hands out its nodes one at a time in the file's order (depth first, each
/// node's payload and child mask). Throws ssta::Error naming the file, as Load does.
class MapFileReader {
 public:
  explicit MapFileReader(const std::string& path);
  ~MapFileReader();
  MapFileReader(const MapFileReader&) = delete;
  MapFileReader& operator=(const MapFileReader&) = delete;

  /// The file's map without its voxels: options, metadata, counters, checksum; an empty tree.
  const TraversabilityMap& shell() const { return shell_; }
  /// Octree nodes the file holds (its header's `size`).
  std::uint64_t nodes() const { return nodes_; }

  /// Reads the next node's payload into `node` (its occupancy and payload; not its children)
  /// and returns its child mask. `depth`: the node's depth (0: root). Throws ssta::Error naming
  /// the file when the stream ends, a value is NaN or infinite, a node below the tree's depth
  /// has children, or more nodes than the header says are read.
  unsigned char ReadNode(TravNode* node, unsigned depth);
  /// After the last node: throws unless the stream ended exactly where the file's nodes end
  /// and held the header's number of nodes.
  void Finish();

 private:
  class LimitedFileBuf;
  std::string path_;
  TraversabilityMap shell_;
  std::uint64_t nodes_ = 0;
  std::uint64_t nodes_read_ = 0;
  unsigned max_depth_ = 0;
  int format_ = 0;
  std::ifstream file_;
  std::unique_ptr<LimitedFileBuf> buffer_;
  std::unique_ptr<std::istream> stream_;
};

}  // namespace ssta::internal
