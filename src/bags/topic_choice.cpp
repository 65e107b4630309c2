#include "bags/topic_choice.h"

#include <algorithm>
#include <iomanip>
#include <sstream>
#include <tuple>

namespace ssta::internal {
namespace {

/// The topic names a stereo driver gives its two cameras differ in one of these words.
const std::vector<std::pair<std::string, std::string>>& SideWords() {
  static const std::vector<std::pair<std::string, std::string>> words = {
      {"left", "right"}, {"cam0", "cam1"}, {"infra1", "infra2"}, {"camera_0", "camera_1"}, {"image_0", "image_1"}};
  return words;
}

/// `topic` with its one left word swapped for the right one ("" when it has none).
std::string RightOf(const std::string& topic) {
  for (const auto& [l, r] : SideWords()) {
    const auto at = topic.rfind(l);
    if (at != std::string::npos) return topic.substr(0, at) + r + topic.substr(at + l.size());
  }
  return "";
}

std::string LeftOf(const std::string& topic) {
  for (const auto& [l, r] : SideWords()) {
    const auto at = topic.rfind(r);
    if (at != std::string::npos) return topic.substr(0, at) + l + topic.substr(at + r.size());
  }
  return "";
}

std::string Join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& s : items) out += (out.empty() ? "" : ", ") + s;
  return out;
}

}  // namespace

std::string PlainType(const std::string& type) {
  std::string out = type;
  const auto at = out.find("/msg/");
  if (at != std::string::npos) out.erase(at, 4);
  return out;
}

Topics::Topics(const BagReader& bag) : bag_(bag) {
  for (std::size_t i = 0; i < bag.connections().size(); ++i) index_[bag.connections()[i].topic] = static_cast<int>(i);
}

std::string Topics::Type(const std::string& topic) const {
  return PlainType(bag_.connections()[static_cast<std::size_t>(Index(topic))].type);
}

RosEncoding Topics::Encoding(const std::string& topic) const {
  return bag_.connections()[static_cast<std::size_t>(Index(topic))].encoding == "cdr" ? RosEncoding::kCdr
                                                                                        : RosEncoding::kRos1;
}

std::vector<std::string> Topics::OfType(const std::string& type) const {
  std::vector<std::string> out;
  for (const auto& [topic, i] : index_) {
    if (PlainType(bag_.connections()[static_cast<std::size_t>(i)].type) == type) out.push_back(topic);
  }
  return out;
}

void Topics::Require(const std::string& topic, const std::vector<std::string>& types, const std::string& option) const {
  if (!Has(topic)) throw Error(bag_.path() + ": " + option + " " + topic + ": no such topic in the bag");
  if (std::find(types.begin(), types.end(), Type(topic)) == types.end()) {
    throw Error(bag_.path() + ": " + option + " " + topic + " is " + Type(topic) + ", expected " + Join(types));
  }
}

