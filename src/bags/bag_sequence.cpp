// A ROS bag as a stereo sequence: the steps that make its SequenceData (topic_choice.h,
// camera_info.h, bag_poses.h, image_decoding.h), frames paired by header stamp, IMU samples, and
// the Sequence entry points for bags.

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "bags/bag_poses.h"
#include "bags/bag_reader.h"
#include "bags/camera_info.h"
#include "bags/image_decoding.h"
#include "bags/ros_messages.h"
#include "bags/topic_choice.h"
#include "ssta/bags/bag_sequence.h"
#include "ssta/core/error.h"
#include "ssta/io/sequence.h"

namespace fs = std::filesystem;

namespace ssta {
namespace internal {
namespace {

struct Stamped {
  std::int64_t stamp_ns;
  BagMessageRef ref;
};

/// Header stamps of every message on an image topic (reads each message once; keeps none).
std::vector<Stamped> ImageStamps(const Topics& topics, const std::string& topic) {
  const BagReader& bag = topics.bag();
  std::vector<Stamped> out;
  const RosEncoding encoding = topics.Encoding(topic);
  for (const BagMessageRef& ref : bag.List({topics.Index(topic)})) {
    const RosHeader h = DecodeHeader(bag.Read(ref), encoding, bag.path() + ": " + topic);
    // A driver that leaves the stamp at 0 is common; the recorder's time is then the best there is.
    out.push_back({h.stamp_ns != 0 ? h.stamp_ns : ref.log_time_ns, ref});
  }
  std::stable_sort(out.begin(), out.end(), [](const Stamped& a, const Stamped& b) { return a.stamp_ns < b.stamp_ns; });
  return out;
}

std::string MessageName(const std::string& path, const std::string& topic, std::int64_t stamp) {
  return path + ":" + topic + "@" + std::to_string(stamp);
}

double RateHz(const std::vector<Stamped>& stamps) {
  if (stamps.size() < 2) return 0.0;
  const double span = 1e-9 * static_cast<double>(stamps.back().stamp_ns - stamps.front().stamp_ns);
  return span > 0 ? static_cast<double>(stamps.size() - 1) / span : 0.0;
}

/// Pairs left and right frames as ASL sequences do; skips are reported.
void PairFrames(const std::string& path, const ChosenTopics& chosen, const std::vector<Stamped>& left,
                const std::vector<Stamped>& right, SequenceData* seq, std::vector<BagImageSource::Pair>* pairs) {
  const auto times = [](const std::vector<Stamped>& list) {
    std::vector<std::int64_t> out;
    for (const Stamped& s : list) out.push_back(s.stamp_ns);
    return out;
  };
  const std::vector<std::ptrdiff_t> paired = PairNearestWithin1Ms(times(left), times(right));
  std::vector<bool> right_used(right.size(), false);
  for (std::size_t i = 0; i < left.size(); ++i) {
    const Stamped& l = left[i];
    if (i > 0 && l.stamp_ns == left[i - 1].stamp_ns) {
      seq->skipped.push_back({l.stamp_ns, "left image with a duplicated stamp"});
      continue;
    }
    const auto j = static_cast<std::size_t>(paired[i]);
    if (paired[i] < 0 || right_used[j]) {
      seq->skipped.push_back({l.stamp_ns, "no " + chosen.right + " image within 1 ms"});
      continue;
    }
    right_used[j] = true;
    seq->frames.push_back({l.stamp_ns, MessageName(path, chosen.left, l.stamp_ns),
                           MessageName(path, chosen.right, right[j].stamp_ns), static_cast<std::int64_t>(pairs->size())});
    pairs->push_back({l.ref, right[j].ref});
  }
  for (std::size_t k = 0; k < right.size(); ++k) {
    if (!right_used[k]) seq->skipped.push_back({right[k].stamp_ns, chosen.right + " image without a left image within 1 ms"});
  }
  std::sort(seq->skipped.begin(), seq->skipped.end(),
            [](const SkippedFrame& a, const SkippedFrame& b) { return a.timestamp_ns < b.timestamp_ns; });
}

/// IMU samples from an Imu topic into `seq->imu`, sorted by stamp; returns their frame.
std::string ReadImu(const Topics& topics, const std::string& topic, SequenceData* seq) {
  const BagReader& bag = topics.bag();
  std::string imu_frame;
  const RosEncoding encoding = topics.Encoding(topic);
  const std::string where = bag.path() + ": " + topic;
  for (const BagMessageRef& ref : bag.List({topics.Index(topic)})) {
    const RosImu m = DecodeImu(bag.Read(ref), encoding, where);
    if (imu_frame.empty()) imu_frame = m.header.frame_id;
    ImuSample s;
    s.timestamp_ns = m.header.stamp_ns != 0 ? m.header.stamp_ns : ref.log_time_ns;
    s.angular_rate = Eigen::Vector3d(m.angular_velocity[0], m.angular_velocity[1], m.angular_velocity[2]);
    s.specific_force = Eigen::Vector3d(m.linear_acceleration[0], m.linear_acceleration[1], m.linear_acceleration[2]);
    seq->imu.push_back(s);
  }
  if (seq->imu.empty()) throw Error(where + ": no IMU messages (--imu-topic none if the platform has no IMU)");
  // Sensor stamps are what the frames are paired with; the log order may differ by jitter.
  std::stable_sort(seq->imu.begin(), seq->imu.end(),
                   [](const ImuSample& a, const ImuSample& b) { return a.timestamp_ns < b.timestamp_ns; });
  seq->imu.erase(std::unique(seq->imu.begin(), seq->imu.end(),
                             [](const ImuSample& a, const ImuSample& b) { return a.timestamp_ns == b.timestamp_ns; }),
                 seq->imu.end());
  seq->imu_path = bag.path() + ":" + topic;
  return imu_frame;
}

/// The image stamps of each camera, paired into `seq->frames` and the messages of each frame.
std::vector<BagImageSource::Pair> ReadFrames(const Topics& topics, const ChosenTopics& chosen, SequenceData* seq,
                                             std::vector<Stamped>* left, std::vector<Stamped>* right) {
  const std::string& path = topics.bag().path();
  *left = ImageStamps(topics, chosen.left);
  *right = ImageStamps(topics, chosen.right);
  if (left->empty()) throw Error(path + ": " + chosen.left + " holds no images");
  if (right->empty()) throw Error(path + ": " + chosen.right + " holds no images");
  std::vector<BagImageSource::Pair> pairs;
  PairFrames(path, chosen, *left, *right, seq, &pairs);
  return pairs;
}

/// Builds the sequence data of a bag; `chosen_out` (may be null) receives the topics it was read
/// from. Used by Sequence::OpenBag and, for a report, by DescribeBag.
SequenceData ReadBagSequence(const std::shared_ptr<const BagReader>& bag, const BagTopics& asked, ChosenTopics* chosen_out) {
  const std::string& path = bag->path();
  const Topics topics(*bag);
  SequenceData seq;
  seq.root = path;
  seq.format = bag->format();
  if (const std::string cut = bag->Truncation(); !cut.empty()) {
    if (!asked.allow_truncated) throw Error(cut + "; --allow-truncated reads the complete messages");
    seq.warnings.push_back(cut + ": only the complete messages were read (--allow-truncated)");
  }
  const ChosenTopics chosen = ChooseTopics(*bag, asked);
  if (chosen_out) *chosen_out = chosen;
  StereoCameraInfo info = ReadStereoCameraInfo(topics, chosen);

  std::vector<Stamped> left, right;
  std::vector<BagImageSource::Pair> pairs = ReadFrames(topics, chosen, &seq, &left, &right);
  const std::int64_t first_stamp_ns = left.front().stamp_ns;
  const std::string imu_frame = chosen.imu.empty() ? "" : ReadImu(topics, chosen.imu, &seq);
  const TfTree tf = ReadTf(topics, &seq.notes);
  const std::string body = ReadPoses(topics, chosen, tf, first_stamp_ns, &seq);

  // Mounts: each camera's optical frame (the rectified one) and the IMU in the body frame.
  const CameraMount mount = FindCameraMount(tf, body, info.left.header.frame_id, first_stamp_ns, &seq.notes);
  SetStereoCalibration(info, mount.body_T_optical, RateHz(left), RateHz(right), &seq);
  std::string error;
  if (!seq.calibration.IsValid(&error)) throw Error(path + ": " + chosen.left_info + ", " + chosen.right_info + ": " + error);
  if (!seq.imu.empty()) SetImuMount(tf, mount, body, imu_frame, first_stamp_ns, &seq);
  if (seq.poses.empty()) {
    seq.notes.push_back("no poses (no Odometry topic, no /tf pose chosen): build-map needs --static, or a pose "
                        "topic (--pose-topic, --pose-frame)");
  }
  seq.image_source = std::make_shared<BagImageSource>(
      bag,
      std::array<RosEncoding, 2>{topics.Encoding(chosen.left), topics.Encoding(chosen.right)},
      std::array<bool, 2>{topics.Type(chosen.left) == "sensor_msgs/CompressedImage",
                          topics.Type(chosen.right) == "sensor_msgs/CompressedImage"},
      std::move(info.cameras), std::move(pairs));
  return seq;
}

}  // namespace
}  // namespace internal

bool IsBagPath(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) return fs::exists(fs::path(path) / "metadata.yaml", ec);
  const std::string ext = fs::path(path).extension().string();
  if (ext == ".mcap" || ext == ".db3" || ext == ".bag") return true;
  std::ifstream in(path, std::ios::binary);
  char magic[13] = {};
  in.read(magic, 13);
  return in.gcount() == 13 && std::string(magic, 13) == "#ROSBAG V2.0\n";
}

