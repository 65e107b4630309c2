#include "ssta/io/ground_truth.h"

#include <filesystem>

#include "ssta/io/image_io.h"

namespace ssta {

std::string TruthFramePath(const Sequence& sequence, const std::string& kind, std::int64_t timestamp_ns) {
  namespace fs = std::filesystem;
  const std::string name = std::to_string(timestamp_ns) + ".png";
  const fs::path own = fs::path(sequence.root()) / "gt" / kind / name;
  if (fs::exists(own)) return own.string();
  // A dataset's cameras may sit one folder down (mav0/): its truth beside them. When neither
  // exists, the sequence's own path is the one an error names.
  const fs::path above = fs::path(sequence.root()).parent_path() / "gt" / kind / name;
  return fs::exists(above) ? above.string() : own.string();
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
