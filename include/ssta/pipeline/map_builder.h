#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "ssta/io/sequence.h"
#include "ssta/mapping/map_types.h"
#include "ssta/mapping/traversability_map.h"
#include "ssta/pipeline/config.h"
#include "ssta/core/progress.h"
#include "ssta/pipeline/frame_pipeline.h"
#include "ssta/pipeline/sequence_run.h"
#include "ssta/mount/online_mount_refiner.h"

namespace ssta {

/// `ssta build-map` options that are not in the config file.
struct BuildMapOptions {
  std::string map_path;        ///< the .ot file to write (and to continue with `resume`)
  bool resume = false;         ///< continue the map at map_path with this sequence
  /// With `resume`: fuse the sequence even when it shares frames (same time and image) with a
  /// recording the map holds, whose evidence then counts twice. Off: such a run is refused.
  bool allow_overlap = false;
  /// The platform stands still and the sequence has no poses: every frame is taken at the
  /// origin, levelled by gravity (IMU, else a level body), yaw 0.
  bool static_platform = false;
  /// Name of the world frame the sequence's poses are in, recorded in a new map's metadata
  /// (MapMetadata::world_frame): maps merge only when they name the same frame. Empty:
  /// unnamed; with `resume`, a non-empty name must be the map's.
  std::string world_frame;
  /// Which frames to fuse; with `strict` a frame that cannot be used (no pose, unreadable
  /// image, ...) is an error, and the map keeps what was fused before it.
  FrameSelection frames;
  /// Fuse frame k into the map on a second thread while frame k+1 is classified (one frame
  /// waits at most), and read frame k+1's images while frame k is classified
  /// (SequenceRun::set_read_ahead). The map and the summary are the same as without; only the
  /// time differs.
  bool pipelined = true;
  /// The true disparity measures the analysis and the fusion apart from the matcher; the true
  /// labels with it the fusion alone, with the matcher what the matcher's geometry costs the
  /// map. A frame without its truth is skipped with a reason (an error with `strict`).
  Oracles oracles;
  bool IsValid(std::string* error) const;
};

/// What a build-map run did.
struct BuildMapSummary {
  int frames_listed = 0;
  int frames_used = 0;
  /// Frames a resumed run found already fused (an interrupted run of the same sequence).
  int frames_already_in_map = 0;
  std::vector<SkippedFrame> skipped;         ///< not fused, and why
  /// Failed the quality check and not judged (QualityCheck::judged): fused for free space only,
  /// with no class verdicts.
  std::vector<SkippedFrame> quality_failed;
  /// What of the recording was missing (Sequence::warnings: a truncated bag read anyway); the
  /// map's metadata notes record them too.
  std::vector<std::string> warnings;
  std::string gravity;  ///< where roll and pitch came from (GravityProvider::Describe)
  std::size_t map_nodes = 0;
  std::size_t map_file_bytes = 0;
  std::size_t points_inserted = 0;
  double wall_s = 0.0;
  bool interrupted = false;  ///< stopped early on request; the map holds what was fused
  bool map_existed = false;  ///< a file was at map_path when the run started
  /// What the online mount refinement did (config.refinement.online); nullopt when off.
  std::optional<OnlineRefinementSummary> refinement;

  /// Whether the map at map_path holds the sequence: the run fused a frame, or found every
  /// frame it could use already in the resumed map.
  bool Fused() const { return frames_used > 0 || frames_already_in_map > 0; }
  std::string BriefReport() const;
  std::string Json() const;
};

/// Unless summary.Fused(), throws ssta::Error "SEQUENCE: no frame could be fused; MAP was left
/// as it was" ("... was not written" when there was no file): a run that fuses nothing fails,
/// after its report, for `build-map` and Python's build_map alike.
void RequireFused(const BuildMapSummary& summary, const std::string& sequence, const std::string& map_path);

/// The name a run records for the sequence at `path` (MapMetadata): its folder or file name,
/// or `path` itself when it has none.
std::string SequenceNameOf(const std::string& path);

/// Fuses one classified frame into `map` the way BuildMap does: its points (MapPointsOfFrame with
/// config.map and config.vehicle, written into `*points`, which is cleared first and keeps its
/// capacity from frame to frame) inserted from the origin of `world_T_rectified` (the rectified
/// cam0 frame in the world) at frame.timestamp_ns. Throws ssta::Error as InsertFrame does.
InsertStats FuseFrame(const FrameResult& frame, const Eigen::Isometry3d& world_T_rectified, const Config& config,
                      const RectifiedGeometry& geometry, std::vector<ClassifiedPoint>* points,
                      TraversabilityMap* map);

/// Classifies every usable frame of `sequence` and fuses it into the map at options.map_path
/// (a new map, or the existing one with `resume`). Poses come from the sequence with roll and
/// pitch corrected by the IMU attitude filter where there is an IMU (GravityProvider); frames
/// without a pose are skipped with a reason. With config.refinement.online, each fused frame's
/// ground evidence goes to an OnlineMountRefiner, and a determined solve replaces cam0's mount
/// for the gravity (up in the camera) and the fusion pose (body_T_rectified) of every later
/// frame; the map's metadata records the refined mount, and a resumed build whose cam0
/// sensor.yaml mount equals the recorded configured one starts from the recorded refined one
/// (a different sensor.yaml starts from its own). The map is saved atomically every
/// config.map.checkpoint_every_frames frames and at the end, also when `stop` turns true (the
/// run then ends after the current frame), but only once the run has fused a frame: a run that
/// fuses none leaves the file at map_path as it was. Throws ssta::Error on bad input before any
/// work; with `resume`, also when the config's vehicle differs from the map's (its classes are
/// that vehicle's) or its map.resolution_m from the map's resolution. With `resume`, when the map's last sequence is `sequence_name` (a run that was interrupted
/// or killed), frames up to the map's last fused timestamp are already in it and are not fused
/// again; another sequence is fused whole, unless it shares a frame (same timestamp, same
/// SampledImageHash of the left image) with a recording in the map's fingerprints
/// (MapMetadata::recordings): then ssta::Error names the map, both recordings and the first
/// shared frame before anything is fused (`allow_overlap` fuses it anyway). The map records
/// the fingerprint of every frame it fuses. The run holds the map's MapWriteLock from before
/// it reads the map to after its last save: a second writer of the same map fails at once
/// with ssta::Error naming the map and this process.
BuildMapSummary BuildMap(const Sequence& sequence, const std::string& sequence_name, const Config& config,
                         const BuildMapOptions& options, const Progress& progress = {},
                         const std::atomic<bool>* stop = nullptr);

}  // namespace ssta
