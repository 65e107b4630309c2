#pragma once

// A child process that holds a map's write lock (MapWriteLock) until it is killed: the other
// writer of the tests of "one writer per map".

#include <csignal>
#include <string>

#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include "ssta/files/file_util.h"

namespace ssta::testing {

class LockHolder {
 public:
  /// Forks; returns once the child holds the lock on `map` (held() true) or failed to take it.
  explicit LockHolder(const std::string& map) {
    int ready[2];
    if (::pipe(ready) != 0) return;
    pid_ = ::fork();
    if (pid_ == 0) {
      ::close(ready[0]);
      char status = 0;
      try {
        const MapWriteLock lock(map);
        status = 1;
        (void)!::write(ready[1], &status, 1);
        for (;;) ::pause();
      } catch (...) {
        (void)!::write(ready[1], &status, 1);
        ::_exit(3);
      }
    }
    ::close(ready[1]);
    char status = 0;
    held_ = pid_ > 0 && ::read(ready[0], &status, 1) == 1 && status == 1;
    ::close(ready[0]);
  }
  ~LockHolder() { Kill(); }
  LockHolder(const LockHolder&) = delete;
  LockHolder& operator=(const LockHolder&) = delete;

  bool held() const { return held_; }
  pid_t pid() const { return pid_; }
  /// SIGKILL, as a crash or the OOM killer would end a writer; waits for the child to go.
  void Kill() {
    if (pid_ <= 0) return;
    ::kill(pid_, SIGKILL);
    ::waitpid(pid_, nullptr, 0);
    pid_ = -1;
  }

 private:
  pid_t pid_ = -1;
  bool held_ = false;
};

}  // namespace ssta::testing
