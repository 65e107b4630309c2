#pragma once

#include <exception>

#include <opencv2/core/utility.hpp>

namespace ssta {
namespace internal {

/// True on a thread whose work runs beside another thread's parallel work, such as the
/// pipelined map worker beside the frame being classified: RunBoth then runs its two parts one
/// after the other there. On two cores, two threads that both fan out oversubscribe them (the
/// yard's pipelined interval measured 105 ms with the map worker serial, 120 ms without).
inline bool& SerialOnThisThread() {
  thread_local bool serial = false;
  return serial;
}

/// Runs a() and b() at the same time on OpenCV's threads (one after the other when its thread
/// count is 1, e.g. under `ssta --threads 1`, or on a SerialOnThisThread thread); the first
/// exception either throws reaches the caller once both are done. For two independent steps of
/// one frame whose results the caller then combines in a fixed order, so the result never
/// depends on the scheduling.
template <typename A, typename B>
void RunBoth(const A& a, const B& b) {
  if (SerialOnThisThread()) {
    a();
    b();
    return;
  }
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
