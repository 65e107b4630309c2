#include "ssta/core/error.h"

#include <sstream>

namespace ssta::internal {

void FailCheck(const char* condition, const char* file, int line, const std::string& message) {
  std::ostringstream out;
  out << "internal check failed: " << condition << " at " << file << ":" << line;
  if (!message.empty()) out << ": " << message;
  throw InternalError(out.str());
}

}  // namespace ssta::internal
