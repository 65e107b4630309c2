#pragma once

// Private: a second thread that runs jobs in submission order, so that the map update of one
// frame overlaps the classification of the next (BuildMap, RunPipelineBench).

#include <condition_variable>
#include <deque>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>

namespace ssta::internal {

/// Runs jobs one at a time on its own thread, in the order they were submitted, with at most
/// `max_waiting` jobs waiting (Submit blocks beyond that, which bounds the frames in flight).
/// With max_waiting 0 there is no thread and Submit runs the job itself: the sequential
/// reference. Either way every job runs exactly once, in order, so state that only jobs touch
/// evolves exactly as in a sequential loop.
///
/// The first exception a job throws is kept, the jobs after it are dropped, and it is rethrown
/// by the next Submit or Drain. Submit and Drain must be called from one thread (the owner).
class OrderedWorker {
 public:
  explicit OrderedWorker(int max_waiting);
  /// Runs the jobs still queued (errors are dropped: call Drain to see them), then joins.
  ~OrderedWorker();
  OrderedWorker(const OrderedWorker&) = delete;
  OrderedWorker& operator=(const OrderedWorker&) = delete;

  void Submit(std::function<void()> job);
  /// Returns when every submitted job has run; rethrows the first job's exception.
  void Drain();

 private:
  void Loop();
  void RethrowError();

  int max_waiting_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<std::function<void()>> jobs_;
  bool busy_ = false;
  bool closing_ = false;
  std::exception_ptr error_;
  std::thread thread_;
};

}  // namespace ssta::internal
