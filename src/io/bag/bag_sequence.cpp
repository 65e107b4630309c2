// A ROS bag as a stereo sequence: which topics, the calibration from CameraInfo, the mounts and
// poses from /tf and Odometry, IMU samples, frames paired by header stamp, images decoded (and
// rectified when raw) as they are read.

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "bag_reader.h"
#include "ros_messages.h"
#include "ssta/core/error.h"
#include "ssta/io/sequence.h"
#include "tf_tree.h"
#include "io/text_parsers.h"

namespace fs = std::filesystem;

namespace ssta {
namespace internal {
namespace {

/// "sensor_msgs/msg/Image" (ROS 2) and "sensor_msgs/Image" (ROS 1) are the same type.
std::string PlainType(const std::string& type) {
  std::string out = type;
  const auto at = out.find("/msg/");
  if (at != std::string::npos) out.erase(at, 4);
  return out;
}

RosEncoding EncodingOf(const BagConnection& c) { return c.encoding == "cdr" ? RosEncoding::kCdr : RosEncoding::kRos1; }


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

/// A bag's connections by topic, with the checks every choice of topic needs.
class Topics {
 public:
  explicit Topics(const BagReader& bag) : bag_(bag) {
    for (std::size_t i = 0; i < bag.connections().size(); ++i) index_[bag.connections()[i].topic] = static_cast<int>(i);
  }
  bool Has(const std::string& topic) const { return index_.count(topic) > 0; }
  int Index(const std::string& topic) const { return index_.at(topic); }
  std::string Type(const std::string& topic) const { return PlainType(bag_.connections()[static_cast<std::size_t>(Index(topic))].type); }
  RosEncoding Encoding(const std::string& topic) const { return EncodingOf(bag_.connections()[static_cast<std::size_t>(Index(topic))]); }
  std::vector<std::string> OfType(const std::string& type) const {
    std::vector<std::string> out;
    for (const auto& [topic, i] : index_) {
      if (PlainType(bag_.connections()[static_cast<std::size_t>(i)].type) == type) out.push_back(topic);
    }
    return out;
  }
  /// Checks that `topic` (given with `option`) exists with one of `types`.
  void Require(const std::string& topic, const std::vector<std::string>& types, const std::string& option) const {
    if (!Has(topic)) throw Error(bag_.path() + ": " + option + " " + topic + ": no such topic in the bag");
    if (std::find(types.begin(), types.end(), Type(topic)) == types.end()) {
      throw Error(bag_.path() + ": " + option + " " + topic + " is " + Type(topic) + ", expected " + Join(types));
    }
  }

