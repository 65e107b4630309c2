#pragma once

// Runs the built `ssta` binary (SSTA_BINARY) with arguments and captures its exit code and
// output (stdout and stderr together, or stdout alone).

#include <array>
#include <cstdio>
#include <string>

#include <sys/wait.h>
#include "ssta_test_paths.h"

namespace ssta::testing {

struct RunResult {
  int exit_code = -1;
  std::string output;
};

inline RunResult RunSsta(const std::string& arguments, bool with_stderr = true) {
  RunResult result;
  const std::string command = std::string(SSTA_BINARY) + " " + arguments + (with_stderr ? " 2>&1" : " 2>/dev/null");
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return result;
  std::array<char, 512> buffer{};
  while (std::fgets(buffer.data(), buffer.size(), pipe) != nullptr) result.output += buffer.data();
  const int status = ::pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

}  // namespace ssta::testing
