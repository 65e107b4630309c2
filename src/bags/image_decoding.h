#pragma once

// Private: image messages decoded to 8-bit grey, and the image source that reads a bag sequence's
// frames as the run asks for them (decoded, and rectified when CameraModel says so).

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "bags/bag_reader.h"
#include "bags/camera_info.h"
#include "bags/ros_messages.h"
#include "ssta/core/image.h"
#include "ssta/io/sequence.h"

namespace ssta::internal {

/// The image as 8-bit grey: colour converted (ITU-R BT.601 weights, as OpenCV), Bayer
/// patterns demosaiced, 16-bit scaled by 1/256 (byte order from `big_endian`), row padding
/// (`step`) dropped. Throws ssta::Error naming `where` for an encoding it does not read or data
/// too short for the size.
ImageU8 GreyImage(const RosImage& image, const std::string& where);
/// A JPEG or PNG image decoded to 8-bit grey. Throws ssta::Error naming `where` when it cannot
/// be decoded (or is a compressed depth image).
ImageU8 GreyImage(const RosCompressedImage& image, const std::string& where);

/// Reads frames from the bag as the run asks for them: each image message decoded to grey,
/// checked against its CameraInfo's size, and rectified when its CameraModel remaps.
class BagImageSource final : public StereoImageSource {
 public:
  /// The left and right message of one frame.
  struct Pair {
    BagMessageRef left, right;
  };

  /// `encodings` and `compressed` (CompressedImage topics) per side, left then right;
  /// `pairs` indexed by StereoFrame::message_index.
  BagImageSource(std::shared_ptr<const BagReader> bag, std::array<RosEncoding, 2> encodings,
                 std::array<bool, 2> compressed, std::array<CameraModel, 2> cameras, std::vector<Pair> pairs);

  StereoImages Read(const StereoFrame& frame) const override;

 private:
  ImageU8 ReadOne(const BagMessageRef& ref, int side, const std::string& where) const;

  std::shared_ptr<const BagReader> bag_;
  std::array<RosEncoding, 2> encodings_;
  std::array<bool, 2> compressed_;
  std::array<CameraModel, 2> cameras_;
  std::vector<Pair> pairs_;
};

}  // namespace ssta::internal