namespace {

/// Every Image and CompressedImage topic, sorted.
std::vector<std::string> ImageTopics(const Topics& topics) {
  std::vector<std::string> images = topics.OfType("sensor_msgs/Image");
  const auto compressed = topics.OfType("sensor_msgs/CompressedImage");
  images.insert(images.end(), compressed.begin(), compressed.end());
  std::sort(images.begin(), images.end());
  return images;
}

std::pair<std::string, std::string> ChooseImagePair(const Topics& topics, const BagTopics& asked, const std::string& path) {
  const std::vector<std::string> images = ImageTopics(topics);
  if (images.empty()) {
    throw Error(path + ": the bag has no image topics (sensor_msgs/Image or CompressedImage): it holds no camera "
                "recording");
  }
  if (!asked.left.empty() || !asked.right.empty()) {
    for (const auto& [topic, option] : {std::pair<const std::string*, const char*>{&asked.left, "--left-topic"},
                                        {&asked.right, "--right-topic"}}) {
      if (!topic->empty() && !topics.Has(*topic)) {
        throw Error(path + ": " + option + " " + *topic + ": no such topic in the bag (image topics: " + Join(images) + ")");
      }
    }
    std::string left = asked.left.empty() ? LeftOf(asked.right) : asked.left;
    std::string right = asked.right.empty() ? RightOf(asked.left) : asked.right;
    if (left.empty() || right.empty()) {
      throw Error(path + ": cannot tell the other camera's topic from " + (left.empty() ? right : left) +
                  ": give both --left-topic and --right-topic");
    }
    topics.Require(left, {"sensor_msgs/Image", "sensor_msgs/CompressedImage"}, "--left-topic");
    topics.Require(right, {"sensor_msgs/Image", "sensor_msgs/CompressedImage"}, "--right-topic");
    return {left, right};
  }
  std::vector<std::pair<std::string, std::string>> pairs;
  for (const auto& t : images) {
    const std::string r = RightOf(t);
    if (!r.empty() && topics.Has(r) && topics.Type(r) == topics.Type(t)) pairs.emplace_back(t, r);
  }
  if (pairs.size() == 1) return pairs.front();
  if (pairs.empty()) {
    throw Error(path + ": no stereo pair of image topics found (image topics: " + Join(images) +
                "); give --left-topic and --right-topic");
  }
  std::vector<std::string> names;
  for (const auto& [l, r] : pairs) names.push_back(l + " + " + r);
  throw Error(path + ": " + std::to_string(pairs.size()) + " stereo pairs of image topics (" + Join(names) +
              "): choose one with --left-topic and --right-topic");
}

/// The CameraInfo beside an image topic: `/ns/image_raw[/compressed]` -> `/ns/camera_info`.
std::string InfoTopicFor(const std::string& image_topic, const Topics& topics, const std::string& path) {
  std::string base = image_topic;
  for (const std::string suffix : {"/compressed", "/theora"}) {
    if (base.size() > suffix.size() && base.compare(base.size() - suffix.size(), suffix.size(), suffix) == 0) {
      base.erase(base.size() - suffix.size());
    }
  }
  for (std::string ns = base; !ns.empty();) {
    const auto slash = ns.rfind('/');
    ns = slash == std::string::npos ? "" : ns.substr(0, slash);
    const std::string candidate = ns + "/camera_info";
    if (topics.Has(candidate) && topics.Type(candidate) == "sensor_msgs/CameraInfo") return candidate;
  }
  throw Error(path + ": no sensor_msgs/CameraInfo beside " + image_topic +
              " (looked for camera_info in its namespace and the ones above): the calibration comes from it");
}

std::string ChooseSingle(const Topics& topics, const std::string& asked, const std::string& type,
                         const std::string& option, const std::string& path) {
  if (asked == "none") return "";
  if (!asked.empty()) {
    topics.Require(asked, {type}, option);
    return asked;
  }
  const auto found = topics.OfType(type);
  if (found.size() <= 1) return found.empty() ? "" : found.front();
  throw Error(path + ": " + std::to_string(found.size()) + " " + type + " topics (" + Join(found) +
              "): choose one with " + option + " (or none)");
}

}  // namespace

ChosenTopics ChooseTopics(const BagReader& bag, const BagTopics& asked) {
  const Topics topics(bag);
  ChosenTopics out;
  std::tie(out.left, out.right) = ChooseImagePair(topics, asked, bag.path());
  out.left_info = InfoTopicFor(out.left, topics, bag.path());
  out.right_info = InfoTopicFor(out.right, topics, bag.path());
  if (out.left_info == out.right_info) {
    throw Error(bag.path() + ": " + out.left + " and " + out.right + " share the CameraInfo " + out.left_info +
                ": a stereo pair needs one per camera");
  }
  out.imu = ChooseSingle(topics, asked.imu, "sensor_msgs/Imu", "--imu-topic", bag.path());
  out.pose_frame = asked.pose_frame;
  if (asked.pose == "none") return out;
  if (asked.pose == "/tf" || asked.pose == "tf") {
    if (!topics.Has("/tf")) throw Error(bag.path() + ": --pose-topic /tf: the bag has no /tf topic");
    out.pose = "/tf";
  } else {
    out.pose = ChooseSingle(topics, asked.pose, "nav_msgs/Odometry", "--pose-topic", bag.path());
    if (out.pose.empty() && topics.Has("/tf")) {
      out.pose = "/tf";
      out.pose_from_tf_if_moving = asked.pose.empty() && asked.pose_frame.empty();
    }
  }
  return out;
}

std::string DescribeTopics(const BagReader& bag) {
  std::ostringstream out;
  out << bag.path() << ": " << bag.format() << " bag, " << bag.connections().size() << " topics\n";
  std::size_t width = 5;
  for (const auto& c : bag.connections()) width = std::max(width, c.topic.size());
  out << "  " << std::left << std::setw(static_cast<int>(width)) << "topic" << "  " << std::setw(30) << "type"
      << std::right << std::setw(9) << "messages" << std::setw(10) << "rate Hz" << "\n";
  for (std::size_t i = 0; i < bag.connections().size(); ++i) {
    const auto& c = bag.connections()[i];
    const auto refs = bag.List({static_cast<int>(i)});
    double rate = 0.0;
    if (refs.size() >= 2 && refs.back().log_time_ns > refs.front().log_time_ns) {
      rate = static_cast<double>(refs.size() - 1) / (1e-9 * static_cast<double>(refs.back().log_time_ns - refs.front().log_time_ns));
    }
    out << "  " << std::left << std::setw(static_cast<int>(width)) << c.topic << "  " << std::setw(30) << PlainType(c.type)
        << std::right << std::setw(9) << refs.size() << std::setw(10) << std::fixed << std::setprecision(1) << rate << "\n";
    out.unsetf(std::ios::fixed);
  }
  return out.str();
}

}  // namespace ssta::internal
