#include "ssta/sensors/gravity_provider.h"

namespace ssta {
namespace {

const EnumTable<GravitySource>& GravitySources() {
  static const EnumTable<GravitySource> table("gravity.source", {{GravitySource::kAuto, "auto"},
                                                                 {GravitySource::kImu, "imu"},
                                                                 {GravitySource::kPose, "pose"},
                                                                 {GravitySource::kLevel, "level"},
                                                                 {GravitySource::kFixed, "fixed"}});
  return table;
}

}  // namespace

const OptionFields<GravityOptions>& GravityOptions::Fields() {
  using O = GravityOptions;
  static const OptionFields<O> fields = [] {
    OptionFields<O> f;
    f.push_back(Choice<O>("source", &O::source, GravitySources(),
                          "auto (the IMU, else the pose, else level) | imu | pose | level | fixed"));
    f.push_back(Vector3<O>("up_camera", &O::up_camera, "",
                           "for source fixed: up in the cam0 frame (x right, y down, z forward)")
                    .Require([](const O& o) { return o.up_camera.norm() >= 1e-6; }, "must not be zero"));
    return f;
  }();
  return fields;
}

std::string GravitySourceName(GravitySource source) { return GravitySources().Name(source); }

bool GravityOptions::IsValid(std::string* error) const { return CheckOptions(*this, Fields(), error); }


GravityProvider::GravityProvider(const Sequence& sequence, const GravityOptions& gravity,
                                 const AttitudeFilterOptions& attitude)
    : sequence_(sequence), gravity_(gravity) {
  if (!sequence.imu().empty() && gravity.source != GravitySource::kPose && gravity.source != GravitySource::kLevel) {
    track_ = std::make_unique<GravityTrack>(sequence.imu(), sequence.body_T_imu(), attitude, sequence.imu_path());
    sequence.RequireFramesWithin(sequence.imu().front().timestamp_ns, sequence.imu().back().timestamp_ns,
                                 sequence.imu_path(), "IMU samples");
  }
}

std::string GravityProvider::Describe() const {
  if (gravity_.source == GravitySource::kFixed) return "fixed up vector (gravity.up_camera)";
  if (track_) return "IMU attitude filter (" + sequence_.imu_path() + ")";
  if (gravity_.source == GravitySource::kLevel) return "level (gravity.source: level)";
  if (!sequence_.poses().empty()) return "pose attitude (" + sequence_.pose_path() + ")";
  return "level (no IMU, no poses)";
}

std::string GravityProvider::ImuGap(std::int64_t t) const {
  const auto& imu = sequence_.imu();
  return sequence_.imu_path() + ": frame " + std::to_string(t) + " lies outside the IMU samples (" +
         std::to_string(imu.front().timestamp_ns) + " to " + std::to_string(imu.back().timestamp_ns) +
         " ns): no attitude for it";
}

Eigen::Vector3d GravityProvider::UpInBody(std::int64_t t, std::string* source_used) const {
  const GravitySource s = gravity_.source;
  auto answer = [&](const Eigen::Vector3d& up, const char* name) {
    if (source_used) *source_used = name;
    return up.normalized();
  };
  if (s == GravitySource::kImu || s == GravitySource::kAuto) {
    if (track_) {
      // With an IMU, a frame it does not cover is skipped, never guessed from another source.
      if (auto up = track_->UpInBodyAt(t)) return answer(*up, "imu");
      throw Error(ImuGap(t));
    }
    if (s == GravitySource::kImu) {
      throw Error(sequence_.root() + ": gravity.source is 'imu' but the sequence has no IMU (imu0/data.csv)");
    }
  }
  if (s == GravitySource::kPose || s == GravitySource::kAuto) {
    if (auto pose = sequence_.WorldTBodyAt(t)) return answer(pose->linear().transpose() * Eigen::Vector3d::UnitZ(), "pose");
    if (s == GravitySource::kPose) {
      throw Error((sequence_.pose_path().empty() ? sequence_.root() : sequence_.pose_path()) +
                  ": gravity.source is 'pose' but there is no pose at frame " + std::to_string(t) + ": " +
                  sequence_.NoPoseReason(t));
    }
  }
  if (s == GravitySource::kFixed) {
    const Eigen::Matrix3d body_R_camera = sequence_.calibration().left.body_T_camera.linear();
    return answer(body_R_camera * gravity_.up_camera, "fixed");
  }
  return answer(Eigen::Vector3d::UnitZ(), "level");
}

Eigen::Vector3d GravityProvider::UpInCamera(std::int64_t t, std::string* source_used) const {
  if (gravity_.source == GravitySource::kFixed) {
    if (source_used) *source_used = "fixed";
    return gravity_.up_camera.normalized();
  }
  const Eigen::Matrix3d camera_R_body = sequence_.calibration().left.body_T_camera.linear().transpose();
  return (camera_R_body * UpInBody(t, source_used)).normalized();
}

std::optional<Eigen::Isometry3d> GravityProvider::WorldTBodyAt(std::int64_t t) const {
  const auto pose = sequence_.WorldTBodyAt(t);
  if (!pose) return std::nullopt;
  if (track_ && gravity_.source != GravitySource::kPose) {
    if (auto up = track_->UpInBodyAt(t)) return CorrectRollPitch(*pose, *up);
    throw Error(ImuGap(t));
  }
  return pose;
}

}  // namespace ssta
