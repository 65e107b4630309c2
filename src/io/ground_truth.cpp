#include "ssta/io/ground_truth.h"

#include <filesystem>

#include "ssta/io/image_io.h"

namespace ssta {

std::string TruthFramePath(const Sequence& sequence, const std::string& kind, std::int64_t timestamp_ns) {
  namespace fs = std::filesystem;
  const std::string name = std::to_string(timestamp_ns) + ".png";
  fs::path gt = fs::path(sequence.root()) / "gt" / kind / name;
  if (!fs::exists(gt)) gt = fs::path(sequence.root()).parent_path() / "gt" / kind / name;
  return gt.string();
}

ImageF ReadTrueDisparity(const Sequence& sequence, std::int64_t timestamp_ns) {
  const ImageU16 raw = ReadImageU16(TruthFramePath(sequence, "disparity", timestamp_ns));
  ImageF disparity(raw.width(), raw.height());
  for (std::size_t i = 0; i < raw.size(); ++i) disparity[i] = raw[i] / 256.0f;
  return disparity;
}

ImageU8 ReadTrueLabels(const Sequence& sequence, std::int64_t timestamp_ns) {
  return ReadLabelImage(TruthFramePath(sequence, "labels", timestamp_ns));
}

}  // namespace ssta
