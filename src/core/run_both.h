#pragma once

#include <exception>

#include <opencv2/core/utility.hpp>

namespace ssta {
namespace internal {

/// Runs a() and b() at the same time on OpenCV's threads (one after the other when its thread
/// count is 1, e.g. under `ssta --threads 1`); the first exception either throws reaches the
/// caller once both are done. For two independent steps of one frame whose results the caller
/// then combines in a fixed order, so the result never depends on the scheduling.
template <typename A, typename B>
void RunBoth(const A& a, const B& b) {
  std::exception_ptr errors[2];
  cv::parallel_for_(
      cv::Range(0, 2),
      [&](const cv::Range& range) {
        for (int i = range.start; i < range.end; ++i) {
          try {
            if (i == 0) {
              a();
            } else {
              b();
            }
          } catch (...) {
            errors[i] = std::current_exception();
          }
        }
      },
      2);
  for (const std::exception_ptr& e : errors) {
    if (e) std::rethrow_exception(e);
  }
}

}  // namespace internal
}  // namespace ssta
