// The ROS message decoders (src/bags/ros_messages.cpp) on any bytes, in both encodings: ROS 1
// serialization (bags read through rosbag) and CDR (ROS 2 bags). Every decoder sees every input,
// and a decoded image goes on to the grey conversion, as a frame's would.

#include "fuzz_util.h"
#include "bags/image_decoding.h"
#include "bags/ros_messages.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::vector<std::uint8_t> bytes(data, data + size);
  using namespace ssta::internal;
  for (const RosEncoding e : {RosEncoding::kRos1, RosEncoding::kCdr}) {
    ssta::fuzz::ExpectParsedOrError([&] { GreyImage(DecodeImage(bytes, e, "image"), "image"); });
    ssta::fuzz::ExpectParsedOrError([&] { DecodeCompressedImage(bytes, e, "compressed"); });
    ssta::fuzz::ExpectParsedOrError([&] { DecodeCameraInfo(bytes, e, "camera_info"); });
    ssta::fuzz::ExpectParsedOrError([&] { DecodeImu(bytes, e, "imu"); });
    ssta::fuzz::ExpectParsedOrError([&] { DecodeOdometry(bytes, e, "odom"); });
    ssta::fuzz::ExpectParsedOrError([&] { DecodeTfMessage(bytes, e, "tf"); });
  }
  return 0;
}
