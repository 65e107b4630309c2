#pragma once

// Private: two independent parts of one step run at the same time, for the modules that do
// not link OpenCV (the map's free-space walk). The modules on OpenCV use RunBoth
// (core/run_both.h), on OpenCV's thread pool.

#include <functional>

namespace ssta {
namespace internal {

/// True on a thread whose work runs beside another thread's parallel work, such as the
/// pipelined map worker beside the frame being classified: RunBoth and RunPair then run their
/// two parts one after the other there. On two cores, two threads that both fan out
/// oversubscribe them (the yard's pipelined interval measured 105 ms with the map worker
/// serial, 120 ms without).
inline bool& SerialOnThisThread() {
  thread_local bool serial = false;
  return serial;
}

/// Runs part(0) and part(1) and returns when both have returned, possibly at the same time.
/// Must not throw: RunPair hands it parts that catch their own exceptions.
using PairRunner = void (*)(const std::function<void(int)>& part);

/// The runner of RunPair in this process (thread-safe; nullptr restores the default). The
/// default runs part(1) on a thread of its own and part(0) on the caller's. The modules on
/// OpenCV install OpenCV's thread pool (src/fusion/frame_points.cpp), so that where frames feed
/// the map, `ssta --threads` caps the map's parallel steps as well.
void SetPairRunner(PairRunner runner);

/// Runs part(0) and part(1) through the process's runner, one after the other on a
/// SerialOnThisThread thread. The first exception either part throws reaches the caller once
/// both are done. For two parts whose results the caller then combines in a fixed order, so the
/// result never depends on the scheduling.
void RunPair(const std::function<void(int)>& part);

/// RunPair through `runner` instead of the process's (nullptr: the default, two threads).
void RunPairWith(PairRunner runner, const std::function<void(int)>& part);

}  // namespace internal
}  // namespace ssta
