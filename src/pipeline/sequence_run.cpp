#include "ssta/pipeline/sequence_run.h"

#include "ssta/analysis/label_rule.h"
#include "ssta/io/ground_truth.h"
#include "ssta/mapping/recording_fingerprint.h"
#include "ssta/sensors/attitude_filter.h"

namespace ssta {
namespace {

/// The frame's true labels over its own, where the truth has a verdict (1-3), with the rule
/// `truth`: 255 (sky, occlusions, the band on class boundaries) keeps the frame's.
void ApplyTrueLabels(const Sequence& sequence, std::int64_t t, const RectifiedGeometry& g, ImageU8* labels,
                     ImageU8* rules) {
  const ImageU8 truth = ReadTrueLabels(sequence, t);
  if (truth.width() != g.full_width || truth.height() != g.full_height) {
    throw Error(TruthFramePath(sequence, "labels", t) + ": the true labels are " + std::to_string(truth.width()) + "x" +
                std::to_string(truth.height()) + ", the frames are " + std::to_string(g.full_width) + "x" +
                std::to_string(g.full_height));
  }
  SSTA_CHECK(labels->width() == g.crop_width && labels->height() == g.crop_height && rules->width() == g.crop_width &&
                 rules->height() == g.crop_height,
             "ApplyTrueLabels: the labels or rules are not of the common area's size");
  constexpr auto truth_rule = static_cast<std::uint8_t>(LabelRule::kTruth);
  for (int v = 0; v < labels->height(); ++v) {
    const std::uint8_t* from = truth.row(v + g.crop_v0) + g.crop_u0;
    std::uint8_t* out = labels->row(v);
    std::uint8_t* rule = rules->row(v);
    for (int u = 0; u < labels->width(); ++u) {
      if (from[u] >= 1 && from[u] <= 3) {
        out[u] = from[u];
        rule[u] = truth_rule;
      }
    }
  }
}

Config Validated(const Config& config) {
  std::string error;
  if (!config.IsValid(&error)) throw Error("config: " + error);
  return config;
}

}  // namespace

bool FrameSelection::IsValid(std::string* error) const {
  if (max_frames < 0) return Fail(error, "max-frames: must not be negative");
  if (every < 1) return Fail(error, "every: must be at least 1");
  return true;
}

RigChain::RigChain(const Eigen::Isometry3d& body_T_camera, const RectifiedGeometry& geometry)
    : camera_R_rectified_(geometry.rectified_R_camera.transpose()) {
  set_body_T_camera(body_T_camera);
}

void RigChain::set_body_T_camera(const Eigen::Isometry3d& body_T_camera) {
  body_T_camera_ = body_T_camera;
  body_T_rectified_ = body_T_camera;
  body_T_rectified_.linear() = body_T_camera.linear() * camera_R_rectified_;
}

SequenceRun::SequenceRun(const Sequence& sequence, const Config& config, const FrameSelection& selection,
                         const Oracles& oracles)
    : sequence_(sequence),
      selection_(selection),
      oracles_(oracles),
      pipeline_(sequence.calibration(), Validated(config)),
      gravity_(sequence, config.gravity, config.attitude) {
  std::string error;
  if (!selection.IsValid(&error)) throw Error(error);
  frames_ = SelectFrames(sequence.frames(), selection.every, selection.max_frames);
  if (!sequence.skipped().empty()) {
    RequireNotStrict(sequence.skipped().front().timestamp_ns, sequence.skipped().front().reason);
  }
}

int SequenceRun::frames_listed() const {
  return static_cast<int>(sequence_.frames().size() + sequence_.skipped().size());
}

Eigen::Isometry3d SequenceRun::WorldTBody(std::int64_t t, bool static_platform) const {
  if (static_platform) return CorrectRollPitch(Eigen::Isometry3d::Identity(), gravity_.UpInBody(t));
  const std::optional<Eigen::Isometry3d> pose = gravity_.WorldTBodyAt(t);
  if (!pose) throw Error("no pose: " + sequence_.NoPoseReason(t));
  return *pose;
}

FrameResult SequenceRun::Classify(const StereoFrame& frame, const Eigen::Vector3d& up_camera,
                                  std::uint64_t* left_image_hash) {
  const StereoImages images = ReadImages(frame);
  if (left_image_hash != nullptr) *left_image_hash = SampledImageHash(images.left);
  FrameResult result =
      oracles_.disparity
          ? pipeline_.ProcessWithDisparity(images.left, images.right,
                                           ReadTrueDisparity(sequence_, frame.timestamp_ns), up_camera)
          : pipeline_.Process(images.left, images.right, up_camera);
  result.timestamp_ns = frame.timestamp_ns;
  if (oracles_.labels) {
    ApplyTrueLabels(sequence_, frame.timestamp_ns, geometry(), &result.analysis.labels, &result.analysis.rules);
  }
  return result;
}

void SequenceRun::set_read_ahead(bool on) {
  read_ahead_ = on;
  if (!on && ahead_.valid()) ahead_.wait();  // its images are dropped with it at the next read
}

StereoImages SequenceRun::ReadImages(const StereoFrame& frame) {
  std::future<StereoImages> ahead = std::move(ahead_);
  const bool ahead_is_this = ahead.valid() && frames_[ahead_index_].timestamp_ns == frame.timestamp_ns &&
                             frames_[ahead_index_].left_path == frame.left_path &&
                             frames_[ahead_index_].right_path == frame.right_path;
  if (ahead.valid() && !ahead_is_this) ahead.wait();  // another frame's: one read at a time
  StereoImages images = ahead_is_this ? ahead.get() : sequence_.ReadImages(frame);  // throws as a read in turn
  if (read_ahead_) {
    // The next frame in frames(): after the one read ahead, else after `frame`'s place.
    std::size_t next = frames_.size();
    if (ahead_is_this) {
      next = ahead_index_ + 1;
    } else {
      for (std::size_t i = 0; i < frames_.size(); ++i) {
        if (frames_[i].timestamp_ns == frame.timestamp_ns && frames_[i].left_path == frame.left_path) {
          next = i + 1;
          break;
        }
      }
    }
    if (next < frames_.size()) {
      ahead_index_ = next;
      const Sequence* sequence = &sequence_;
      const StereoFrame* to_read = &frames_[next];
      ahead_ = std::async(std::launch::async, [sequence, to_read] { return sequence->ReadImages(*to_read); });
    }
  }
  return images;
}

void SequenceRun::RequireNotStrict(std::int64_t t, const std::string& reason) const {
  if (!selection_.strict) return;
  throw StrictStop(sequence_.root() + ": frame " + std::to_string(t) + ": " + reason +
                   " (strict: no frame may be skipped)");
}

}  // namespace ssta