 private:
  const BagReader& bag_;
  std::map<std::string, int> index_;
};

/// The topics a bag sequence is read from, after the automatic choice.
struct ChosenTopics {
  std::string left, right, left_info, right_info, imu, pose;
  std::string pose_frame;
  /// `pose` is "/tf" because the bag has no Odometry: used when /tf moves the body frame.
  bool pose_from_tf_if_moving = false;
};

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

/// The first message on `topic`, decoded with `decode`.
template <typename Decode>
auto FirstMessage(const BagReader& bag, const Topics& topics, const std::string& topic, Decode decode) {
  const auto refs = bag.List({topics.Index(topic)});
  if (refs.empty()) throw Error(bag.path() + ": " + topic + " holds no messages");
  return decode(bag.Read(refs.front()), topics.Encoding(topic), bag.path() + ": " + topic);
}

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

/// One camera's rectification from its CameraInfo, as ROS's image_proc does it: the raw image
/// through K and D, rotated by R, reprojected with P. Used only for the distortion models the
/// Rectifier does not take (RectifierTakes); the others reach the pipeline's Rectifier raw.
struct CameraModel {
  RosCameraInfo info;
  bool remap = false;  ///< the images are raw: rectify them with `map1`, `map2`
  cv::Mat map1, map2;
};

bool AllZero(const std::vector<double>& v) { return std::all_of(v.begin(), v.end(), [](double d) { return d == 0.0; }); }

/// R as recorded, or identity for the all-zero R of a driver that leaves it unset.
Eigen::Matrix3d RectificationRotation(const RosCameraInfo& info) {
  if (std::all_of(info.r.begin(), info.r.end(), [](double v) { return v == 0.0; })) return Eigen::Matrix3d::Identity();
  Eigen::Matrix3d r;
  for (int i = 0; i < 9; ++i) r(i / 3, i % 3) = info.r[static_cast<std::size_t>(i)];
  return r;
}

/// Whether a raw image differs from the rectified one CameraInfo describes: distortion, a
/// rotation R, or P's intrinsics other than K's.
bool NeedsRectification(const RosCameraInfo& info) {
  const bool distorted = !AllZero(info.d);
  const bool rotated = !RectificationRotation(info).isIdentity(1e-12);
  bool k_is_p = true;
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 3; ++col) {
      k_is_p &= std::abs(info.k[static_cast<std::size_t>(3 * row + col)] - info.p[static_cast<std::size_t>(4 * row + col)]) < 1e-9;
    }
  }
  return distorted || rotated || !k_is_p;
}

/// Whether SSTA's Rectifier (CameraCalibration: pinhole K without skew, radial-tangential k1 k2
/// p1 p2) describes the raw camera: plumb_bob (or no model) whose further coefficients are 0.
bool RectifierTakes(const RosCameraInfo& info) {
  const std::string& m = info.distortion_model;
  if (!(m == "plumb_bob" || m == "rational_polynomial" || m.empty() || m == "Brown Conrady")) return false;
  const std::size_t n = info.d.size();
  if (n != 0 && n != 4 && n != 5 && n != 8 && n != 12 && n != 14) return false;  // MakeCameraModel says why
  for (std::size_t i = 4; i < info.d.size(); ++i) {
    if (info.d[i] != 0.0) return false;
  }
  return info.k[0] > 0 && info.k[4] > 0 && info.k[1] == 0.0 && info.k[3] == 0.0 && info.k[6] == 0.0 &&
         info.k[7] == 0.0 && info.k[8] == 1.0;
}

CameraModel MakeCameraModel(const RosCameraInfo& info, bool remap, const std::string& where) {
  if (info.width == 0 || info.height == 0) throw Error(where + ": the image size is 0 (an uncalibrated camera?)");
  if (!(info.p[0] > 0 && info.p[5] > 0)) {
    throw Error(where + ": P has no focal length (P[0] = " + std::to_string(info.p[0]) +
                "): the camera is not calibrated");
  }
  CameraModel model;
  model.info = info;
  model.remap = remap;
  if (!model.remap) return model;
  if (!(info.k[0] > 0 && info.k[4] > 0)) throw Error(where + ": K has no focal length: the camera is not calibrated");
  const bool all_zero_r = std::all_of(info.r.begin(), info.r.end(), [](double v) { return v == 0.0; });
  const cv::Mat k(3, 3, CV_64F, const_cast<double*>(info.k.data()));
  const cv::Mat r = all_zero_r ? cv::Mat::eye(3, 3, CV_64F) : cv::Mat(3, 3, CV_64F, const_cast<double*>(info.r.data()));
  const cv::Mat p(3, 4, CV_64F, const_cast<double*>(info.p.data()));
  const cv::Size size(static_cast<int>(info.width), static_cast<int>(info.height));
  const std::string& m = info.distortion_model;
  if (m == "equidistant" || m == "fisheye") {
    if (info.d.size() != 4) throw Error(where + ": the equidistant model needs 4 coefficients in D");
    cv::fisheye::initUndistortRectifyMap(k, cv::Mat(info.d), r, p.colRange(0, 3), size, CV_16SC2, model.map1, model.map2);
  } else if (m == "plumb_bob" || m == "rational_polynomial" || m.empty() || (m == "Brown Conrady" && info.d.size() == 5)) {
    const std::size_t n = info.d.size();
    if (n != 0 && n != 4 && n != 5 && n != 8 && n != 12 && n != 14) {
      throw Error(where + ": D has " + std::to_string(n) + " coefficients; OpenCV takes 4, 5, 8, 12 or 14");
    }
    cv::initUndistortRectifyMap(k, cv::Mat(info.d), r, p, size, CV_16SC2, model.map1, model.map2);
  } else {
    throw Error(where + ": distortion model '" + m +
                "' is not one SSTA rectifies (plumb_bob, rational_polynomial, equidistant)");
  }
  return model;
}

/// The raw camera as the Rectifier takes it: K and the first four coefficients of D.
CameraCalibration RawCamera(const RosCameraInfo& info, double rate_hz) {
  CameraCalibration c;
  c.width = static_cast<int>(info.width);
  c.height = static_cast<int>(info.height);
  c.fu = info.k[0];
  c.fv = info.k[4];
  c.cu = info.k[2];
  c.cv = info.k[5];
  for (std::size_t i = 0; i < 4 && i < info.d.size(); ++i) c.distortion[i] = info.d[i];
  c.rate_hz = rate_hz;
  return c;
}

/// The rectified camera the sequence's calibration describes (no distortion, intrinsics P).
CameraCalibration RectifiedCamera(const RosCameraInfo& info, double rate_hz) {
  CameraCalibration c;
  c.width = static_cast<int>(info.width);
  c.height = static_cast<int>(info.height);
  c.fu = info.p[0];
  c.fv = info.p[5];
  c.cu = info.p[2];
  c.cv = info.p[6];
  c.rate_hz = rate_hz;
  return c;
}

/// Converts a decoded image message to 8-bit grey.
cv::Mat GreyFromImage(const RosImage& m, const std::string& where) {
  struct Layout {
    int type;
    int conversion;  // -1: none
  };
  static const std::map<std::string, Layout> layouts = {
      {"mono8", {CV_8UC1, -1}},         {"8UC1", {CV_8UC1, -1}},
      {"mono16", {CV_16UC1, -1}},       {"16UC1", {CV_16UC1, -1}},
      {"rgb8", {CV_8UC3, cv::COLOR_RGB2GRAY}},    {"bgr8", {CV_8UC3, cv::COLOR_BGR2GRAY}},
      {"rgba8", {CV_8UC4, cv::COLOR_RGBA2GRAY}},  {"bgra8", {CV_8UC4, cv::COLOR_BGRA2GRAY}},
      // ROS names a Bayer pattern by its first row, OpenCV by the second row's middle pair.
      {"bayer_rggb8", {CV_8UC1, cv::COLOR_BayerBG2GRAY}}, {"bayer_bggr8", {CV_8UC1, cv::COLOR_BayerRG2GRAY}},
      {"bayer_gbrg8", {CV_8UC1, cv::COLOR_BayerGR2GRAY}}, {"bayer_grbg8", {CV_8UC1, cv::COLOR_BayerGB2GRAY}},
  };
  const auto layout = layouts.find(m.encoding);
  if (layout == layouts.end()) {
    throw Error(where + ": image encoding '" + m.encoding +
                "' is not read (mono8, mono16, rgb8, bgr8, rgba8, bgra8, bayer_*8)");
  }
  const int type = layout->second.type;
  const std::size_t row_bytes = static_cast<std::size_t>(m.width) * static_cast<std::size_t>(CV_ELEM_SIZE(type));
  if (m.width == 0 || m.height == 0 || m.step < row_bytes ||
      static_cast<std::uint64_t>(m.step) * m.height > m.data.size()) {
    throw Error(where + ": image data (" + std::to_string(m.data.size()) + " bytes) does not hold " +
                std::to_string(m.width) + "x" + std::to_string(m.height) + " " + m.encoding + " pixels with step " +
                std::to_string(m.step));
  }
  cv::Mat raw(static_cast<int>(m.height), static_cast<int>(m.width), type, const_cast<std::uint8_t*>(m.data.data()), m.step);
  cv::Mat grey;
  if (type == CV_16UC1) {
    cv::Mat native = raw;
    if (m.big_endian) {
      native = raw.clone();
      for (int v = 0; v < native.rows; ++v) {
        auto* row = native.ptr<std::uint16_t>(v);
        for (int u = 0; u < native.cols; ++u) row[u] = static_cast<std::uint16_t>((row[u] >> 8) | (row[u] << 8));
      }
    }
    native.convertTo(grey, CV_8U, 1.0 / 256.0);
  } else if (layout->second.conversion >= 0) {
    cv::cvtColor(raw, grey, layout->second.conversion);
  } else {
    grey = raw.clone();
  }
  return grey;
}

ImageU8 ToImage(const cv::Mat& grey) {
  ImageU8 image(grey.cols, grey.rows);
  for (int v = 0; v < grey.rows; ++v) std::copy_n(grey.ptr<std::uint8_t>(v), grey.cols, &image(v, 0));
  return image;
}

cv::Mat GreyFromCompressed(const RosCompressedImage& m, const std::string& where) {
  if (m.format.find("compressedDepth") != std::string::npos) throw Error(where + ": a compressed depth image, not a camera image");
  // image_transport writes "bayer_rggb8; png compressed ...": the PNG holds the mosaic, which
  // decoding as grey would pass on undemosaiced.
  if (m.format.rfind("bayer", 0) == 0) {
    throw Error(where + ": a compressed Bayer mosaic (" + m.format + ") is not read; record the raw Image or a debayered topic");
  }
  cv::Mat grey;
  if (!m.data.empty()) {
    const cv::Mat buffer(1, static_cast<int>(m.data.size()), CV_8UC1, const_cast<std::uint8_t*>(m.data.data()));
    grey = cv::imdecode(buffer, cv::IMREAD_GRAYSCALE);
  }
  if (grey.empty()) throw Error(where + ": the compressed image (" + m.format + ") cannot be decoded");
  return grey;
}

/// Reads frames from the bag as the run asks for them.
class BagImageSource final : public StereoImageSource {
 public:
  struct Pair {
    BagMessageRef left, right;
  };

