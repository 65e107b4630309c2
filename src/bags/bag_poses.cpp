#include "bags/bag_poses.h"

#include <optional>
#include <set>

#include "bags/ros_messages.h"
#include "ssta/core/error.h"

namespace ssta::internal {
namespace {

Eigen::Isometry3d FromXyzw(const std::array<double, 3>& t, const std::array<double, 4>& q, const std::string& where) {
  Eigen::Quaterniond rotation(q[3], q[0], q[1], q[2]);
  const double norm = rotation.norm();
  if (!(norm > 0.5 && norm < 1.5)) throw Error(where + ": quaternion norm " + std::to_string(norm) + " is not 1");
  rotation.normalize();
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = rotation.toRotationMatrix();
  out.translation() = Eigen::Vector3d(t[0], t[1], t[2]);
  return out;
}

/// The camera looking along body x (optical z forward = body x, optical x right = body -y,
/// optical y down = body -z), at the body origin: the mount assumed when /tf has none.
Eigen::Isometry3d ForwardLookingMount() {
  Eigen::Matrix3d r;
  r << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = r;
  return out;
}

PoseSample ToPose(std::int64_t t, const Eigen::Isometry3d& world_T_body) {
  PoseSample p;
  p.timestamp_ns = t;
  p.world_p_body = world_T_body.translation();
  p.world_q_body = Eigen::Quaterniond(world_T_body.linear()).normalized();
  return p;
}

void SortPoses(std::vector<PoseSample>* poses) {
  std::stable_sort(poses->begin(), poses->end(), [](const PoseSample& a, const PoseSample& b) { return a.timestamp_ns < b.timestamp_ns; });
  poses->erase(std::unique(poses->begin(), poses->end(),
                           [](const PoseSample& a, const PoseSample& b) { return a.timestamp_ns == b.timestamp_ns; }),
               poses->end());
}

/// Poses T_WB from an Odometry topic; returns the body frame (the messages' child frame).
std::string ReadOdometry(const Topics& topics, const std::string& topic, SequenceData* seq) {
  const BagReader& bag = topics.bag();
  const RosEncoding encoding = topics.Encoding(topic);
  const std::string where = bag.path() + ": " + topic;
  std::string body;
  for (const BagMessageRef& ref : bag.List({topics.Index(topic)})) {
    const RosOdometry m = DecodeOdometry(bag.Read(ref), encoding, where);
    if (body.empty()) body = m.child_frame_id;
    seq->poses.push_back(ToPose(m.header.stamp_ns != 0 ? m.header.stamp_ns : ref.log_time_ns,
                                FromXyzw(m.position, m.orientation_xyzw, where)));
  }
  if (seq->poses.empty()) throw Error(where + ": no Odometry messages (--pose-topic none to map without poses)");
  SortPoses(&seq->poses);
  seq->pose_path = bag.path() + ":" + topic;
  return body;
}

/// The frames a body frame is looked for under, in order, when --pose-frame is not given.
const std::vector<std::string>& BodyFrameNames() {
  static const std::vector<std::string> names = {"base_link", "base_footprint"};
  return names;
}

/// Poses T_WB from /tf: the body frame's pose in the root of its tree, at every time a
/// transform on the way changes.
void PosesFromTf(const std::string& path, const TfTree& tf, const std::string& body, SequenceData* seq) {
  const std::string world = tf.RootOf(body);
  if (world == body) throw Error(path + ": /tf: frame '" + body + "' has no parent: no pose to read");
  for (const std::int64_t t : tf.ChangeTimes(world, body)) {
    if (const auto pose = tf.Lookup(world, body, t)) seq->poses.push_back(ToPose(t, *pose));
  }
  if (seq->poses.empty()) throw Error(path + ": /tf: no pose of '" + body + "' in '" + world + "'");
  SortPoses(&seq->poses);
  seq->pose_path = path + ":/tf (" + world + " -> " + body + ")";
}

}  // namespace

TfTree ReadTf(const Topics& topics, std::vector<std::string>* notes) {
  const BagReader& bag = topics.bag();
  TfTree tree;
  std::set<std::string> bad_links;
  for (const std::string topic : {"/tf_static", "/tf"}) {
    const bool is_static = topic == "/tf_static";
    if (!topics.Has(topic)) continue;
    if (topics.Type(topic) != "tf2_msgs/TFMessage") continue;
    const RosEncoding encoding = topics.Encoding(topic);
    for (const BagMessageRef& ref : bag.List({topics.Index(topic)})) {
      const std::string where = bag.path() + ": " + topic;
      for (const RosTransform& t : DecodeTfMessage(bag.Read(ref), encoding, where)) {
        const std::string link = topic + " " + t.header.frame_id + " -> " + t.child_frame_id;
        try {
          tree.Add(t.header.frame_id, t.child_frame_id, t.header.stamp_ns,
                   FromXyzw(t.translation, t.rotation_xyzw, where + " " + link), is_static);
        } catch (const Error& e) {
          if (bad_links.insert(link).second) notes->push_back(std::string(e.what()) + ": left out, as tf2 leaves it out");
        }
      }
    }
  }
  return tree;
}

std::string ReadPoses(const Topics& topics, const ChosenTopics& chosen, const TfTree& tf, std::int64_t first_stamp_ns,
                      SequenceData* seq) {
  const std::string& path = topics.bag().path();
  std::string body = chosen.pose_frame;
  if (!chosen.pose.empty() && chosen.pose != "/tf") {
    const std::string child = ReadOdometry(topics, chosen.pose, seq);
    if (body.empty()) body = child;
    if (body != child) {
      // Odometry of another frame: carry it to the body frame through the mount between them.
      const auto child_T_body = tf.Lookup(child, body, first_stamp_ns);
      if (!child_T_body) {
        throw Error(path + ": " + chosen.pose + " gives the pose of '" + child + "', and /tf_static has no transform from it to '" + body + "'");
      }
      for (auto& p : seq->poses) {
        const Eigen::Isometry3d w = (Eigen::Translation3d(p.world_p_body) * p.world_q_body) * *child_T_body;
        p = ToPose(p.timestamp_ns, w);
      }
    }
  }
  if (body.empty()) {
    for (const auto& name : BodyFrameNames()) {
      if (tf.Has(name)) {
        body = name;
        break;
      }
    }
  }
  if (chosen.pose == "/tf") {
    // Without Odometry, /tf is the pose when it moves the body frame (a SLAM or odometry node's
    // odom -> base_link); asked for, it must.
    const bool moving = !body.empty() && !tf.ChangeTimes(tf.RootOf(body), body).empty();
    if (!chosen.pose_from_tf_if_moving || moving) {
      if (body.empty()) throw Error(path + ": /tf has no base_link or base_footprint frame: name the body frame with --pose-frame");
      PosesFromTf(path, tf, body, seq);
    }
  }
  return body;
}

CameraMount FindCameraMount(const TfTree& tf, const std::string& body, const std::string& camera_frame,
                            std::int64_t stamp_ns, std::vector<std::string>* notes) {
  CameraMount out;
  out.body_T_optical = ForwardLookingMount();
  std::optional<Eigen::Isometry3d> mount;
  if (!body.empty() && !camera_frame.empty()) mount = tf.Lookup(body, camera_frame, stamp_ns);
  // Without a mount the body frame is made up around the camera: other mounts (the IMU's) are
  // then read relative to the camera frame and carried through the assumed mount.
  out.frame = body;
  if (mount) {
    out.body_T_optical = *mount;
    out.from_tf = true;
  } else {
    out.frame = camera_frame;
    notes->push_back("no transform from the body frame" + (body.empty() ? std::string() : " '" + body + "'") +
                     " to the camera frame '" + camera_frame +
                     "' in /tf_static or /tf: the left camera is taken at the body origin, looking along body x "
                     "(the dominant ground plane and the IMU still level each frame)");
  }
  return out;
}

void SetImuMount(const TfTree& tf, const CameraMount& mount, const std::string& body, const std::string& imu_frame,
                 std::int64_t stamp_ns, SequenceData* seq) {
  std::optional<Eigen::Isometry3d> imu_mount;
  bool relative_to_camera = !mount.from_tf;
  if (!imu_frame.empty()) imu_mount = tf.Lookup(mount.frame, imu_frame, stamp_ns);
  if (!imu_mount && !mount.from_tf && !body.empty() && !imu_frame.empty()) {
    imu_mount = tf.Lookup(body, imu_frame, stamp_ns);  // a body frame /tf knows
    relative_to_camera = false;
  }
  if (imu_mount) {
    seq->body_T_imu = relative_to_camera ? mount.body_T_optical * *imu_mount : *imu_mount;
  } else {
    seq->notes.push_back("no transform from the body frame to the IMU frame '" + imu_frame +
                         "': the IMU axes are taken as the body axes (x forward, y left, z up)");
  }
}

}  // namespace ssta::internal
