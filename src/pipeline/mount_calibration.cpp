#include "ssta/pipeline/mount_calibration.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <optional>
#include <sstream>
#include <utility>
#include <vector>

#include "mount/refinement_json.h"
#include "ssta/core/error.h"
#include "ssta/core/units.h"
#include "ssta/pipeline/sequence_run.h"

namespace ssta {
namespace {

/// The path reference chooses its points later, among more: the driven-over band is a small
/// part of the ground segment.
constexpr int kPathPointsFactor = 8;

/// The sub-pixel refinement window calibrate-mount uses when the config has none [px].
constexpr int kUnbiasedSubpixelWindowPx = 7;

/// The config calibrate-mount matches with (RefinementOptions::unbiased_matching); `note` says
/// what changed, or stays empty.
Config MatchingConfig(const Config& config, const MountCalibrationOptions& options, std::string* note) {
  Config out = config;
  StereoMatcherOptions& stereo = out.stereo;
  if (!options.refinement.unbiased_matching || options.oracle_disparity) return out;
  std::vector<std::string> changes;
  const bool one_pass = stereo.sgbm_mode == SgbmMode::kThreeWay || stereo.sgbm_mode == SgbmMode::kFive;
  if (stereo.algorithm == MatcherType::kSemiGlobal && one_pass) {
    changes.push_back("stereo.sgbm_mode hh4 instead of " + SgbmModeName(stereo.sgbm_mode));
    stereo.sgbm_mode = SgbmMode::kHh4;
  }
  if (stereo.subpixel_window_px == 0) {
    changes.push_back("stereo.subpixel_window_px " + std::to_string(kUnbiasedSubpixelWindowPx));
    stereo.subpixel_window_px = kUnbiasedSubpixelWindowPx;
  }
  if (changes.empty()) return out;
  *note = "matched with " + changes.front() + (changes.size() > 1 ? " and " + changes.back() : std::string()) +
          " (refinement.unbiased_matching): the ground's disparity unbiased";
  return out;
}

/// What the per-frame pipeline gave over a run's frames.
struct GroundCollection {
  std::vector<GroundEvidence> body;  ///< each usable frame's evidence, in frame order
  /// Per frame of the run, kPathPointsFactor times the points for the path reference (default
  /// evidence for a frame that is not usable); empty for any other reference.
  std::vector<GroundEvidence> path;
  int frames_processed = 0;           ///< frames run through the pipeline
  std::vector<SkippedFrame> skipped;  ///< frames of the run not used, with the reason
  double pipeline_s = 0.0;            ///< wall time of the pipeline over all frames [s]
};

/// The mount correction and the reference it was solved against.
struct MountSolution {
  MountRefinementResult refinement;
  int frames_on_path = 0;      ///< path reference: frames whose ground a later body stands on
  std::string reference_note;  ///< why the path reference gave way to the body reference
};

/// The pose of every frame of the run for the path reference, `nullopt` for none; all `nullopt`
/// for any other reference.
std::vector<std::optional<Eigen::Isometry3d>> PathPoses(const Sequence& sequence, const SequenceRun& run,
                                                        const RefinementOptions& refinement) {
  // The path reference needs every selected frame's pose before the first frame is processed:
  // the sequence's own poses, as they are. Only their relative motion over the seconds between
  // seeing the ground and standing on it matters, and the IMU attitude filter's roll and pitch
  // lean with every turn's centripetal acceleration, which the relative rotation would carry.
  // A frame without a pose has no path: its ground and the ground it stands on are unused.
  std::vector<std::optional<Eigen::Isometry3d>> poses(run.frames().size());
  if (refinement.ground_reference == GroundReference::kPath) {
    for (std::size_t i = 0; i < poses.size(); ++i) poses[i] = sequence.WorldTBodyAt(run.frames()[i].timestamp_ns);
  }
  return poses;
}

/// Runs the per-frame pipeline over every frame of `run` and takes each frame's ground evidence,
/// up in the body from the run's gravity. A frame that fails is skipped with the reason (a
/// StrictStop in a strict run).
GroundCollection CollectGroundEvidence(SequenceRun* run, const StereoCalibration& rig,
                                       const RefinementOptions& refinement, const Progress& progress) {
  const RigChain chain(rig.left.body_T_camera, run->geometry());
  const bool path = refinement.ground_reference == GroundReference::kPath;
  RefinementOptions wide = refinement;
  wide.points_per_frame *= kPathPointsFactor;
  GroundCollection out;
  out.path.resize(path ? run->frames().size() : 0);
  const auto start = std::chrono::steady_clock::now();
  int done = 0;
  for (std::size_t i = 0; i < run->frames().size(); ++i) {
    const StereoFrame& frame = run->frames()[i];
    const std::int64_t t = frame.timestamp_ns;
    try {
      // Gravity through the configured (uncorrected) mount: it only steers the choice of the
      // ground segment, whose points are what the refinement uses.
      const FrameResult result = run->Classify(frame, run->gravity().UpInCamera(t));
      ++out.frames_processed;
      const Eigen::Vector3d up_body = run->gravity().UpInBody(t);
      GroundEvidence evidence = ExtractGroundEvidence(result, chain.camera_R_rectified(), up_body, refinement);
      if (evidence.usable) {
        out.body.push_back(std::move(evidence));
        if (path) out.path[i] = ExtractGroundEvidence(result, chain.camera_R_rectified(), up_body, wide);
      } else {
        out.skipped.push_back({t, evidence.reason});
      }
    } catch (const StrictStop&) {
      throw;
    } catch (const Error& e) {
      run->RequireNotStrict(t, e.what());
      out.skipped.push_back({t, e.what()});
    }
    if (progress) progress(++done, static_cast<int>(run->frames().size()));
  }
  out.pipeline_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

/// How far the body's z axis turns over the drive: the largest angle between a pose's body z
/// and the poses' mean body z [deg]; 0 without poses.
double BodyTiltRadiusDeg(const std::vector<std::optional<Eigen::Isometry3d>>& poses) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& pose : poses) {
    if (pose) mean += pose->linear().col(2);
  }
  if (mean.norm() < 1e-9) return 0.0;
  mean.normalize();
  double radius = 0.0;
  for (const auto& pose : poses) {
    if (pose) radius = std::max(radius, std::acos(std::clamp(pose->linear().col(2).dot(mean), -1.0, 1.0)));
  }
  return RadToDeg(radius);
}

/// The body reference, standing in for the path reference, expects the ground the frames see
/// parallel to the wheel plane of the body that sees it. A body that tilts over the drive by
/// more than twice systematic_sigma_deg from its mean shows ground that is not uniformly sloped
/// at the drive's own scale; ground farther ahead may tilt more, the same way for every frame,
/// so no scatter shows it and the sigma would not cover it. Such a correction is not applied.
void KeepMountOnNonUniformGround(const RefinementOptions& refinement, double tilt_radius_deg,
                                 MountRefinementResult* result) {
  const double limit_deg = 2.0 * refinement.systematic_sigma_deg;
  if (!result->applied() || tilt_radius_deg <= limit_deg) return;
  std::ostringstream m;
  m << std::setprecision(3) << "the ground is not uniform: the body reference stands in for the path reference, and the "
    << "body tilts up to " << tilt_radius_deg << " deg from its mean over the drive (more than twice "
    << "systematic_sigma_deg, " << limit_deg << " deg), so the ground ahead need not lie parallel to the wheels; "
    << "the configured mount is kept (drive on over the ground the first frames see, or on level ground)";
  result->status = RefinementStatus::kTerrainTooRough;
  result->message = m.str();
  result->body_T_camera_refined = result->body_T_camera_initial;
}

/// Solves for cam0's mount correction from the collected evidence: the path reference when the
/// drive went over the ground of at least min_frames frames; otherwise the plane under the
/// wheels now, where the poses show the body tilting little. `body_T_camera` is the configured
/// mount of cam0.
MountSolution SolveMount(const RefinementOptions& refinement, const Eigen::Isometry3d& body_T_camera,
                         const std::vector<std::optional<Eigen::Isometry3d>>& poses, GroundCollection* ground) {
  const bool path = refinement.ground_reference == GroundReference::kPath;
  MountSolution out;
  int frames_on_path = 0;
  if (path) {
    out.refinement = SolveAlongPath(refinement, body_T_camera, poses, ground->path, &frames_on_path);
    out.frames_on_path = frames_on_path;
  }
  if (!path || frames_on_path < refinement.min_frames) {
    RefinementOptions body = refinement;
    if (path) {
      body.ground_reference = GroundReference::kBody;
      out.reference_note = "path reference: the drive goes over the ground of " + std::to_string(frames_on_path) +
                           " frame(s), fewer than min_frames (" + std::to_string(body.min_frames) +
                           "); the body reference is used";
    }
    MountRefiner refiner(body, body_T_camera);
    for (GroundEvidence& e : ground->body) refiner.AddFrame(std::move(e));
    out.refinement = refiner.Solve();
    if (path) KeepMountOnNonUniformGround(refinement, BodyTiltRadiusDeg(poses), &out.refinement);
  }
  return out;
}

}  // namespace