  BagImageSource(std::shared_ptr<const BagReader> bag, std::array<RosEncoding, 2> encodings, std::array<bool, 2> compressed, std::array<CameraModel, 2> cameras,
                 std::vector<Pair> pairs)
      : bag_(std::move(bag)),
        encodings_(encodings),
        compressed_(compressed),
        cameras_(std::move(cameras)),
        pairs_(std::move(pairs)) {}

  StereoImages Read(const StereoFrame& frame) const override {
    SSTA_CHECK(frame.message_index >= 0 && static_cast<std::size_t>(frame.message_index) < pairs_.size(),
               "a frame from another sequence");
    const Pair& pair = pairs_[static_cast<std::size_t>(frame.message_index)];
    StereoImages out;
    out.left = ReadOne(pair.left, 0, frame.left_path);
    out.right = ReadOne(pair.right, 1, frame.right_path);
    return out;
  }

  ImageU8 ReadOne(const BagMessageRef& ref, int side, const std::string& where) const {
    const auto s = static_cast<std::size_t>(side);
    const std::vector<std::uint8_t> bytes = bag_->Read(ref);
    cv::Mat grey;
    if (compressed_[s]) {
      grey = GreyFromCompressed(DecodeCompressedImage(bytes, encodings_[s], where), where);
    } else {
      grey = GreyFromImage(DecodeImage(bytes, encodings_[s], where), where);
    }
    const CameraModel& camera = cameras_[s];
    if (grey.cols != static_cast<int>(camera.info.width) || grey.rows != static_cast<int>(camera.info.height)) {
      throw Error(where + ": image is " + std::to_string(grey.cols) + "x" + std::to_string(grey.rows) +
                  " px, its CameraInfo says " + std::to_string(camera.info.width) + "x" +
                  std::to_string(camera.info.height));
    }
    if (camera.remap) {
      cv::Mat rectified;
      cv::remap(grey, rectified, camera.map1, camera.map2, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0));
      grey = rectified;
    }
    return ToImage(grey);
  }

