#include "bags/image_decoding.h"

#include <map>

#include <opencv2/imgproc.hpp>

#include "ssta/core/error.h"
#include "ssta/io/image_codec.h"

namespace ssta::internal {
namespace {

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

}  // namespace

ImageU8 GreyImage(const RosImage& image, const std::string& where) { return ToImage(GreyFromImage(image, where)); }

ImageU8 GreyImage(const RosCompressedImage& m, const std::string& where) {
  if (m.format.find("compressedDepth") != std::string::npos) throw Error(where + ": a compressed depth image, not a camera image");
  // image_transport writes "bayer_rggb8; png compressed ...": the PNG holds the mosaic, which
  // decoding as grey would pass on undemosaiced.
  if (m.format.rfind("bayer", 0) == 0) {
    throw Error(where + ": a compressed Bayer mosaic (" + m.format + ") is not read; record the raw Image or a debayered topic");
  }
  if (m.data.empty()) throw Error(where + ": the compressed image (" + m.format + ") is empty");
  return DecodeGrey(m.data.data(), m.data.size(), where + " (" + m.format + ")");
}

BagImageSource::BagImageSource(std::shared_ptr<const BagReader> bag, std::array<RosEncoding, 2> encodings,
                               std::array<bool, 2> compressed, std::array<CameraModel, 2> cameras,
                               std::vector<Pair> pairs)
    : bag_(std::move(bag)),
      encodings_(encodings),
      compressed_(compressed),
      cameras_(std::move(cameras)),
      pairs_(std::move(pairs)) {}

StereoImages BagImageSource::Read(const StereoFrame& frame) const {
  SSTA_CHECK(frame.message_index >= 0 && static_cast<std::size_t>(frame.message_index) < pairs_.size(),
             "a frame from another sequence");
  const Pair& pair = pairs_[static_cast<std::size_t>(frame.message_index)];
  StereoImages out;
  out.left = ReadOne(pair.left, 0, frame.left_path);
  out.right = ReadOne(pair.right, 1, frame.right_path);
  return out;
}

ImageU8 BagImageSource::ReadOne(const BagMessageRef& ref, int side, const std::string& where) const {
  const auto s = static_cast<std::size_t>(side);
  const std::vector<std::uint8_t> bytes = bag_->Read(ref);
  // A compressed image is decoded into `decoded` and seen through `grey` without a copy.
  ImageU8 decoded;
  cv::Mat grey;
  if (compressed_[s]) {
    decoded = GreyImage(DecodeCompressedImage(bytes, encodings_[s], where), where);
    grey = cv::Mat(decoded.height(), decoded.width(), CV_8UC1, decoded.data());
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
    return ToImage(rectified);
  }
  return decoded.empty() ? ToImage(grey) : decoded;
}

}  // namespace ssta::internal
