// Merging maps: the evidence of several recordings of one site added into one map
// (docs/fleet.md). The tree walk is TravOcTree::MergeFrom; this file holds the per-voxel rule,
// the checks and the metadata.

#include "ssta/mapping/map_merge.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <functional>
#include <optional>
#include <sstream>

#include "mapping/map_file_reader.h"
#include "mapping/map_impl.h"
#include "ssta/core/error.h"

namespace ssta {
namespace {

float ClampedSum(float a, float b, double lo, double hi) {
  return static_cast<float>(std::min(hi, std::max(lo, static_cast<double>(a) + b)));
}

/// Mean of `a` over `wa` samples and `b` over `wb`, in double: the same bits for (a, b) and
/// (b, a). Precondition: wa + wb > 0.
float WeightedMean(float a, double wa, float b, double wb) {
  return static_cast<float>((wa * a + wb * b) / (wa + wb));
}

/// The per-voxel rule of MergeMapInto (map_merge.h). Every step is symmetric in its two
/// operands, so merge(A, B) and merge(B, A) hold the same bits.
struct CombineEvidence {
  double occupancy_min, occupancy_max, class_min, class_max;
  double occupancy_hit;  ///< log-odds a hit adds (MapOptions::occupancy_hit_prob)
  bool keeps_traversable;  ///< MapOptions::free_space_keeps_traversable of the merged map
  /// The last frame of each map [ns] (TraversabilityMap::last_timestamp_ns).
  std::int64_t into_last_ns, from_last_ns;

  /// One run over the recordings in time order spares ground held as traversable from the
  /// rays of later frames (free_space_keeps_traversable), but not from the rays of earlier
  /// ones: those passed before the ground was seen, and the hits had to outweigh them. So a
  /// map's misses are left out where the other map held the voxel as traversable ground
  /// before the passing map's last frame.
  bool Spared(const internal::TravNode& ground, std::int64_t passing_last_ns) const {
    return keeps_traversable && internal::HeldAsTraversable(ground) && ground.last_seen_ns < passing_last_ns;
  }
  /// What `passed` adds to the occupancy of ground the other map held: its hits without its
  /// misses. A map keeps only the net log-odds, so its hits are estimated from its
  /// observations (each a hit of occupancy_hit_prob; hits without a class verdict are not
  /// counted, so the net sum is the floor).
  float HitsOnly(const internal::TravNode& passed) const {
    const double hits = std::min(occupancy_max, passed.observations * occupancy_hit);
    return std::max(passed.getLogOdds(), static_cast<float>(hits));
  }