bool MountCalibrationOptions::IsValid(std::string* error) const {
  if (!frames.IsValid(error)) return false;
  std::string inner;
  if (!refinement.IsValid(&inner)) return Fail(error, "refinement." + inner);
  return true;
}

MountCalibration CalibrateMount(const Sequence& sequence, const Config& config, const MountCalibrationOptions& options,
                                const Progress& progress) {
  std::string error;
  if (!options.IsValid(&error)) throw Error(error);
  std::string matching_note;
  const Config matching = MatchingConfig(config, options, &matching_note);
  SequenceRun run(sequence, matching, options.frames, Oracles{options.oracle_disparity, false});
  const StereoCalibration& rig = sequence.calibration();
  const std::vector<std::optional<Eigen::Isometry3d>> poses = PathPoses(sequence, run, options.refinement);

  MountCalibration out;
  out.matching_note = std::move(matching_note);
  out.frames_listed = run.frames_listed();
  out.skipped = run.sequence_skips();
  GroundCollection ground = CollectGroundEvidence(&run, rig, options.refinement, progress);
  out.frames_processed = ground.frames_processed;
  out.skipped.insert(out.skipped.end(), ground.skipped.begin(), ground.skipped.end());
  out.pipeline_s = ground.pipeline_s;
  if (ground.body.empty()) {
    std::ostringstream m;
    m << sequence.root() << ": no frame has a usable ground plane (" << run.frames().size() << " tried)";
    if (!out.skipped.empty()) m << "; first: " << out.skipped.front().reason;
    throw Error(m.str());
  }
  MountSolution solution = SolveMount(options.refinement, rig.left.body_T_camera, poses, &ground);
  out.refinement = std::move(solution.refinement);
  out.frames_on_path = solution.frames_on_path;
  out.reference_note = std::move(solution.reference_note);
  out.refined = rig;
  out.refined.left.body_T_camera = out.refinement.body_T_camera_refined;
  out.refined.right.body_T_camera = out.refinement.body_T_camera_refined * rig.LeftTRight();
  return out;
}

