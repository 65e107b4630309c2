#pragma once

// A one-line progress meter on stderr (frames, frames/s, ETA), drawn only on a terminal.

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <string>

namespace ssta::cli {

class ProgressLine {
 public:
  explicit ProgressLine(std::string label, bool enabled = true)
      : label_(std::move(label)), enabled_(enabled && isatty(STDERR_FILENO)) {}
  ~ProgressLine() { Finish(); }

  void Update(int done, int total) {
    if (!enabled_) return;
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    const double rate = s > 0 ? done / s : 0.0;
    const double eta = rate > 0 ? (total - done) / rate : 0.0;
    std::fprintf(stderr, "\r%s %d/%d frames, %.1f frames/s, ETA %.0f s   ", label_.c_str(), done, total, rate, eta);
    std::fflush(stderr);
    drawn_ = true;
  }
  void Finish() {
    if (drawn_) std::fprintf(stderr, "\n");
    drawn_ = false;
  }

 private:
  std::string label_;
  bool enabled_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace ssta::cli
