// Linked into every test binary: OpenCV's thread count comes from OPENCV_FOR_THREADS_NUM when it
// is set, as in the CLI (apps/ssta/main.cpp). OpenCV reads the variable only when asked for its
// default, so without this a test process would run its loops on every core whatever the
// variable says. scripts/sanitize.sh sets it to 1: under ASan two test processes then share the
// two cores without oversubscribing them, and under TSan no loop runs on TBB's threads, whose
// hand-over TSan cannot see.

#include <opencv2/core/utility.hpp>

namespace {

const bool kOpenCvThreadsFromEnvironment = [] {
  cv::setNumThreads(-1);
  return true;
}();

}  // namespace
