#include "eval/class_ids.h"

#include "ssta/core/classes.h"
#include "ssta/core/error.h"

namespace ssta::internal {
namespace {

std::string PixelText(const ImageU8& image, std::size_t i) {
  const auto w = static_cast<std::size_t>(image.width());
  return "(v " + std::to_string(i / w) + ", u " + std::to_string(i % w) + ")";
}

}  // namespace

void CheckTruthIds(const ImageU8& truth, const std::string& name) {
  for (std::size_t i = 0; i < truth.size(); ++i) {
    if (truth[i] >= kNumClasses && truth[i] != kDontCare) {
      throw Error(name + ": value " + std::to_string(truth[i]) + " at " + PixelText(truth, i) +
                  " is not a class id (0..4 or 255 = don't care)");
    }
  }
}

void CheckPredictedIds(const ImageU8& predicted, const std::string& name) {
  for (std::size_t i = 0; i < predicted.size(); ++i) {
    if (predicted[i] >= kNumClasses) {
      throw Error(name + ": value " + std::to_string(predicted[i]) + " at " +
                  PixelText(predicted, i) + " is not a class id 0..4");
    }
  }
}

}  // namespace ssta::internal
