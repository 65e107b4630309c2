#include "ssta/analysis/label_rule.h"

#include "ssta/core/error.h"

namespace ssta {

const std::array<LabelRuleInfo, kNumLabelRules>& LabelRules() {
  // The one table of rule names and colours; its rows are in value order (checked in the test).
  static const std::array<LabelRuleInfo, kNumLabelRules> kTable = {{
      {LabelRule::kNoDepth, "no_depth", {0, 0, 0}},
      {LabelRule::kQualityCheck, "quality_check", {90, 90, 90}},
      {LabelRule::kNoSegment, "no_segment", {150, 150, 150}},
      {LabelRule::kSegment, "segment", {70, 170, 70}},
      {LabelRule::kSmallSegment, "small_segment", {200, 200, 60}},
      {LabelRule::kPixelSlope, "pixel_slope", {60, 110, 230}},
      {LabelRule::kGroundDisparity, "ground_disparity", {40, 220, 200}},
      {LabelRule::kFragmentPlane, "fragment_plane", {150, 90, 220}},
      {LabelRule::kLocalStep, "local_step", {240, 60, 40}},
      {LabelRule::kDisparityFace, "disparity_face", {250, 150, 30}},
      {LabelRule::kConsensusFill, "consensus_fill", {240, 110, 190}},
      {LabelRule::kHeightFill, "height_fill", {130, 80, 40}},
      {LabelRule::kTexture, "texture", {255, 255, 255}},
      {LabelRule::kOutside, "outside", {30, 30, 60}},
      {LabelRule::kTruth, "truth", {255, 0, 255}},
      {LabelRule::kHiddenDrop, "hidden_drop", {120, 0, 40}},
      {LabelRule::kSmearedStep, "smeared_step", {255, 180, 120}},
  }};
  return kTable;
}

std::string_view LabelRuleName(LabelRule rule) {
  const auto i = static_cast<std::size_t>(rule);
  return i < LabelRules().size() ? LabelRules()[i].name : std::string_view("invalid");
}

void LabelRuleTracker::Begin(const ImageU8& labels) { before_ = labels; }

void LabelRuleTracker::Mark(const ImageU8& labels, LabelRule rule, ImageU8* rules) {
  SSTA_CHECK(labels.width() == before_.width() && labels.height() == before_.height() &&
                 rules->width() == labels.width() && rules->height() == labels.height(),
             "LabelRuleTracker::Mark: labels, rules and the copy differ in size");
  const auto id = static_cast<std::uint8_t>(rule);
  for (std::size_t i = 0; i < labels.size(); ++i) {
    if (labels[i] != before_[i]) {
      (*rules)[i] = id;
      before_[i] = labels[i];
    }
  }
}

}  // namespace ssta
