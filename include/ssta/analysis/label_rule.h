#pragma once

// Which rule set a pixel's class: the per-pixel "why" of a frame's labels. FrameAnalyzer and
// FramePipeline write one LabelRule per pixel (AnalysisResult::rules, FrameResult::rules), only
// where a rule changes the pixel's class; the frame's JSON counts the pixels of each class per
// rule, and `ssta classify --explain` writes the rule image.

#include <array>
#include <cstdint>
#include <string_view>

#include "ssta/core/image.h"

namespace ssta {

/// The rules that set a pixel's class, in the order they run (docs/architecture.md). The value
/// is the id written to `explain/<ts>.png`; the name is the key in the frame's JSON.
enum class LabelRule : std::uint8_t {
  kNoDepth = 0,          ///< no 3D point: unknown
  kQualityCheck = 1,     ///< the frame failed the quality check: undecided
  kNoSegment = 2,        ///< a point outside every segment: undecided
  kSegment = 3,          ///< a large segment's slope / step verdict (the paper, eq. 3-5)
  kSmallSegment = 4,     ///< a small segment's verdict (analysis.small_segments), or none (eq. 4)
  kPixelSlope = 5,       ///< refinement 1, the pixel's own slope
  kGroundDisparity = 6,  ///< refinement 2, a small segment on the ground plane in disparity
  kFragmentPlane = 7,    ///< refinement 3, a small segment on a neighbour's plane
  kLocalStep = 8,        ///< refinement 4, the height jump within the step radius
  kDisparityFace = 9,    ///< refinement 5, a thin face along the image column
  kConsensusFill = 10,   ///< refinement 6, an undecided pixel amid agreement
  kHeightFill = 11,      ///< refinement 7, an undecided pixel by its height
  kTexture = 12,         ///< the texture mask (analysis.label_min_texture): unknown
  kOutside = 13,         ///< outside the rectified common area: unknown
  kTruth = 14,           ///< the sequence's true label (build-map --oracle-labels)
  kHiddenDrop = 15,      ///< refinement 8, the lip of a drop-off whose foot the frame cannot see
  kSmearedStep = 16,     ///< refinement 9, beside a jump, its point smeared over the step radius
};
inline constexpr int kNumLabelRules = 17;

/// One row of the rule table: its value and its name in JSON and docs.
struct LabelRuleInfo {
  LabelRule rule;
  std::string_view name;  ///< snake_case: "segment", "local_step", ...
  Rgb8 colour;            ///< its colour in the explain picture
};

/// Every rule, in value order (the table the names, colours and JSON keys come from).
const std::array<LabelRuleInfo, kNumLabelRules>& LabelRules();

/// The rule's name ("segment", "local_step", ...); "invalid" for a value outside the table.
std::string_view LabelRuleName(LabelRule rule);

/// Records which rule changes labels: Begin takes a copy of the labels, Mark writes `rule` into
/// `rules` wherever the labels now differ from that copy and takes the new copy. Costs one pass
/// over the labels per Mark; the labels themselves are never touched.
class LabelRuleTracker {
 public:
  /// Starts from `labels` with `rules` as they are (same size).
  void Begin(const ImageU8& labels);
  /// Precondition: Begin was called with labels of this size.
  void Mark(const ImageU8& labels, LabelRule rule, ImageU8* rules);
  /// The labels as the last Begin or Mark saw them: before the step now running.
  const ImageU8& Before() const { return before_; }

 private:
  ImageU8 before_;
};

}  // namespace ssta
