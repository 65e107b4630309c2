#include "core/ordered_worker.h"

#include <utility>

#include "core/parallel_pair.h"

namespace ssta::internal {

OrderedWorker::OrderedWorker(int max_waiting) : max_waiting_(max_waiting < 0 ? 0 : max_waiting) {
  if (max_waiting_ > 0) thread_ = std::thread([this] { Loop(); });
}

OrderedWorker::~OrderedWorker() {
  if (!thread_.joinable()) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    closing_ = true;
  }
  changed_.notify_all();
  thread_.join();
}

void OrderedWorker::Submit(std::function<void()> job) {
  if (max_waiting_ == 0) {
    RethrowError();
    try {
      job();
    } catch (...) {
      error_ = std::current_exception();
      RethrowError();
    }
    return;
  }
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [&] { return error_ || static_cast<int>(jobs_.size()) < max_waiting_; });
  if (error_) {
    lock.unlock();
    RethrowError();
  }
  jobs_.push_back(std::move(job));
  lock.unlock();
  changed_.notify_all();
}

void OrderedWorker::Drain() {
  if (max_waiting_ > 0) {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait(lock, [&] { return jobs_.empty() && !busy_; });
  }
  RethrowError();
}

void OrderedWorker::RethrowError() {
  std::exception_ptr error;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    error = std::exchange(error_, nullptr);
  }
  if (error) std::rethrow_exception(error);
}

void OrderedWorker::Loop() {
  // The jobs run beside the caller's own parallel work: they keep to this thread.
  SerialOnThisThread() = true;
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    changed_.wait(lock, [&] { return closing_ || !jobs_.empty(); });
    if (jobs_.empty()) return;  // closing, nothing left
    std::function<void()> job = std::move(jobs_.front());
    jobs_.pop_front();
    busy_ = true;
    const bool failed_before = error_ != nullptr;
    lock.unlock();
    changed_.notify_all();
    std::exception_ptr error;
    if (!failed_before) {
      try {
        job();
      } catch (...) {
        error = std::current_exception();
      }
    }
    lock.lock();
    if (error && !error_) error_ = error;
    if (error_) jobs_.clear();  // the jobs after a failed one are dropped
    busy_ = false;
    changed_.notify_all();
  }
}

}  // namespace ssta::internal