 private:
  std::shared_ptr<const BagReader> bag_;
  std::array<RosEncoding, 2> encodings_;
  std::array<bool, 2> compressed_;
  std::array<CameraModel, 2> cameras_;
  std::vector<Pair> pairs_;
};

struct Stamped {
  std::int64_t stamp_ns;
  BagMessageRef ref;
};

/// Header stamps of every message on an image topic (reads each message once; keeps none).
std::vector<Stamped> ImageStamps(const BagReader& bag, const Topics& topics, const std::string& topic) {
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

/// Every transform on /tf_static and /tf. A transform whose rotation is not a
/// quaternion (a misconfigured static_transform_publisher's 0 0 0 0) is left out with a note, as
/// tf2 ignores it: it breaks only the chains through its link, which then report their absence.
TfTree ReadTf(const BagReader& bag, const Topics& topics, std::vector<std::string>* notes) {
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

void ReadImu(const BagReader& bag, const Topics& topics, const std::string& topic, SequenceData* seq,
             std::string* imu_frame) {
  const RosEncoding encoding = topics.Encoding(topic);
  const std::string where = bag.path() + ": " + topic;
  for (const BagMessageRef& ref : bag.List({topics.Index(topic)})) {
    const RosImu m = DecodeImu(bag.Read(ref), encoding, where);
    if (imu_frame->empty()) *imu_frame = m.header.frame_id;
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
std::string ReadOdometry(const BagReader& bag, const Topics& topics, const std::string& topic, SequenceData* seq) {
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

std::string TruncationText(const std::string& path, const std::string& what, std::int64_t last_ns) {
  if (last_ns < 0) return path + ": truncated: " + what + ", before any complete message";
  std::ostringstream t;
  t << last_ns / 1'000'000'000 << "." << std::setw(9) << std::setfill('0') << last_ns % 1'000'000'000;
  return path + ": truncated: " + what + "; the last complete message was logged at " + t.str() + " s";
}

ImageU8 GreyImage(const RosImage& image, const std::string& where) { return ToImage(GreyFromImage(image, where)); }

ImageU8 GreyImage(const RosCompressedImage& image, const std::string& where) {
  return ToImage(GreyFromCompressed(image, where));
}

std::unique_ptr<BagReader> OpenBag(const std::string& path) {
  if (!fs::exists(path)) throw Error(path + ": bag not found");
  std::error_code ec;
  if (fs::is_directory(path, ec) || fs::path(path).extension() == ".mcap" || fs::path(path).extension() == ".db3") {
    return OpenRos2Bag(path);
  }
  return OpenRos1Bag(path);
}

/// Builds the sequence data of a bag; `notes` collects what was assumed. Used by OpenBag and,
/// for a report, by DescribeBag.
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
  ChosenTopics chosen = ChooseTopics(*bag, asked);
  if (chosen_out) *chosen_out = chosen;

  // Calibration: the first CameraInfo of each camera (drivers repeat the same one).
  const auto decode_info = [](const std::vector<std::uint8_t>& b, RosEncoding e, const std::string& w) {
    return DecodeCameraInfo(b, e, w);
  };
  const RosCameraInfo left_info = FirstMessage(*bag, topics, chosen.left_info, decode_info);
  const RosCameraInfo right_info = FirstMessage(*bag, topics, chosen.right_info, decode_info);
  // image_proc's outputs are image_rect, image_rect_color, image_rect_raw...: the topic's own
  // name, not a namespace that happens to hold "rect".
  const auto rectified_topic = [](std::string t) {
    if (t.size() > 11 && t.compare(t.size() - 11, 11, "/compressed") == 0) t.erase(t.size() - 11);
    return t.substr(t.rfind('/') + 1).rfind("image_rect", 0) == 0;
  };
  // Raw images go to the pipeline raw, with K, D and the pair's relative pose from R and P, so
  // that the Rectifier rectifies and crops them as it does a folder's: the same recording gives
  // the same images in any container. Only distortion models it does not take are rectified
  // here, with P, as image_proc does.
  const std::array<bool, 2> needs = {!rectified_topic(chosen.left) && NeedsRectification(left_info),
                                     !rectified_topic(chosen.right) && NeedsRectification(right_info)};
  const bool raw_pair = (needs[0] || needs[1]) && !rectified_topic(chosen.left) && !rectified_topic(chosen.right) &&
                        RectifierTakes(left_info) && RectifierTakes(right_info);
  std::array<CameraModel, 2> cameras = {
      MakeCameraModel(left_info, needs[0] && !raw_pair, path + ": " + chosen.left_info),
      MakeCameraModel(right_info, needs[1] && !raw_pair, path + ": " + chosen.right_info)};
  if (left_info.width != right_info.width || left_info.height != right_info.height) {
    throw Error(path + ": " + chosen.left_info + " and " + chosen.right_info + " give different image sizes");
  }
  // P of the right camera holds -fx * baseline (ROS's stereo convention).
  const double baseline_m = -right_info.p[3] / right_info.p[0];
  if (!(std::abs(baseline_m) > 1e-6)) {
    throw Error(path + ": " + chosen.right_info +
                ": P[3] is 0: not a stereo calibration (ROS puts -fx * baseline there; calibrate the pair with "
                "camera_calibration's stereo mode or ssta calibrate-stereo)");
  }

  const std::vector<Stamped> left = ImageStamps(*bag, topics, chosen.left);
  const std::vector<Stamped> right = ImageStamps(*bag, topics, chosen.right);
  if (left.empty()) throw Error(path + ": " + chosen.left + " holds no images");
  if (right.empty()) throw Error(path + ": " + chosen.right + " holds no images");
  std::vector<BagImageSource::Pair> pairs;
  PairFrames(path, chosen, left, right, &seq, &pairs);

  std::string imu_frame;
  if (!chosen.imu.empty()) ReadImu(*bag, topics, chosen.imu, &seq, &imu_frame);

  const TfTree tf = ReadTf(*bag, topics, &seq.notes);
  std::string body = chosen.pose_frame;
  if (!chosen.pose.empty() && chosen.pose != "/tf") {
    const std::string child = ReadOdometry(*bag, topics, chosen.pose, &seq);
    if (body.empty()) body = child;
    if (body != child) {
      // Odometry of another frame: carry it to the body frame through the mount between them.
      const auto child_T_body = tf.Lookup(child, body, left.front().stamp_ns);
      if (!child_T_body) {
        throw Error(path + ": " + chosen.pose + " gives the pose of '" + child + "', and /tf_static has no transform from it to '" + body + "'");
      }
      for (auto& p : seq.poses) {
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
      PosesFromTf(path, tf, body, &seq);
    }
  }

  // Mounts: each camera's optical frame (the rectified one) and the IMU in the body frame.
  const std::string& camera_frame = left_info.header.frame_id;
  Eigen::Isometry3d body_T_optical = ForwardLookingMount();
  std::optional<Eigen::Isometry3d> mount;
  if (!body.empty() && !camera_frame.empty()) mount = tf.Lookup(body, camera_frame, left.front().stamp_ns);
  // Without a mount the body frame is made up around the camera: other mounts (the IMU's) are
  // then read relative to the camera frame and carried through the assumed mount.
  std::string mount_frame = body;
  if (mount) {
    body_T_optical = *mount;
  } else {
    mount_frame = camera_frame;
    seq.notes.push_back("no transform from the body frame" + (body.empty() ? std::string() : " '" + body + "'") +
                        " to the camera frame '" + camera_frame +
                        "' in /tf_static or /tf: the left camera is taken at the body origin, looking along body x "
                        "(the dominant ground plane and the IMU still level each frame)");
  }
  // The optical frame in /tf is the raw camera's; R turns it into the rectified one, and the
  // right rectified camera sits at +baseline along the left rectified x.
  const Eigen::Matrix3d left_R = RectificationRotation(left_info);
  const Eigen::Matrix3d right_R = RectificationRotation(right_info);
  if (raw_pair) {
    seq.calibration.left = RawCamera(left_info, RateHz(left));
    seq.calibration.right = RawCamera(right_info, RateHz(right));
    Eigen::Isometry3d left_T_right = Eigen::Isometry3d::Identity();
    left_T_right.linear() = left_R.transpose() * right_R;
    left_T_right.translation() = left_R.transpose() * Eigen::Vector3d(baseline_m, 0.0, 0.0);
    seq.calibration.left.body_T_camera = body_T_optical;
    seq.calibration.right.body_T_camera = body_T_optical * left_T_right;
  } else {
    Eigen::Isometry3d body_T_left = body_T_optical;
    body_T_left.linear() = body_T_optical.linear() * left_R.transpose();
    seq.calibration.left = RectifiedCamera(left_info, RateHz(left));
    seq.calibration.right = RectifiedCamera(right_info, RateHz(right));
    seq.calibration.left.body_T_camera = body_T_left;
    seq.calibration.right.body_T_camera = body_T_left * Eigen::Translation3d(baseline_m, 0.0, 0.0);
    if (cameras[0].remap || cameras[1].remap) {
      seq.notes.push_back("the '" + left_info.distortion_model + "' / '" + right_info.distortion_model +
                          "' distortion is rectified with CameraInfo's P as image_proc does, not by SSTA's "
                          "rectification: rectification.crop_to_common_area does not apply");
    }
  }
  std::string error;
  if (!seq.calibration.IsValid(&error)) throw Error(path + ": " + chosen.left_info + ", " + chosen.right_info + ": " + error);

  if (!seq.imu.empty()) {
    std::optional<Eigen::Isometry3d> imu_mount;
    bool relative_to_camera = !mount;
    if (!imu_frame.empty()) imu_mount = tf.Lookup(mount_frame, imu_frame, left.front().stamp_ns);
    if (!imu_mount && !mount && !body.empty() && !imu_frame.empty()) {
      imu_mount = tf.Lookup(body, imu_frame, left.front().stamp_ns);  // a body frame /tf knows
      relative_to_camera = false;
    }
    if (imu_mount) {
      seq.body_T_imu = relative_to_camera ? body_T_optical * *imu_mount : *imu_mount;
    } else {
      seq.notes.push_back("no transform from the body frame to the IMU frame '" + imu_frame +
                          "': the IMU axes are taken as the body axes (x forward, y left, z up)");
    }
  }
  if (seq.poses.empty()) {
    seq.notes.push_back("no poses (no Odometry topic, no /tf pose chosen): build-map needs --static, or a pose "
                        "topic (--pose-topic, --pose-frame)");
  }
  seq.image_source = std::make_shared<BagImageSource>(
      bag,
      std::array<RosEncoding, 2>{topics.Encoding(chosen.left), topics.Encoding(chosen.right)},
      std::array<bool, 2>{topics.Type(chosen.left) == "sensor_msgs/CompressedImage",
                          topics.Type(chosen.right) == "sensor_msgs/CompressedImage"},
      std::move(cameras), std::move(pairs));
  return seq;
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
