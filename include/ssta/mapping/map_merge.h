#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "ssta/mapping/traversability_map.h"

namespace ssta {

/// How maps are merged.
struct MergeOptions {
  /// Merge maps that share frames of a recording (same timestamp, same image: the overlap
  /// rule of FramesShared), whose evidence then counts twice. Off: refused, naming both.
  bool allow_overlap = false;
};

/// Throws ssta::Error when the maps `a` (read from `a_file`) and `b` (from `b_file`) do not lie
/// on one grid of one world: another resolution, or another world frame name
/// (MapMetadata::world_frame; maps built without one are all "unnamed"). The message names `b_file`
/// and its value, then `a_file` and its, then `advice`. Merging (CheckMergeable) and comparing
/// (DiffMaps) maps both require it.
void RequireSameWorldGrid(const TraversabilityMap& a, const std::string& a_file, const TraversabilityMap& b,
                          const std::string& b_file, const std::string& advice);

/// Throws ssta::Error when the map `from` (read from the file `from_file`) cannot be merged
/// into `into` (from `into_file`), naming both files and the difference: another resolution or
/// world frame name (RequireSameWorldGrid), another vehicle (its classes are that vehicle's), or another
/// evidence scale (the occupancy and class log-odds clamps and the occupied threshold, which
/// give the sums their meaning). The other fusion options (range, hit and miss
/// probabilities, free-space rules) shaped how each map gathered its evidence and may differ;
/// the merged map keeps `into`'s.
void CheckMergeable(const TraversabilityMap& into, const std::string& into_file,
                    const TraversabilityMap& from, const std::string& from_file);

/// Adds the evidence of `from` to `into`, voxel by voxel (docs/fleet.md):
///  - occupancy and the three class log-odds add, clamped to the map's clamps;
///  - observations add; mean slope and step are the observation-weighted means; max step,
///    last seen and (over voxels with a fused height) the horizontal sigma take the max, max
///    and min;
///  - the fused surface height is the inverse-variance weighted mean, its weights add.
///  - with the merged map's free_space_keeps_traversable, one map's rays do not erode ground
///    the other map held as traversable before the first map's last frame (as one run in time
///    order spares it): that map adds only its hits to the occupancy (observations times the
///    hit log-odds, or its net log-odds when larger).
/// A voxel only one map holds keeps its values. Merging is commutative exactly. Grouping
/// (which maps are merged first) can change a voxel in two ways: where a sum reaches a clamp,
/// and through the ground-sparing rule above, which compares each map's last frame with the
/// time the other map last saw the voxel, so where recordings overlap in time a merged map's
/// last frame can spare ground that one of its parts alone would not have. Without the clamps
/// and with free_space_keeps_traversable off, the result is the same in any order up to float
/// rounding (docs/fleet.md measures by how much the order changes a map).
/// The metadata: `into` gains `from`'s sequences, its sources (`from` itself when it was not
/// merged, described as `from_file`), sensor path and frame count; last timestamp is the later.
/// Throws as CheckMergeable; when `from` is `into`; and when a source of `from` (by its file
/// checksum) is already in `into` (its `merged_from`, or `into` itself when it was read from a
/// file and is not a merge): its evidence would count twice; and, unless
/// `options.allow_overlap`, when a recording of `from` shares a frame with one of `into`
/// (MapMetadata::recordings; recordings without a fingerprint are not compared). The merged
/// map lists the recordings of both. Not thread safe on `into`; `from` is only read.
void MergeMapInto(const TraversabilityMap& from, const std::string& from_file, TraversabilityMap* into,
                  const MergeOptions& options = {});

/// What MergeMaps did.
struct MergeSummary {
  std::size_t inputs = 0;        ///< map files merged
  std::size_t nodes = 0;         ///< octree nodes of the merged map
  std::size_t largest_input_nodes = 0;  ///< nodes of the largest input (memory: see MergeMaps)
  double wall_s = 0.0;           ///< time to read and merge [s]
  std::string BriefReport() const;
};

/// Merges the map files `map_files` (at least one) into a new map: the first file's options
/// and vehicle, every file's evidence added as MergeMapInto adds it, in the order given (the
/// same tree, bit for bit). Each file is checked as Load checks it (end marker, checksum,
/// header, every node) and read node by node into the merged map, without a tree of its own:
/// memory holds the merged map and fixed buffers, whatever the inputs' sizes. Throws
/// ssta::Error naming the file that cannot be read or merged (CheckMergeable: against the
/// first file), and naming both files when two inputs hold the same source map (its checksum
/// in both: a copy, or a merged map and one of its sources) or, unless
/// `options.allow_overlap`, a recording that shares a frame with one of another input (naming
/// both files, both recordings and the shared frames); the partial result is dropped.
TraversabilityMap MergeMaps(const std::vector<std::string>& map_files, MergeSummary* summary = nullptr,
                            const MergeOptions& options = {});

}  // namespace ssta
