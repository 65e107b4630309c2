#pragma once

// The picture of a map diff and the diff's files (`ssta diff-maps A.ot B.ot --out D`), drawn
// with OpenCV: the data part, DiffMaps and MapDiffCsv, is in ssta/mapping/map_diff.h.

#include <string>

#include "ssta/core/image.h"
#include "ssta/mapping/map_diff.h"

namespace ssta {

/// The picture of a diff: each column in its change's colour (change_colours; unchanged
/// obstacles darker than unchanged ground, columns without a class white), both sensor paths,
/// metric axes, a scale bar, a legend with each change's count, and `title`.
ImageRgb RenderMapDiffPicture(const MapDiff& diff, const std::string& title);

/// Writes `out_dir`/diff.csv (MapDiffCsv) and `out_dir`/diff.png (RenderMapDiffPicture), each
/// atomically; creates `out_dir`. Errors name the file.
void WriteMapDiff(const MapDiff& diff, const std::string& out_dir, const std::string& title);

}  // namespace ssta
