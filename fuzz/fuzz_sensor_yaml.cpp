// A camera's sensor.yaml (ASL layout), through the YAML reader and the calibration checks.

#include "fuzz_util.h"
#include "io/text_parsers.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text = ssta::fuzz::AsText(data, size);
  ssta::fuzz::ExpectParsedOrError([&] {
    const ssta::CameraCalibration c = ssta::internal::ParseCameraCalibration(text, "cam0/sensor.yaml");
    // A calibration that parsed must be usable: valid, and with a stereo partner shifted along x.
    std::string error;
    if (!c.IsValid(&error)) __builtin_trap();
  });
  return 0;
}
