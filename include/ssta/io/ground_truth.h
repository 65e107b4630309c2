#pragma once

// Readers of a synthetic sequence's per-frame truth (docs/interfaces.md, "Synthetic sequences"):
// gt/disparity/<ts>.png and gt/labels/<ts>.png beside the sequence's cam0/, or in its parent
// folder (ASL's mav0/ layout).

#include <cstdint>
#include <string>

#include "ssta/core/image.h"
#include "ssta/io/sequence.h"

namespace ssta {

/// The path of frame `timestamp_ns`'s truth of `kind` ("labels" or "disparity"):
/// SEQ/gt/<kind>/<ts>.png, else the same under the sequence root's parent folder. The file
/// need not exist.
std::string TruthFramePath(const Sequence& sequence, const std::string& kind, std::int64_t timestamp_ns);

/// The true disparity of the frame [px], of the rectified common area: gt/disparity/<ts>.png
/// (16 bit, disparity * 256, 0 = none). Throws ssta::Error naming the file when it is missing
/// or unreadable.
ImageF ReadTrueDisparity(const Sequence& sequence, std::int64_t timestamp_ns);

/// The true class ids of the frame at the full rectified size: gt/labels/<ts>.png (ids 0-4,
/// 255 = don't care). Throws ssta::Error naming the file when it is missing or unreadable.
ImageU8 ReadTrueLabels(const Sequence& sequence, std::int64_t timestamp_ns);

}  // namespace ssta
