#include "ssta/pipeline/mount_calibration.h"

#include <chrono>
#include <sstream>

#include "refinement/refinement_json.h"
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
  MountRefiner refiner(options.refinement, rig.left.body_T_camera);

  MountCalibration out;
  out.frames_listed = run.frames_listed();
  out.skipped = run.sequence_skips();
  const auto start = std::chrono::steady_clock::now();
  int done = 0;
  for (const StereoFrame& frame : run.frames()) {
    const std::int64_t t = frame.timestamp_ns;
    try {
      // Gravity through the configured (uncorrected) mount: it only steers the choice of the
      // ground segment, whose points are what the refinement uses.
      const FrameResult result = run.Classify(frame, run.gravity().UpInCamera(t));
      ++out.frames_processed;
      GroundEvidence evidence =
          ExtractGroundEvidence(result, chain.camera_R_rectified(), run.gravity().UpInBody(t), options.refinement);
      if (evidence.usable) {
        refiner.AddFrame(std::move(evidence));
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
  if (refiner.NumFrames() == 0) {
    std::ostringstream m;
    m << sequence.root() << ": no frame has a usable ground plane (" << run.frames().size() << " tried)";
    if (!out.skipped.empty()) m << "; first: " << out.skipped.front().reason;
    throw Error(m.str());
  }
  out.refinement = refiner.Solve();
  out.refined = rig;
  out.refined.left.body_T_camera = out.refinement.body_T_camera_refined;
  out.refined.right.body_T_camera = out.refinement.body_T_camera_refined * rig.LeftTRight();
  return out;
}

std::string MountCalibration::BriefReport() const {
  std::ostringstream r;
  r << refinement.BriefReport();
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
