#include "ssta/pipeline/map_builder.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iomanip>
#include <map>
#include <memory>
#include <optional>
#include <sstream>

#include "core/json_escape.h"
#include "core/ordered_worker.h"
#include "ssta/files/file_util.h"
#include "ssta/fusion/frame_points.h"
#include "ssta/mapping/recording_fingerprint.h"
#include "ssta/sensors/gravity_provider.h"
#include "ssta/mount/ground_evidence.h"

namespace ssta {
namespace {

/// Whether two sequence names (paths as typed) name the same folder: "seq/", "seq" and
/// "./seq" do.
bool SameSequenceName(const std::string& a, const std::string& b) {
  auto normal = [](const std::string& name) {
    std::string s = std::filesystem::path(name).lexically_normal().string();
    while (s.size() > 1 && s.back() == '/') s.pop_back();
    return s;
  };
  return normal(a) == normal(b);
}

std::string CalibrationSummary(const StereoCalibration& c, const RectifiedGeometry& g) {
  std::ostringstream s;
  s << std::setprecision(10) << "cam0 " << c.left.width << "x" << c.left.height << " fu " << c.left.fu
    << " fv " << c.left.fv << " cu " << c.left.cu << " cv " << c.left.cv << "; rectified f " << g.f
    << " baseline " << g.baseline_m << " m; crop " << g.crop_width << "x" << g.crop_height << "+"
    << g.crop_u0 << "+" << g.crop_v0;
  return s.str();
}

/// `*continues_sequence`: the resumed map's last sequence is this one (an interrupted run of it).
TraversabilityMap OpenMap(const BuildMapOptions& options, const Config& config, const std::string& sequence_name,
                          const RectifiedGeometry& geometry, const std::string& calibration,
                          bool* continues_sequence) {
  *continues_sequence = false;
  if (!options.resume) {
    MapMetadata metadata;
    metadata.vehicle = config.vehicle;
    metadata.calibration_summary = calibration;
    metadata.sequences = {sequence_name};
    metadata.world_frame = options.world_frame;
    return TraversabilityMap(config.map.FusionFor(geometry.f * geometry.baseline_m, config.stereo.disparity_sigma_px),
                             metadata);
  }
  TraversabilityMap map = TraversabilityMap::Load(options.map_path);
  const double resolution = map.options().resolution_m;
  if (std::abs(resolution - config.map.fusion.resolution_m) > 1e-9) {
    std::ostringstream m;
    m << options.map_path << ": map resolution " << resolution << " m differs from map.resolution_m "
      << config.map.fusion.resolution_m << " m in the config (a resumed map keeps its resolution)";
    throw Error(m.str());
  }
  // A resumed map's classes are its vehicle's: frames classed for another vehicle would mix two
  // verdicts in one voxel.
  RequireSameVehicle(map.metadata().vehicle, options.map_path + ": the map was built for", config.vehicle,
                     "the config gives", "",
                     "a resumed map keeps its vehicle: its classes are that vehicle's; build a new map for this one");
  // A resumed map's voxels are in its world frame: poses in another would land beside them.
  if (!options.world_frame.empty() && options.world_frame != map.metadata().world_frame) {
    throw Error(options.map_path + ": the map's world frame is '" + map.metadata().world_frame +
                "', but --world-frame gives '" + options.world_frame + "'; a resumed map keeps its frame");
  }
  MapMetadata metadata = map.metadata();
  *continues_sequence = !metadata.sequences.empty() && SameSequenceName(metadata.sequences.back(), sequence_name);
  if (!*continues_sequence) metadata.sequences.push_back(sequence_name);
  map.set_metadata(metadata);
  return map;
}

/// The refined mount a resumed map recorded when it corrected this same configured mount.
std::optional<Eigen::Isometry3d> RecordedMount(const TraversabilityMap& map, const Eigen::Isometry3d& configured) {
  const std::optional<RefinedMount>& recorded = map.metadata().refined_mount;
  if (recorded && recorded->configured.isApprox(configured, 1e-9)) return recorded->refined;
  return std::nullopt;
}

}  // namespace

InsertStats FuseFrame(const FrameResult& frame, const Eigen::Isometry3d& world_T_rectified, const Config& config,
                      const RectifiedGeometry& geometry, std::vector<ClassifiedPoint>* points,
                      TraversabilityMap* map) {
  MapPointsOfFrame(frame, world_T_rectified, config.map, geometry, config.vehicle, points);
  return map->InsertFrame(*points, world_T_rectified.translation(), frame.timestamp_ns);
}

bool BuildMapOptions::IsValid(std::string* error) const {
  if (map_path.empty()) return Fail(error, "map: a map file is required");
  return frames.IsValid(error);
}

namespace {

/// One build-map run: the frames of a sequence classified and fused into a map, in frame order.
/// Everything that touches the map or the summary runs as a job on `fusion_`, so the map and
/// the summary are those of the sequential loop; pipelined, the fusion of frame k overlaps the
/// classification of frame k+1. The refiner and the mount in use stay on the calling thread:
/// each job gets its pose by value.
class MapBuilder {
 public:
  MapBuilder(const Sequence& sequence, const std::string& sequence_name, const Config& config,
             const BuildMapOptions& options, const Progress& progress, const std::atomic<bool>* stop)
      : config_(config),
        options_(options),
        progress_(progress),
        stop_(stop),
        lock_(LockedMapPath(options)),
        run_(RequirePoses(sequence, options), config, options.frames, options.oracles),
        chain_(sequence.calibration().left.body_T_camera, run_.geometry()),
        map_(OpenMap(options, config, sequence_name, run_.geometry(),
                     CalibrationSummary(sequence.calibration(), run_.geometry()),
                     &same_sequence_)),
        fusion_(options.pipelined ? 1 : 0) {
    // Continuing an interrupted run of this sequence: what the map holds is not fused twice.
    continues_this_sequence_ = options.resume && map_.frames_inserted() > 0 && same_sequence_;
    fused_up_to_ = map_.last_timestamp_ns();
    run_.set_read_ahead(options.pipelined);  // the next frame's images decoded while this one is classified
    StartRecording(sequence_name);
    if (options.resume && !options.allow_overlap) RefuseFramesHeld(sequence_name);
    StartRefinement();
    summary_.frames_listed = run_.frames_listed();
    summary_.gravity = run_.gravity().Describe();
    summary_.skipped = run_.sequence_skips();
    summary_.warnings = sequence.warnings();
    RecordWarnings(sequence_name, sequence.warnings());
  }

