#pragma once

#include <iomanip>
#include <sstream>
#include <string>

namespace ssta::internal {

/// "label value unit" with the value in fixed notation at `precision` decimals, for the reasons
/// the analysis gives people (quality check, segment verdicts).
inline std::string FormatNumber(const char* label, double value, int precision, const char* unit) {
  std::ostringstream s;
  s << label << " " << std::fixed << std::setprecision(precision) << value << unit;
  return s.str();
}

}  // namespace ssta::internal
