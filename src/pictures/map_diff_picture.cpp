#include "ssta/pictures/map_diff_picture.h"

#include "ssta/files/file_util.h"
#include "ssta/io/image_io.h"

namespace ssta {

void WriteMapDiff(const MapDiff& diff, const std::string& out_dir, const std::string& title) {
  MakeDirectories(out_dir);
  WriteTextAtomically(out_dir + "/diff.csv", MapDiffCsv(diff));
  WriteImageCompact(RenderMapDiffPicture(diff, title), out_dir + "/diff.png");
}

}  // namespace ssta