  BuildMapSummary Run() {
    const auto start = std::chrono::steady_clock::now();
    const int total = static_cast<int>(run_.frames().size());
    int done = 0;
    for (const StereoFrame& frame : run_.frames()) {
      if (stop_ && stop_->load()) {
        summary_.interrupted = true;
        break;
      }
      if (continues_this_sequence_ && frame.timestamp_ns <= fused_up_to_) {
        ++summary_.frames_already_in_map;
      } else {
        ProcessFrame(frame);
      }
      ++done;
      if (config_.map.checkpoint_every_frames > 0 && done % config_.map.checkpoint_every_frames == 0) {
        fusion_.Submit([this] { SaveIfFused(); });
      }
      if (progress_) progress_(done, total);
    }
    FuseHeldFrames();  // a sequence (or run) shorter than the warm-up: fused with the mount in use
    fusion_.Drain();
    Finish(start);
    return summary_;
  }

 private:
  /// The frames of frames past the warm-up are fused as they come; during the warm-up of the
  /// online refinement they are held (see FuseHeldFrames).
  struct HeldFrame {
    StereoFrame frame;
    Eigen::Isometry3d world_T_body;
  };

  /// The map's path once the options are valid: its write lock is the run's first step.
  static const std::string& LockedMapPath(const BuildMapOptions& options) {
    std::string error;
    if (!options.IsValid(&error)) throw Error(error);
    return options.map_path;
  }

  /// The sequence's warnings go into the map's notes (once: a resumed run repeats them).
  void RecordWarnings(const std::string& sequence_name, const std::vector<std::string>& warnings) {
    if (warnings.empty()) return;
    MapMetadata metadata = map_.metadata();
    for (const std::string& w : warnings) {
      const std::string note = sequence_name + ": " + w;
      if (std::find(metadata.notes.begin(), metadata.notes.end(), note) == metadata.notes.end()) {
        metadata.notes.push_back(note);
      }
    }
    map_.set_metadata(metadata);
  }

  static const Sequence& RequirePoses(const Sequence& sequence, const BuildMapOptions& options) {
    std::string error;
    if (!options.IsValid(&error)) throw Error(error);
    if (options.static_platform) return sequence;
    if (sequence.poses().empty()) {
      if (!sequence.pose_path().empty()) {  // the file is there, with a header and no rows
        throw Error(sequence.pose_path() + ": lists no poses; use --static if the platform stands still");
      }
      throw Error(sequence.root() + ": the sequence has no poses (pose0/ or state_groundtruth_estimate0/); "
                  "use --static if the platform stands still");
    }
    sequence.RequireFramesWithin(sequence.poses().front().timestamp_ns, sequence.poses().back().timestamp_ns,
                                 sequence.pose_path(), "poses");
    return sequence;
  }

