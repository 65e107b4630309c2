#pragma once

// Private helper: writes a MountRefinementResult into a JSON document being built, so that the
// offline calibration can nest it in its own report.

#include "ssta/core/json_writer.h"
#include <vector>

#include "ssta/io/sequence.h"
#include "ssta/mount/mount_refiner.h"

namespace ssta::internal {

/// Writes `result` as one JSON object value (the caller has written its key, if any).
void WriteRefinementJson(const MountRefinementResult& result, JsonWriter* json);

/// Writes frames as an array of {timestamp_ns, reason} objects.
void WriteSkippedFramesJson(const std::vector<SkippedFrame>& frames, JsonWriter* json);

}  // namespace ssta::internal
