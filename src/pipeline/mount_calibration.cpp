#include "ssta/pipeline/mount_calibration.h"

#include <chrono>
#include <optional>
#include <sstream>

#include "mount/refinement_json.h"
#include "ssta/core/error.h"
#include "ssta/pipeline/sequence_run.h"

namespace ssta {

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
  SequenceRun run(sequence, config, options.frames);
  const StereoCalibration& rig = sequence.calibration();
  const RigChain chain(rig.left.body_T_camera, run.geometry());
  const bool path = options.refinement.ground_reference == GroundReference::kPath;

  // The path reference needs every selected frame's pose before the first frame is processed:
  // the sequence's own poses, as they are. Only their relative motion over the seconds between
  // seeing the ground and standing on it matters, and the IMU attitude filter's roll and pitch
  // lean with every turn's centripetal acceleration, which the relative rotation would carry.
  // A frame without a pose has no path: its ground and the ground it stands on are unused.
  std::vector<std::optional<Eigen::Isometry3d>> poses(run.frames().size());
  if (path) {
    for (std::size_t i = 0; i < poses.size(); ++i) poses[i] = sequence.WorldTBodyAt(run.frames()[i].timestamp_ns);
  }

  MountCalibration out;
  out.frames_listed = run.frames_listed();
  out.skipped = run.sequence_skips();
  // The path reference chooses its points later, among more: the driven-over band is a small
  // part of the ground segment.
  constexpr int kPathPointsFactor = 8;
  RefinementOptions wide = options.refinement;
  wide.points_per_frame *= kPathPointsFactor;
  std::vector<GroundEvidence> evidence_body, evidence_path(path ? run.frames().size() : 0);
  const auto start = std::chrono::steady_clock::now();
  int done = 0;
  for (std::size_t i = 0; i < run.frames().size(); ++i) {
    const StereoFrame& frame = run.frames()[i];
    const std::int64_t t = frame.timestamp_ns;
    try {
      // Gravity through the configured (uncorrected) mount: it only steers the choice of the
      // ground segment, whose points are what the refinement uses.
      const FrameResult result = run.Classify(frame, run.gravity().UpInCamera(t));
      ++out.frames_processed;
      const Eigen::Vector3d up_body = run.gravity().UpInBody(t);
      GroundEvidence evidence =
          ExtractGroundEvidence(result, chain.camera_R_rectified(), up_body, options.refinement);
      if (evidence.usable) {
        evidence_body.push_back(std::move(evidence));
        if (path) evidence_path[i] = ExtractGroundEvidence(result, chain.camera_R_rectified(), up_body, wide);
      } else {
        out.skipped.push_back({t, evidence.reason});
      }
    } catch (const StrictStop&) {
      throw;
    } catch (const Error& e) {
      run.RequireNotStrict(t, e.what());
      out.skipped.push_back({t, e.what()});
    }
    if (progress) progress(++done, static_cast<int>(run.frames().size()));
  }
  out.pipeline_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (evidence_body.empty()) {
    std::ostringstream m;
    m << sequence.root() << ": no frame has a usable ground plane (" << run.frames().size() << " tried)";
    if (!out.skipped.empty()) m << "; first: " << out.skipped.front().reason;
    throw Error(m.str());
  }
  // The path reference when the drive went over the ground of at least min_frames frames;
  // otherwise the plane under the wheels now.
  int frames_on_path = 0;
  if (path) {
    out.refinement = SolveAlongPath(options.refinement, rig.left.body_T_camera, poses, evidence_path, &frames_on_path);
    out.frames_on_path = frames_on_path;
  }
  if (!path || frames_on_path < options.refinement.min_frames) {
    RefinementOptions body = options.refinement;
    if (path) {
      body.ground_reference = GroundReference::kBody;
      out.reference_note = "path reference: the drive goes over the ground of " + std::to_string(frames_on_path) +
                           " frame(s), fewer than min_frames (" + std::to_string(body.min_frames) +
                           "); the body reference is used";
    }
    MountRefiner refiner(body, rig.left.body_T_camera);
    for (GroundEvidence& e : evidence_body) refiner.AddFrame(std::move(e));
    out.refinement = refiner.Solve();
  }
  out.refined = rig;
  out.refined.left.body_T_camera = out.refinement.body_T_camera_refined;
  out.refined.right.body_T_camera = out.refinement.body_T_camera_refined * rig.LeftTRight();
  return out;
}

std::string MountCalibration::BriefReport() const {
  std::ostringstream r;
  r << refinement.BriefReport();
  if (!reference_note.empty()) r << reference_note << "\n";
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
