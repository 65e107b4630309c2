#pragma once

// Shared by the fuzz targets: the rule is that any input either parses or throws ssta::Error.
// Anything else (another exception, a crash, a sanitizer report, a leak, a hang) is a bug.

#include <cstddef>
#include <cstdint>
#include <string>

#include "ssta/core/error.h"

namespace ssta::fuzz {

inline std::string AsText(const std::uint8_t* data, std::size_t size) {
  return std::string(reinterpret_cast<const char*>(data), size);
}

/// Runs `parse`; ssta::Error is the expected outcome for bad input, everything else escapes
/// (libFuzzer reports an uncaught exception as a crash).
template <typename Parse>
void ExpectParsedOrError(Parse&& parse) {
  try {
    parse();
  } catch (const ssta::Error& e) {
    if (std::string(e.what()).empty()) __builtin_trap();  // an error must say what is wrong
  }
}

}  // namespace ssta::fuzz