std::string MountCalibration::BriefReport() const {
  std::ostringstream r;
  r << refinement.BriefReport();
  if (!reference_note.empty()) r << reference_note << "\n";
  if (!matching_note.empty()) r << matching_note << "\n";
  r << "frames: " << frames_processed << " processed of " << frames_listed << " listed, " << refinement.frames_used
    << " used, " << skipped.size() << " skipped; pipeline " << pipeline_s << " s\n";
  for (const SkippedFrame& s : skipped) r << "  skipped " << s.timestamp_ns << ": " << s.reason << "\n";
  return r.str();
}

std::string MountCalibration::Json() const {
  internal::JsonWriter json;
  json.BeginObject();
  json.Key("refinement");
  internal::WriteRefinementJson(refinement, &json);
  json.Key("cam0_T_BS");
  json.MatrixRows(refined.left.body_T_camera.matrix());
  json.Key("cam1_T_BS");
  json.MatrixRows(refined.right.body_T_camera.matrix());
  json.Key("reference_note");
  json.String(reference_note);
  json.Key("matching_note");
  json.String(matching_note);
  json.Key("frames_listed");
  json.Integer(frames_listed);
  json.Key("frames_processed");
  json.Integer(frames_processed);
  json.Key("pipeline_s");
  json.Number(pipeline_s);
  json.Key("skipped");
  internal::WriteSkippedFramesJson(skipped, &json);
  json.EndObject();
  return json.Take() + "\n";
}

}  // namespace ssta