  /// The fingerprint this run adds to: the map's last recording when this run continues it,
  /// else a new one, entered into the metadata at the first save.
  void StartRecording(const std::string& sequence_name) {
    const std::vector<RecordingFingerprint>& held = map_.metadata().recordings;
    if (continues_this_sequence_ && !held.empty() && SameSequenceName(held.back().sequence, sequence_name)) {
      recording_ = held.back();
      recording_index_ = held.size() - 1;
    } else {
      recording_.sequence = sequence_name;
      recording_index_ = held.size();
    }
  }

  /// Throws before anything is fused when a frame of this run is already in the map: same
  /// timestamp and same left image as a frame of one of its recordings (the recording this
  /// run continues excepted: its frames in the map are skipped by time). Only the frames whose
  /// timestamp the map holds are read.
  void RefuseFramesHeld(const std::string& sequence_name) const {
    const std::vector<RecordingFingerprint>& held = map_.metadata().recordings;
    const std::size_t compared = std::min(recording_index_, held.size());
    std::multimap<std::int64_t, std::pair<std::size_t, std::uint64_t>> by_stamp;
    for (std::size_t i = 0; i < compared; ++i) {
      for (std::size_t k = 0; k < held[i].frames(); ++k) by_stamp.emplace(held[i].stamps_ns[k], std::make_pair(i, held[i].image_hashes[k]));
    }
    if (by_stamp.empty()) return;
    for (const StereoFrame& frame : run_.frames()) {
      const auto range = by_stamp.equal_range(frame.timestamp_ns);
      if (range.first == range.second) continue;
      std::uint64_t hash = 0;
      try {
        hash = SampledImageHash(run_.sequence().ReadImages(frame).left);
      } catch (const Error&) {
        continue;  // an unreadable frame is not fused either
      }
      for (auto it = range.first; it != range.second; ++it) {
        if (it->second.second != hash) continue;
        const RecordingFingerprint& r = held[it->second.first];
        throw Error(options_.map_path + ": already holds the recording '" + r.sequence + "' (" +
                    std::to_string(r.frames()) + " frames, " + r.Digest() + "), and '" + sequence_name +
                    "' shares its frame at " + std::to_string(frame.timestamp_ns) +
                    " ns (same time, same image): fusing it would count that evidence twice; "
                    "--allow-overlap fuses it anyway");
      }
    }
  }

  /// cam0's mount: the configured one, or the online refinement's once a solve is applied. A
  /// resumed map that recorded a refined mount for this same configured one starts from it and
  /// needs no warm-up.
  void StartRefinement() {
    if (!config_.refinement.online) return;
    const Eigen::Isometry3d configured = chain_.body_T_camera();
    const std::optional<Eigen::Isometry3d> recorded = RecordedMount(map_, configured);
    refiner_.emplace(config_.refinement, configured, recorded.value_or(configured));
    chain_.set_body_T_camera(refiner_->body_T_camera());
    warming_up_ = !recorded.has_value();
  }

  /// Poses, classifies and fuses (or holds) one frame; a frame that cannot be used is skipped
  /// with its reason, or stops a strict run.
  void ProcessFrame(const StereoFrame& frame) {
    const std::int64_t t = frame.timestamp_ns;
    try {
      const Eigen::Isometry3d world_T_body = run_.WorldTBody(t, options_.static_platform);
      const Eigen::Vector3d up_body = UpInBody(world_T_body);
      std::uint64_t image_hash = 0;
      auto result = std::make_shared<FrameResult>(run_.Classify(frame, chain_.UpInCamera(up_body), &image_hash));
      if (warming_up_) {
        held_.push_back({frame, world_T_body});
        Refine(*result, up_body);
        if (refiner_->summary().applied > 0 || static_cast<int>(held_.size()) >= config_.refinement.window_frames) {
          FuseHeldFrames();
        }
      } else {
        Fuse(result, world_T_body, image_hash);
        if (refiner_) Refine(*result, up_body);
      }
    } catch (const StrictStop&) {
      throw;
    } catch (const Error& e) {
      Skip(t, e.what());
    }
  }