  void operator()(internal::TravNode& into, const internal::TravNode& from) const {
    float into_occupancy = into.getLogOdds(), from_occupancy = from.getLogOdds();
    if (Spared(into, from_last_ns)) from_occupancy = HitsOnly(from);
    if (Spared(from, into_last_ns)) into_occupancy = HitsOnly(into);
    into.setLogOdds(ClampedSum(into_occupancy, from_occupancy, occupancy_min, occupancy_max));
    for (int k = 0; k < 3; ++k) {
      into.class_log_odds[k] = ClampedSum(into.class_log_odds[k], from.class_log_odds[k], class_min, class_max);
    }
    const double n_into = into.observations, n_from = from.observations;
    if (n_into + n_from > 0.0) {
      into.slope_deg = WeightedMean(into.slope_deg, n_into, from.slope_deg, n_from);
      into.step_m = WeightedMean(into.step_m, n_into, from.step_m, n_from);
    }
    const std::uint64_t observations = std::uint64_t{into.observations} + from.observations;
    into.observations = static_cast<std::uint32_t>(std::min<std::uint64_t>(observations, UINT32_MAX));
    into.max_step_m = std::max(into.max_step_m, from.max_step_m);
    into.last_seen_ns = std::max(into.last_seen_ns, from.last_seen_ns);
    if (from.surface_weight > 0.0f) {
      if (into.surface_weight > 0.0f) {
        into.surface_z = WeightedMean(into.surface_z, into.surface_weight, from.surface_z, from.surface_weight);
        into.surface_xy_sigma_m = std::min(into.surface_xy_sigma_m, from.surface_xy_sigma_m);
      } else {
        into.surface_z = from.surface_z;
        into.surface_xy_sigma_m = from.surface_xy_sigma_m;
      }
      into.surface_weight = static_cast<float>(static_cast<double>(into.surface_weight) + from.surface_weight);
    }
  }
};

std::string Number(double v) { return ShortestDecimal(v); }

/// `from`'s sources as the merged map lists them: its own when it is a merge, else itself.
std::vector<MapSource> SourcesOf(const TraversabilityMap& map, const std::string& file) {
  if (!map.metadata().merged_from.empty()) return map.metadata().merged_from;
  MapSource source;
  source.file = file;
  source.checksum = internal::TraversabilityMapAccess::Impl(map).file_checksum;
  source.sequences = map.metadata().sequences;
  source.frames_inserted = map.frames_inserted();
  source.software_version = map.software_version();
  return {source};
}

/// What a source holds, for a message: its recordings, or its file when it names none.
std::string Holdings(const MapSource& source) {
  if (source.sequences.empty()) return "the map " + source.file;
  std::string names;
  for (const std::string& sequence : source.sequences) names += (names.empty() ? "'" : ", '") + sequence + "'";
  return (source.sequences.size() == 1 ? "the recording " : "the recordings ") + names;
}

/// Throws when a source of `from` (read from `from_file`) is one of `have`, the sources merged
/// so far, by its checksum (a copy of a file is the same evidence under another name; a merged
/// map holds its sources' evidence): its evidence would count twice. `input_of(i)` names the
/// input that brought `have[i]`. A source without a checksum (never saved) is not compared.
void RefuseEvidenceMergedBefore(const std::vector<MapSource>& have,
                                const std::function<std::string(std::size_t)>& input_of,
                                const TraversabilityMap& from, const std::string& from_file) {
  for (const MapSource& adding : SourcesOf(from, from_file)) {
    if (adding.checksum.empty()) continue;
    for (std::size_t i = 0; i < have.size(); ++i) {
      if (have[i].checksum != adding.checksum) continue;
      throw Error(input_of(i) + " and " + from_file + " both hold " + Holdings(have[i]) + " (checksum " +
                  adding.checksum + "): merging them would count its evidence twice");
    }
  }
}

/// Throws when a recording of `from` (read from `from_file`) shares a frame with one of
/// `have`, the recordings merged so far: the same frames would count twice. `input_of(i)`
/// names the input that brought `have[i]`.
void RefuseRecordingsMergedBefore(const std::vector<RecordingFingerprint>& have,
                                  const std::function<std::string(std::size_t)>& input_of,
                                  const TraversabilityMap& from, const std::string& from_file) {
  for (const RecordingFingerprint& adding : from.metadata().recordings) {
    for (std::size_t i = 0; i < have.size(); ++i) {
      const SharedFrames shared = FramesShared(have[i], adding);
      if (shared.count == 0) continue;
      throw Error(input_of(i) + " and " + from_file + " hold frames of one recording: '" + have[i].sequence + "' (" +
                  std::to_string(have[i].frames()) + " frames) and '" + adding.sequence + "' (" +
                  std::to_string(adding.frames()) + " frames) share " + std::to_string(shared.count) +
                  " (same time, same image; the first at " + std::to_string(shared.first_stamp_ns) +
                  " ns): merging them would count that evidence twice; --allow-overlap merges them anyway");
    }
  }
}

}  // namespace

void RequireSameWorldGrid(const TraversabilityMap& a, const std::string& a_file, const TraversabilityMap& b,
                          const std::string& b_file, const std::string& advice) {
  const double res_a = a.options().resolution_m, res_b = b.options().resolution_m;
  if (std::abs(res_a - res_b) > 1e-9 * res_a) {
    throw Error(b_file + ": resolution " + Number(res_b) + " m, but " + a_file + " has " + Number(res_a) + " m; " +
                advice);
  }
  if (a.metadata().world_frame != b.metadata().world_frame) {
    const auto name = [](const std::string& frame) { return frame.empty() ? std::string("(unnamed)") : "'" + frame + "'"; };
    throw Error(b_file + ": world frame " + name(b.metadata().world_frame) + ", but " + a_file + " has " +
                name(a.metadata().world_frame) + "; " + advice);
  }
}

void CheckMergeable(const TraversabilityMap& into, const std::string& into_file, const TraversabilityMap& from,
                    const std::string& from_file) {
  const MapOptions& a = into.options();
  const MapOptions& b = from.options();
  const std::string advice = "maps merge only when they share resolution, vehicle, world frame and evidence scale";
  RequireSameWorldGrid(into, into_file, from, from_file, advice);
  RequireSameVehicle(into.metadata().vehicle, into_file + ": built for", from.metadata().vehicle,
                     from_file + ": built for", "", advice);
  const struct {
    const char* key;
    double MapOptions::*field;
  } scale[] = {{"occupancy_clamp_min_prob", &MapOptions::occupancy_clamp_min_prob},
               {"occupancy_clamp_max_prob", &MapOptions::occupancy_clamp_max_prob},
               {"occupied_threshold_prob", &MapOptions::occupied_threshold_prob},
               {"class_clamp_min", &MapOptions::class_clamp_min},
               {"class_clamp_max", &MapOptions::class_clamp_max}};
  for (const auto& s : scale) {
    if (a.*s.field != b.*s.field) {
      throw Error(from_file + ": map_options." + s.key + " " + Number(b.*s.field) + ", but " + into_file + " has " +
                  Number(a.*s.field) + "; " + advice);
    }
  }
}

namespace {

using internal::MapImpl;

/// The rule for merging a map whose last frame is at `from_last_ns` into `out`.
CombineEvidence CombineInto(const MapImpl& out, std::int64_t from_last_ns) {
  return {out.tree->getClampingThresMinLog(), out.tree->getClampingThresMaxLog(), out.options.class_clamp_min,
          out.options.class_clamp_max, out.tree->getProbHitLog(), out.options.free_space_keeps_traversable,
          out.last_timestamp_ns, from_last_ns};
}

/// Everything but the voxels of `from` (read from `from_file`) into `out`.
void MergeMetadata(const TraversabilityMap& from, const std::string& from_file, MapImpl* out) {
  const auto& in = internal::TraversabilityMapAccess::Impl(from);
  MapMetadata& meta = out->metadata;
  meta.sequences.insert(meta.sequences.end(), in.metadata.sequences.begin(), in.metadata.sequences.end());
  meta.recordings.insert(meta.recordings.end(), in.metadata.recordings.begin(), in.metadata.recordings.end());
  meta.notes.insert(meta.notes.end(), in.metadata.notes.begin(), in.metadata.notes.end());
  for (MapSource& source : SourcesOf(from, from_file)) meta.merged_from.push_back(std::move(source));
  if (meta.calibration_summary.empty()) meta.calibration_summary = in.metadata.calibration_summary;
  for (const Eigen::Vector3d& p : in.sensor_path.points()) out->sensor_path.Append(p);
  out->frames_inserted += in.frames_inserted;
  out->last_timestamp_ns = std::max(out->last_timestamp_ns, in.last_timestamp_ns);
}

}  // namespace

void MergeMapInto(const TraversabilityMap& from, const std::string& from_file, TraversabilityMap* into,
                  const MergeOptions& options) {
  if (into == &from) throw Error(from_file + ": a map merged into itself would count its evidence twice");
  CheckMergeable(*into, "the merged map", from, from_file);
  // A map that is not a merge holds its own evidence (when it was read from a file).
  const std::vector<MapSource> have = into->metadata().merged_from.empty() ? SourcesOf(*into, "the merged map")
                                                                           : into->metadata().merged_from;
  RefuseEvidenceMergedBefore(have, [](std::size_t) { return std::string("the merged map"); }, from, from_file);
  if (!options.allow_overlap) {
    RefuseRecordingsMergedBefore(into->metadata().recordings, [](std::size_t) { return std::string("the merged map"); },
                                 from, from_file);
  }
  auto& out = internal::TraversabilityMapAccess::Impl(*into);
  const auto& in = internal::TraversabilityMapAccess::Impl(from);
  out.tree->MergeFrom(*in.tree, CombineInto(out, in.last_timestamp_ns));
  MergeMetadata(from, from_file, &out);
}

TraversabilityMap MergeMaps(const std::vector<std::string>& map_files, MergeSummary* summary,
                            const MergeOptions& options) {
  if (map_files.empty()) throw Error("merge: no map to merge");
  const auto start = std::chrono::steady_clock::now();
  MergeSummary s;
  // The first input is read and checked like the others; the merged map starts empty with its
  // options, vehicle and frame, so every input enters through the same rule.
  std::optional<TraversabilityMap> merged;
  std::string first_file;
  std::vector<std::string> input_of_source;     // the file that brought each of merged_from
  std::vector<std::string> input_of_recording;  // ... and each of recordings
  for (const std::string& file : map_files) {
    // Read node by node into the merged map: memory holds the merged map, not also this one.
    internal::MapFileReader reader(file);
    const TraversabilityMap& map = reader.shell();
    if (!merged) {
      MapMetadata metadata;
      metadata.vehicle = map.metadata().vehicle;
      metadata.world_frame = map.metadata().world_frame;
      metadata.calibration_summary = map.metadata().calibration_summary;
      merged.emplace(map.options(), metadata);
      first_file = file;
    } else {
      CheckMergeable(*merged, first_file, map, file);
    }
    auto& out = internal::TraversabilityMapAccess::Impl(*merged);
    RefuseEvidenceMergedBefore(out.metadata.merged_from, [&](std::size_t i) { return input_of_source[i]; }, map, file);
    if (!options.allow_overlap) {
      RefuseRecordingsMergedBefore(out.metadata.recordings, [&](std::size_t i) { return input_of_recording[i]; }, map,
                                   file);
    }
    if (reader.nodes() > 0) {
      out.tree->MergeFromNodes([&](internal::TravNode* node, unsigned depth) { return reader.ReadNode(node, depth); },
                               CombineInto(out, map.last_timestamp_ns()));
    }
    reader.Finish();
    MergeMetadata(map, file, &out);
    input_of_source.resize(out.metadata.merged_from.size(), file);
    input_of_recording.resize(out.metadata.recordings.size(), file);
    s.largest_input_nodes = std::max<std::size_t>(s.largest_input_nodes, reader.nodes());
    ++s.inputs;
  }
  s.nodes = merged->NumNodes();
  s.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (summary != nullptr) *summary = s;
  return std::move(*merged);
}

std::string MergeSummary::BriefReport() const {
  std::ostringstream r;
  r << "merged " << inputs << " map" << (inputs == 1 ? "" : "s") << " into " << nodes << " nodes (largest input "
    << largest_input_nodes << ") in " << wall_s << " s\n";
  return r.str();
}

}  // namespace ssta
