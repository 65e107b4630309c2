#pragma once

#include <stdexcept>
#include <string>

namespace ssta {

/// The one exception type for bad input: a missing or corrupt file, a bad config value, a
/// calibration that cannot be right. The message names the file, line or key at fault and is
/// meant to be printed to the user as it is.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

/// Thrown by SSTA_CHECK: a broken precondition inside the library (a programmer error, not a
/// user's). Always on, also in Release builds.
class InternalError : public std::logic_error {
 public:
  explicit InternalError(const std::string& message) : std::logic_error(message) {}
};

/// Sets `*error` (when not null) to `message` and returns false: how every IsValid(std::string*
/// error) reports the key at fault.
inline bool Fail(std::string* error, const std::string& message) {
  if (error) *error = message;
  return false;
}

namespace internal {
[[noreturn]] void FailCheck(const char* condition, const char* file, int line,
                            const std::string& message);
}  // namespace internal

}  // namespace ssta

/// Always-on precondition check for programmer errors; throws ssta::InternalError.
#define SSTA_CHECK(condition, message)                                           \
  do {                                                                           \
    if (!(condition)) {                                                          \
      ::ssta::internal::FailCheck(#condition, __FILE__, __LINE__, (message));     \
    }                                                                            \
  } while (false)