  /// Queues the fusion of `result` seen from `world_T_body` through the mount in use now;
  /// `image_hash` is its left image's SampledImageHash, for the map's fingerprint.
  void Fuse(std::shared_ptr<const FrameResult> result, const Eigen::Isometry3d& world_T_body, std::uint64_t image_hash) {
    const Eigen::Isometry3d world_T_rectified = chain_.WorldTRectified(world_T_body);
    fusion_.Submit([this, result, world_T_rectified, image_hash] {
      const std::int64_t t = result->timestamp_ns;
      InsertStats stats;
      try {
        stats = FuseFrame(*result, world_T_rectified, config_, run_.geometry(), &map_points_, &map_);
      } catch (const Error& e) {
        RecordSkip(t, e.what());
        return;
      }
      if (!stats.inserted) {
        RecordSkip(t, "map rejected the frame: " + stats.reason);
        return;
      }
      ++summary_.frames_used;
      recording_.Add(t, image_hash);
      summary_.points_inserted += stats.points_hit;
      if (!result->analysis.quality.judged) summary_.quality_failed.push_back({t, result->analysis.quality.reason});
    });
  }

  /// The frame's ground evidence to the refiner; an applied solve serves the frames after it
  /// and is recorded in the map's metadata.
  void Refine(const FrameResult& result, const Eigen::Vector3d& up_body) {
    if (!refiner_->AddFrame(ExtractGroundEvidence(result, chain_.camera_R_rectified(), up_body, config_.refinement))) {
      return;
    }
    const RefinedMount mount{run_.sequence().calibration().left.body_T_camera, refiner_->body_T_camera()};
    chain_.set_body_T_camera(mount.refined);
    fusion_.Submit([this, mount] {
      MapMetadata metadata = map_.metadata();
      metadata.refined_mount = mount;
      map_.set_metadata(metadata);
    });
  }

  /// Ends the warm-up: the frames held until the first solve (at most window_frames) are
  /// processed again with the mount in use and fused, so the map holds no frame seen through
  /// the configured mount when the refinement succeeds.
  void FuseHeldFrames() {
    warming_up_ = false;
    for (const HeldFrame& h : held_) {
      try {
        const Eigen::Vector3d up_body = UpInBody(h.world_T_body);
        std::uint64_t image_hash = 0;
        auto result = std::make_shared<FrameResult>(run_.Classify(h.frame, chain_.UpInCamera(up_body), &image_hash));
        Fuse(result, h.world_T_body, image_hash);
        ++reprocessed_;
      } catch (const StrictStop&) {
        throw;
      } catch (const Error& e) {
        Skip(h.frame.timestamp_ns, e.what());
      }
    }
    held_.clear();
  }

  /// A frame that cannot be used, queued behind the frames before it.
  void Skip(std::int64_t t, const std::string& reason) {
    fusion_.Submit([this, t, reason] { RecordSkip(t, reason); });
  }

  /// On the fusion thread: an error in strict mode (nothing fused so far is lost), else a skip.
  void RecordSkip(std::int64_t t, const std::string& reason) {
    try {
      run_.RequireNotStrict(t, reason);
    } catch (const StrictStop&) {
      SaveIfFused();
      throw;
    }
    summary_.skipped.push_back({t, reason});
  }

  /// The map file is written only once this run has fused a frame: a run that fuses nothing
  /// (every frame skipped, or a strict stop at the first) leaves the file as it was.
  void SaveIfFused() {
    if (summary_.frames_used == 0) return;
    MapMetadata metadata = map_.metadata();
    if (recording_index_ < metadata.recordings.size()) {
      metadata.recordings[recording_index_] = recording_;
    } else {
      recording_index_ = metadata.recordings.size();
      metadata.recordings.push_back(recording_);
    }
    map_.set_metadata(metadata);
    map_.Save(options_.map_path);
  }

  void Finish(std::chrono::steady_clock::time_point start) {
    SaveIfFused();
    summary_.map_nodes = map_.NumNodes();
    std::error_code no_file;
    const std::uintmax_t bytes = std::filesystem::file_size(options_.map_path, no_file);
    summary_.map_file_bytes = no_file ? 0 : static_cast<std::size_t>(bytes);
    summary_.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (refiner_) {
      summary_.refinement = refiner_->summary();
      summary_.refinement->frames_reprocessed = reprocessed_;
    }
  }