Sequence Sequence::Open(const std::string& path, const BagTopics& topics) {
  if (IsBagPath(path)) return OpenBag(path, topics);
  for (const auto& [option, value] : {std::pair<const char*, const std::string*>{"--left-topic", &topics.left},
                                      {"--right-topic", &topics.right},
                                      {"--imu-topic", &topics.imu},
                                      {"--pose-topic", &topics.pose},
                                      {"--pose-frame", &topics.pose_frame}}) {
    if (!value->empty()) throw Error(path + ": " + option + " applies to ROS bags; this is not one (a .bag, .mcap, .db3 or rosbag2 folder)");
  }
  if (!fs::exists(path)) throw Error(path + ": sequence not found (a folder or a ROS bag)");
  if (!fs::is_directory(path)) {
    throw Error(path + ": not a sequence: neither a folder (ASL, KITTI raw) nor a ROS bag (.bag, .mcap, .db3, a "
                "rosbag2 folder)");
  }
  if (fs::is_directory(fs::path(path) / "image_00") && fs::is_directory(fs::path(path) / "oxts")) {
    return OpenKittiRaw(path);
  }
  return OpenAsl(path);
}

Sequence Sequence::OpenBag(const std::string& path, const BagTopics& topics) {
  std::shared_ptr<const internal::BagReader> bag = internal::OpenBag(path);
  return Sequence(internal::ReadBagSequence(bag, topics, nullptr));
}

