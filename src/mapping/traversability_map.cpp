// TraversabilityMap itself: construction, moves and accessors. The fusion of a frame is in
// frame_fusion.cpp, the queries in map_queries.cpp, what a voxel says in cell_description.cpp,
// Save and Load in map_file.cpp.

#include "ssta/mapping/traversability_map.h"

#include <memory>
#include <string>
#include <utility>

#include "mapping/map_impl.h"
#include "ssta/core/error.h"

#ifndef SSTA_VERSION
#define SSTA_VERSION "unknown"
#endif

namespace ssta {

namespace internal {

std::unique_ptr<TravOcTree> MakeTree(const MapOptions& options) {
  auto tree = std::make_unique<TravOcTree>(options.resolution_m);
  tree->setProbHit(options.occupancy_hit_prob);
  tree->setProbMiss(options.occupancy_miss_prob);
  tree->setClampingThresMin(options.occupancy_clamp_min_prob);
  tree->setClampingThresMax(options.occupancy_clamp_max_prob);
  tree->setOccupancyThres(options.occupied_threshold_prob);
  return tree;
}

}  // namespace internal

TraversabilityMap::TraversabilityMap(const MapOptions& options, MapMetadata metadata)
    : impl_(std::make_unique<Impl>()) {
  std::string error;
  if (!options.IsValid(&error)) throw Error("map options: " + error);
  if (!metadata.vehicle.IsValid(&error)) throw Error("map vehicle: " + error);
  impl_->options = options;
  impl_->metadata = std::move(metadata);
  impl_->tree = internal::MakeTree(options);
  impl_->software_version = SSTA_VERSION;
}

TraversabilityMap::TraversabilityMap(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
TraversabilityMap::~TraversabilityMap() = default;
TraversabilityMap::TraversabilityMap(TraversabilityMap&&) noexcept = default;
TraversabilityMap& TraversabilityMap::operator=(TraversabilityMap&&) noexcept = default;

const MapOptions& TraversabilityMap::options() const { return impl_->options; }
const MapMetadata& TraversabilityMap::metadata() const { return impl_->metadata; }

void TraversabilityMap::set_metadata(MapMetadata metadata) {
  std::string error;
  if (!metadata.vehicle.IsValid(&error)) throw Error("map vehicle: " + error);
  impl_->metadata = std::move(metadata);
}

std::uint64_t TraversabilityMap::frames_inserted() const { return impl_->frames_inserted; }
const std::vector<Eigen::Vector3d>& TraversabilityMap::sensor_path() const { return impl_->sensor_path.points(); }
std::int64_t TraversabilityMap::last_timestamp_ns() const { return impl_->last_timestamp_ns; }
const std::string& TraversabilityMap::software_version() const { return impl_->software_version; }
std::size_t TraversabilityMap::NumNodes() const { return impl_->tree->size(); }

}  // namespace ssta
