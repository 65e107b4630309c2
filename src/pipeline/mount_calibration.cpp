#include "ssta/pipeline/mount_calibration.h"

#include <chrono>
#include <sstream>

#include "refinement/refinement_json.h"
#include "ssta/core/error.h"
#include "ssta/io/image_io.h"
#include "ssta/pipeline/frame_pipeline.h"
#include "ssta/sensors/gravity_provider.h"

namespace ssta {

bool MountCalibrationOptions::IsValid(std::string* error) const {
  if (every < 1) {
    if (error) *error = "every: must be at least 1";
    return false;
  }
  if (max_frames < 0) {
    if (error) *error = "max-frames: must not be negative";
    return false;
  }
  std::string inner;
  if (!refinement.IsValid(&inner)) {
    if (error) *error = "refinement." + inner;
    return false;
  }
  return true;
}

MountCalibration CalibrateMount(const Sequence& sequence, const Config& config, const MountCalibrationOptions& options,
                                const std::function<void(int done, int total)>& progress) {
  std::string error;
  if (!options.IsValid(&error)) throw Error(error);
  if (!config.IsValid(&error)) throw Error("config: " + error);
  const StereoCalibration& rig = sequence.calibration();
  FramePipeline pipeline(rig, config);
  const GravityProvider gravity(sequence, config.gravity, config.attitude);
  const Eigen::Matrix3d camera_R_rectified = pipeline.geometry().rectified_R_camera.transpose();
  MountRefiner refiner(options.refinement, rig.left.body_T_camera);

  MountCalibration out;
  out.frames_listed = static_cast<int>(sequence.frames().size() + sequence.skipped().size());
  out.skipped = sequence.skipped();
  const std::vector<StereoFrame> todo = SelectFrames(sequence.frames(), options.every, options.max_frames);
  const auto start = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < todo.size(); ++i) {
    const std::int64_t t = todo[i].timestamp_ns;
    try {
      const StereoImages images = ReadStereoImages(todo[i], sequence.calibration());
      const ImageU8& left = images.left;
      const ImageU8& right = images.right;
      // Gravity through the configured (uncorrected) mount: it only steers the choice of the
      // ground segment, whose points are what the refinement uses.
      FrameResult frame = pipeline.Process(left, right, gravity.UpInCamera(t));
      frame.timestamp_ns = t;
      ++out.frames_processed;
      GroundEvidence evidence = ExtractGroundEvidence(frame, camera_R_rectified, gravity.UpInBody(t), options.refinement);
      if (evidence.usable) {
        refiner.AddFrame(std::move(evidence));
      } else {
        out.skipped.push_back({t, evidence.reason});
      }
    } catch (const Error& e) {
      out.skipped.push_back({t, e.what()});
    }
    if (progress) progress(static_cast<int>(i + 1), static_cast<int>(todo.size()));
  }
  out.pipeline_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (refiner.NumFrames() == 0) {
    std::ostringstream m;
    m << sequence.root() << ": no frame has a usable ground plane (" << todo.size() << " tried)";
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
