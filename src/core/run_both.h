#pragma once

// Private, for the modules that link OpenCV (the core library itself does not): parallel work on
// OpenCV's thread pool.

#include <functional>

#include <opencv2/core/utility.hpp>

#include "core/parallel_pair.h"

namespace ssta {
namespace internal {

/// A PairRunner (core/parallel_pair.h) on OpenCV's thread pool: part(0) and part(1) at the same
/// time, one after the other when OpenCV's thread count is 1.
inline void RunPairOnOpenCv(const std::function<void(int)>& part) {
  cv::parallel_for_(
      cv::Range(0, 2),
      [&](const cv::Range& range) {
        for (int i = range.start; i < range.end; ++i) part(i);
      },
      2);
}

/// Runs a() and b() at the same time on OpenCV's threads (one after the other when its thread
/// count is 1, e.g. under `ssta --threads 1`, or on a SerialOnThisThread thread); the first
/// exception either throws reaches the caller once both are done. For two independent steps of
/// one frame whose results the caller then combines in a fixed order, so the result never
/// depends on the scheduling.
template <typename A, typename B>
void RunBoth(const A& a, const B& b) {
  RunPairWith(&RunPairOnOpenCv, [&](int part) {
    if (part == 0) {
      a();
    } else {
      b();
    }
  });
}

}  // namespace internal
}  // namespace ssta
