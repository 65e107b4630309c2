#include "ssta/pipeline/map_builder.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iomanip>
#include <memory>
#include <optional>
#include <sstream>

#include "core/json_escape.h"
#include "core/run_both.h"
#include "core/ordered_worker.h"
#include "ssta/io/image_io.h"
#include "ssta/mapping/frame_points.h"
#include "ssta/sensors/gravity_provider.h"
#include "ssta/pipeline/sequence_classifier.h"
#include "ssta/refinement/ground_evidence.h"
#include "ssta/stereo/stereo_matcher.h"

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
                          const std::string& calibration, bool* continues_sequence) {
  *continues_sequence = false;
  if (!options.resume) {
    MapMetadata metadata;
    metadata.vehicle = config.vehicle;
    metadata.calibration_summary = calibration;
    metadata.sequences = {sequence_name};
    return TraversabilityMap(config.map.fusion, metadata);
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

bool BuildMapOptions::IsValid(std::string* error) const {
  if (map_path.empty()) return Fail(error, "map: a map file is required");
  if (max_frames < 0) return Fail(error, "max-frames: must not be negative");
  if (every < 1) return Fail(error, "every: must be at least 1");
  return true;
}

BuildMapSummary BuildMap(const Sequence& sequence, const std::string& sequence_name, const Config& config,
                         const BuildMapOptions& options, const BuildProgress& progress,
                         const std::atomic<bool>* stop) {
  std::string error;
  if (!options.IsValid(&error)) throw Error(error);
  if (!config.IsValid(&error)) throw Error("config: " + error);
  if (!options.static_platform && sequence.poses().empty()) {
    if (!sequence.pose_path().empty()) {  // the file is there, with a header and no rows
      throw Error(sequence.pose_path() + ": lists no poses; use --static if the platform stands still");
    }
    throw Error(sequence.root() + ": the sequence has no poses (pose0/ or state_groundtruth_estimate0/); "
                "use --static if the platform stands still");
  }
  if (!options.static_platform) {
    sequence.RequireFramesWithin(sequence.poses().front().timestamp_ns, sequence.poses().back().timestamp_ns,
                                 sequence.pose_path(), "poses");
  }
  FramePipeline pipeline(sequence.calibration(), config);
  const GravityProvider gravity(sequence, config.gravity, config.attitude);
  bool same_sequence = false;
  TraversabilityMap map = OpenMap(options, config, sequence_name,
                                  CalibrationSummary(sequence.calibration(), pipeline.geometry()), &same_sequence);
  // Continuing an interrupted run of this sequence: what the map holds is not fused twice.
  const bool continues_this_sequence = options.resume && map.frames_inserted() > 0 && same_sequence;
  const std::int64_t fused_up_to = map.last_timestamp_ns();

  // cam0's mount: the configured one, or the online refinement's once a solve is applied.
  const Eigen::Isometry3d body_T_camera_configured = sequence.calibration().left.body_T_camera;
  const Eigen::Matrix3d camera_R_rectified = pipeline.geometry().rectified_R_camera.transpose();
  std::optional<OnlineMountRefiner> refiner;
  bool resumed_mount = false;  // starts from the mount a resumed map recorded
  if (config.refinement.online) {
    const std::optional<Eigen::Isometry3d> recorded = RecordedMount(map, body_T_camera_configured);
    resumed_mount = recorded.has_value();
    refiner.emplace(config.refinement, body_T_camera_configured, recorded.value_or(body_T_camera_configured));
  }
  Eigen::Isometry3d body_T_camera = refiner ? refiner->body_T_camera() : body_T_camera_configured;
  // world_T_rectified = world_T_body * body_T_cam0 * cam0_T_rectified.
  auto rectified_in_body = [&] {
    Eigen::Isometry3d body_T_rectified = body_T_camera;
    body_T_rectified.linear() = body_T_camera.linear() * camera_R_rectified;
    return body_T_rectified;
  };
  Eigen::Isometry3d body_T_rectified = rectified_in_body();

  const std::vector<StereoFrame> todo = SelectFrames(sequence.frames(), options.every, options.max_frames);
  BuildMapSummary summary;
  summary.frames_listed = static_cast<int>(sequence.frames().size() + sequence.skipped().size());
  summary.gravity = gravity.Describe();
  summary.skipped = sequence.skipped();
  // Strict mode stops at the first unusable frame, once: the per-frame handlers below turn
  // errors into skips, so they let this one through (it is still an ssta::Error for the CLI).
  struct StrictStop : Error {
    using Error::Error;
  };
  // The map file is written only once this run has fused a frame: a run that fuses nothing
  // (every frame skipped, or a strict stop at the first) leaves the file as it was.
  auto save_if_fused = [&] {
    if (summary.frames_used > 0) map.Save(options.map_path);
  };
  auto fail_if_strict = [&](std::int64_t t, const std::string& reason) {
    if (!options.strict) return;
    save_if_fused();  // nothing fused so far is lost
    throw StrictStop(sequence.root() + ": frame " + std::to_string(t) + ": " + reason +
                     " (strict: no frame may be skipped)");
  };
  if (!summary.skipped.empty()) fail_if_strict(summary.skipped.front().timestamp_ns, summary.skipped.front().reason);
  // Everything that touches the map or the summary runs as a job on `fusion`, in frame order,
  // so the map and the summary are those of the sequential loop; with options.pipelined the
  // fusion of frame k overlaps the classification of frame k+1. The refiner and the mount in
  // use stay on this thread: each job gets its pose by value. Declared after them: its
  // destructor finishes the queued jobs before they go.
  internal::OrderedWorker fusion(options.pipelined ? 1 : 0);
  // The points of the frame being fused, kept from frame to frame (~5 MB at VGA; the fusion
  // jobs run one at a time).
  std::vector<ClassifiedPoint> map_points;
  // A frame that cannot be used: an error in strict mode, else a skip with its reason. On the
  // fusion thread (it touches the summary); `skip` queues it from this one.
  auto record_skip = [&](std::int64_t t, const std::string& reason) {
    fail_if_strict(t, reason);
    summary.skipped.push_back({t, reason});
  };
  auto skip = [&](std::int64_t t, const std::string& reason) {
    fusion.Submit([&, t, reason] { record_skip(t, reason); });
  };
  // One frame through the pipeline with the mount in use (gravity in the camera).
  auto process = [&](const StereoFrame& frame, const Eigen::Vector3d& up_body) {
    const StereoImages images = ReadStereoImages(frame, sequence.calibration());
    const Eigen::Vector3d up_camera = (body_T_camera.linear().transpose() * up_body).normalized();
    auto result = std::make_shared<FrameResult>(
        options.oracle_disparity ? pipeline.ProcessWithDisparity(images.left, images.right,
                                                                 ReadTrueDisparity(sequence, frame.timestamp_ns), up_camera)
                                 : pipeline.Process(images.left, images.right, up_camera));
    result->timestamp_ns = frame.timestamp_ns;
    if (options.oracle_labels) {
      ApplyTrueLabels(sequence, frame.timestamp_ns, pipeline.geometry(), &result->analysis.labels);
    }
    return result;
  };
  auto fuse = [&](std::shared_ptr<const FrameResult> result, const Eigen::Isometry3d& world_T_body) {
    const Eigen::Isometry3d world_T_rectified = world_T_body * body_T_rectified;
    fusion.Submit([&, result, world_T_rectified] {
      const std::int64_t t = result->timestamp_ns;
      InsertStats stats;
      try {
        MapPointsOfFrame(*result, world_T_rectified, config.map, pipeline.geometry(), &map_points);
        stats = map.InsertFrame(map_points, world_T_rectified.translation(), t);
      } catch (const Error& e) {
        record_skip(t, e.what());
        return;
      }
      if (!stats.inserted) {
        record_skip(t, "map rejected the frame: " + stats.reason);
        return;
      }
      ++summary.frames_used;
      summary.points_inserted += stats.points_hit;
      if (!result->analysis.quality.passed) summary.quality_failed.push_back({t, result->analysis.quality.reason});
    });
  };
  // The frame's ground evidence to the refiner; an applied solve serves the frames after it.
  auto refine = [&](const FrameResult& result, const Eigen::Vector3d& up_body) {
    if (!refiner->AddFrame(ExtractGroundEvidence(result, camera_R_rectified, up_body, config.refinement))) return;
    body_T_camera = refiner->body_T_camera();
    body_T_rectified = rectified_in_body();
    const RefinedMount mount{body_T_camera_configured, body_T_camera};
    fusion.Submit([&, mount] {
      MapMetadata metadata = map.metadata();
      metadata.refined_mount = mount;
      map.set_metadata(metadata);
    });
  };
  // Warm-up: until the first solve is applied (at most window_frames frames), frames give
  // evidence but are not fused; then they are processed again with the refined mount and fused,
  // so the map holds no frame seen through the configured mount when refinement succeeds. A
  // start mount recorded by a resumed map needs no warm-up.
  struct HeldFrame {
    StereoFrame frame;
    Eigen::Isometry3d world_T_body;
  };
  std::vector<HeldFrame> held;
  bool warming_up = refiner && !resumed_mount;
  int reprocessed = 0;
  auto fuse_held = [&] {
    warming_up = false;
    for (const HeldFrame& h : held) {
      try {
        fuse(process(h.frame, h.world_T_body.linear().transpose() * Eigen::Vector3d::UnitZ()), h.world_T_body);
        ++reprocessed;
      } catch (const StrictStop&) {
        throw;
      } catch (const Error& e) {
        skip(h.frame.timestamp_ns, e.what());
      }
    }
    held.clear();
  };
  const auto start = std::chrono::steady_clock::now();
  int done = 0, already_in_map = 0;
  for (const StereoFrame& frame : todo) {
    if (stop && stop->load()) {
      summary.interrupted = true;
      break;
    }
    const std::int64_t t = frame.timestamp_ns;
    if (continues_this_sequence && t <= fused_up_to) {
      ++already_in_map;
      ++done;
      if (progress) progress(done, static_cast<int>(todo.size()));
      continue;
    }
    std::optional<Eigen::Isometry3d> world_T_body;
    std::string no_attitude;  // a frame the IMU in use does not cover: skipped
    try {
      if (options.static_platform) {
        world_T_body = CorrectRollPitch(Eigen::Isometry3d::Identity(), gravity.UpInBody(t));
      } else {
        world_T_body = gravity.WorldTBodyAt(t);
      }
    } catch (const Error& e) {
      no_attitude = e.what();
    }
    if (!no_attitude.empty()) {
      skip(t, no_attitude);
    } else if (!world_T_body) {
      skip(t, "no pose: " + sequence.NoPoseReason(t));
    } else {
      try {
        const Eigen::Vector3d up_body = (world_T_body->linear().transpose() * Eigen::Vector3d::UnitZ()).normalized();
        const std::shared_ptr<FrameResult> result = process(frame, up_body);
        if (warming_up) {
          held.push_back({frame, *world_T_body});
          refine(*result, up_body);
          if (refiner->summary().applied > 0 || static_cast<int>(held.size()) >= config.refinement.window_frames) {
            fuse_held();
          }
        } else {
          fuse(result, *world_T_body);
          if (refiner) refine(*result, up_body);
        }
      } catch (const StrictStop&) {
        throw;
      } catch (const Error& e) {
        skip(t, e.what());
      }
    }
    ++done;
    if (config.map.checkpoint_every_frames > 0 && done % config.map.checkpoint_every_frames == 0) {
      fusion.Submit([&] { save_if_fused(); });
    }
    if (progress) progress(done, static_cast<int>(todo.size()));
  }
  fuse_held();  // a sequence (or run) shorter than the warm-up: fused with the mount in use
  fusion.Drain();
  summary.frames_already_in_map = already_in_map;
  save_if_fused();
  summary.map_nodes = map.NumNodes();
  std::error_code no_file;
  const std::uintmax_t bytes = std::filesystem::file_size(options.map_path, no_file);
  summary.map_file_bytes = no_file ? 0 : static_cast<std::size_t>(bytes);
  summary.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (refiner) {
    summary.refinement = refiner->summary();
    summary.refinement->frames_reprocessed = reprocessed;
  }
  return summary;
}

std::string BuildMapSummary::BriefReport() const {
  std::ostringstream r;
  r << std::fixed << std::setprecision(1);
  r << "frames: " << frames_used << " fused, ";
  if (frames_already_in_map > 0) r << frames_already_in_map << " already in the resumed map, ";
  r << skipped.size() << " skipped, " << quality_failed.size()
    << " failed the quality check (free space only) (of " << frames_listed << " listed)"
    << (interrupted ? "; interrupted, the map holds what was fused" : "") << "\n";
  for (const auto& s : skipped) r << "  skipped " << s.timestamp_ns << ": " << s.reason << "\n";
  for (const auto& s : quality_failed) r << "  no verdicts " << s.timestamp_ns << ": " << s.reason << "\n";
  if (!gravity.empty()) r << "gravity: " << gravity << "\n";
  if (frames_used == 0 && frames_already_in_map == 0) {  // BuildMap wrote nothing
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
  j << ",\n  \"map_nodes\": " << map_nodes << ",\n  \"map_file_bytes\": " << map_file_bytes
    << ",\n  \"points_inserted\": " << points_inserted << ",\n  \"wall_s\": " << wall_s
    << ",\n  \"interrupted\": " << (interrupted ? "true" : "false") << ",\n  \"gravity\": \""
    << internal::JsonEscape(gravity) << "\"";
  if (refinement) j << ",\n  \"refinement\": " << refinement->Json();
  j << "\n}\n";
  return j.str();
}

}  // namespace ssta