BagDescription DescribeBag(const std::string& path, const BagTopics& topics) {
  std::shared_ptr<const internal::BagReader> bag = internal::OpenBag(path);
  BagDescription description;
  std::ostringstream out;
  out << internal::DescribeTopics(*bag);
  internal::ChosenTopics chosen;
  try {
    const Sequence seq(internal::ReadBagSequence(bag, topics, &chosen));
    const auto& c = seq.calibration();
    out << "as a stereo sequence:\n"
        << "  left   " << chosen.left << " (calibration " << chosen.left_info << ")\n"
        << "  right  " << chosen.right << " (calibration " << chosen.right_info << ")\n"
        << "  imu    " << (chosen.imu.empty() ? "none" : chosen.imu) << "\n"
        << "  poses  " << (seq.pose_path().empty() ? "none" : seq.pose_path()) << "\n"
        << "  camera: " << c.left.width << "x" << c.left.height << " px, f " << c.left.fu << " px, baseline "
        << c.LeftTRight().translation().norm() << " m, "
        << (c.IsRectified() ? "rectified" : "raw (rectified on read)") << "\n"
        << "  frames: " << seq.frames().size() << " paired, " << seq.skipped().size() << " skipped";
    if (!seq.frames().empty()) {
      out << ", " << 1e-9 * static_cast<double>(seq.frames().back().timestamp_ns - seq.frames().front().timestamp_ns)
          << " s";
    }
    out << "\n" << DescribeSkipped(seq.skipped());
    for (const auto& note : seq.notes()) out << "  note: " << note << "\n";
    for (const auto& warning : seq.warnings()) out << "  warning: " << warning << "\n";
    if (seq.frames().empty()) description.problem = path + ": no left and right images pair up: no frame to use";
  } catch (const Error& e) {
    description.problem = e.what();
  }
  if (!description.problem.empty()) out << "not usable as a stereo sequence: " << description.problem << "\n";
  description.text = out.str();
  return description;
}

}  // namespace ssta
