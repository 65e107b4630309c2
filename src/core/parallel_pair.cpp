#include "core/parallel_pair.h"

#include <atomic>
#include <exception>
#include <thread>

namespace ssta {
namespace internal {
namespace {

std::atomic<PairRunner> g_runner{nullptr};

void RunOnTwoThreads(const std::function<void(int)>& part) {
  std::thread second([&] { part(1); });
  part(0);
  second.join();
}

}  // namespace

void SetPairRunner(PairRunner runner) { g_runner.store(runner); }

void RunPair(const std::function<void(int)>& part) { RunPairWith(g_runner.load(), part); }

void RunPairWith(PairRunner runner, const std::function<void(int)>& part) {
  if (SerialOnThisThread()) {
    part(0);
    part(1);
    return;
  }
  std::exception_ptr errors[2];
  const std::function<void(int)> guarded = [&](int i) {
    try {
      part(i);
    } catch (...) {
      errors[i] = std::current_exception();
    }
  };
  if (runner != nullptr) {
    runner(guarded);
  } else {
    RunOnTwoThreads(guarded);
  }
  for (const std::exception_ptr& e : errors) {
    if (e) std::rethrow_exception(e);
  }
}

}  // namespace internal
}  // namespace ssta