  const Config& config_;
  const BuildMapOptions& options_;
  const Progress& progress_;
  const std::atomic<bool>* stop_;
  /// One writer per map for the whole run, before the map is read (docs/robustness.md).
  MapWriteLock lock_;
  SequenceRun run_;
  RigChain chain_;
  bool same_sequence_ = false;
  TraversabilityMap map_;
  bool continues_this_sequence_ = false;
  std::int64_t fused_up_to_ = 0;
  /// The frames this run's recording has in the map (with those of the run it continues),
  /// and its place in the metadata's recordings (their count until the first save).
  RecordingFingerprint recording_;
  std::size_t recording_index_ = 0;
  std::optional<OnlineMountRefiner> refiner_;
  bool warming_up_ = false;
  std::vector<HeldFrame> held_;
  int reprocessed_ = 0;
  BuildMapSummary summary_;
  /// The points of the frame being fused, kept from frame to frame (the jobs run one at a time).
  std::vector<ClassifiedPoint> map_points_;
  /// Declared last: its destructor finishes the queued jobs before the members they use go.
  internal::OrderedWorker fusion_;
};

}  // namespace

BuildMapSummary BuildMap(const Sequence& sequence, const std::string& sequence_name, const Config& config,
                         const BuildMapOptions& options, const Progress& progress, const std::atomic<bool>* stop) {
  std::error_code ec;
  const bool map_existed = std::filesystem::exists(options.map_path, ec);
  BuildMapSummary summary = MapBuilder(sequence, sequence_name, config, options, progress, stop).Run();
  summary.map_existed = map_existed;
  return summary;
}

void RequireFused(const BuildMapSummary& summary, const std::string& sequence, const std::string& map_path) {
  if (summary.Fused()) return;
  throw Error(sequence + ": no frame could be fused; " + map_path +
              (summary.map_existed ? " was left as it was" : " was not written"));
}

std::string SequenceNameOf(const std::string& path) {
  const std::string name = std::filesystem::path(path).lexically_normal().filename().string();
  return name.empty() ? path : name;
}

std::string BuildMapSummary::BriefReport() const {
  std::ostringstream r;
  r << std::fixed << std::setprecision(1);
  r << "frames: " << frames_used << " fused, ";
  if (frames_already_in_map > 0) r << frames_already_in_map << " already in the resumed map, ";
  r << skipped.size() << " skipped, " << quality_failed.size()
    << " without verdicts by the quality check (free space only) (of " << frames_listed << " listed)"
    << (interrupted ? "; interrupted, the map holds what was fused" : "") << "\n";
  for (const auto& w : warnings) r << "warning: " << w << "\n";
  for (const auto& s : skipped) r << "  skipped " << s.timestamp_ns << ": " << s.reason << "\n";
  for (const auto& s : quality_failed) r << "  no verdicts " << s.timestamp_ns << ": " << s.reason << "\n";
  if (!gravity.empty()) r << "gravity: " << gravity << "\n";
  if (!Fused()) {  // BuildMap wrote nothing
    r << "map: nothing fused, the file was not written"
      << (map_file_bytes > 0 ? " (the earlier one, " + std::to_string(map_file_bytes / 1024) + " KiB, is as it was)" : "")
      << "\n";
  } else {
    r << "map: " << map_nodes << " nodes, " << map_file_bytes / 1024.0 << " KiB on disk, " << points_inserted
      << " points fused\n";
  }
  r << "time: " << wall_s << " s (" << (wall_s > 0 ? frames_used / wall_s : 0.0) << " frames/s)\n";
  if (refinement) r << refinement->BriefReport();
  return r.str();
}

std::string BuildMapSummary::Json() const {
  std::ostringstream j;
  auto list = [&](const std::vector<SkippedFrame>& v) {
    j << "[";
    for (std::size_t i = 0; i < v.size(); ++i) {
      j << (i ? ", " : "") << "{\"timestamp_ns\": " << v[i].timestamp_ns << ", \"reason\": \"" << internal::JsonEscape(v[i].reason) << "\"}";
    }
    j << "]";
  };
  j << "{\n  \"frames_listed\": " << frames_listed << ",\n  \"frames_used\": " << frames_used
    << ",\n  \"frames_already_in_map\": " << frames_already_in_map << ",\n  \"skipped\": ";
  list(skipped);
  j << ",\n  \"quality_failed\": ";
  list(quality_failed);
  j << ",\n  \"warnings\": [";
  for (std::size_t i = 0; i < warnings.size(); ++i) j << (i ? ", " : "") << "\"" << internal::JsonEscape(warnings[i]) << "\"";
  j << "]";
  j << ",\n  \"map_nodes\": " << map_nodes << ",\n  \"map_file_bytes\": " << map_file_bytes
    << ",\n  \"points_inserted\": " << points_inserted << ",\n  \"wall_s\": " << wall_s
    << ",\n  \"interrupted\": " << (interrupted ? "true" : "false") << ",\n  \"gravity\": \""
    << internal::JsonEscape(gravity) << "\"";
  if (refinement) j << ",\n  \"refinement\": " << refinement->Json();
  j << "\n}\n";
  return j.str();
}

}  // namespace ssta
