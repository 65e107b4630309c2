#include "ssta/core/option_fields.h"

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>

namespace ssta {

std::string ShortestDecimal(double v) {
  char buffer[40];
  for (int precision = 1; precision <= 17; ++precision) {
    std::snprintf(buffer, sizeof(buffer), "%.*g", precision, v);
    if (std::strtod(buffer, nullptr) == v) break;
  }
  std::string shortest = buffer;
  if (std::isfinite(v) && std::abs(v) < 1e16) {  // fixed notation, when it is shorter
    for (int decimals = 0; decimals <= 17; ++decimals) {
      std::snprintf(buffer, sizeof(buffer), "%.*f", decimals, v);
      if (std::strtod(buffer, nullptr) != v) continue;
      if (std::strlen(buffer) < shortest.size()) shortest = buffer;
      break;
    }
  }
  return shortest;
}

std::string FormatOptionValue(const OptionValue& value, OptionKind kind) {
  switch (kind) {
    case OptionKind::kReal:
      return ShortestDecimal(std::get<double>(value));
    case OptionKind::kInteger:
      return std::to_string(static_cast<long long>(std::get<double>(value)));
    case OptionKind::kFlag:
      return std::get<bool>(value) ? "true" : "false";
    case OptionKind::kChoice:
      return std::get<std::string>(value);
    case OptionKind::kVector3: {
      const Eigen::Vector3d& v = std::get<Eigen::Vector3d>(value);
      return "[" + ShortestDecimal(v.x()) + ", " + ShortestDecimal(v.y()) + ", " + ShortestDecimal(v.z()) + "]";
    }
  }
  return "";
}

std::string Interval::Text() const {
  auto end = [](double v) { return std::isinf(v) ? std::string(v < 0 ? "-inf" : "inf") : ShortestDecimal(v); };
  return (lo_open ? "(" : "[") + end(lo) + ", " + end(hi) + (hi_open ? ")" : "]");
}

}  // namespace ssta
