#include "bags/bag_reader.h"

#include <filesystem>
#include <iomanip>
#include <sstream>

#include "ssta/core/error.h"

namespace fs = std::filesystem;

namespace ssta::internal {

std::string TruncationText(const std::string& path, const std::string& what, std::int64_t last_ns) {
  if (last_ns < 0) return path + ": truncated: " + what + ", before any complete message";
  std::ostringstream t;
  t << last_ns / 1'000'000'000 << "." << std::setw(9) << std::setfill('0') << last_ns % 1'000'000'000;
  return path + ": truncated: " + what + "; the last complete message was logged at " + t.str() + " s";
}

std::unique_ptr<BagReader> OpenBag(const std::string& path) {
  if (!fs::exists(path)) throw Error(path + ": bag not found");
  std::error_code ec;
  if (fs::is_directory(path, ec) || fs::path(path).extension() == ".mcap" || fs::path(path).extension() == ".db3") {
    return OpenRos2Bag(path);
  }
  return OpenRos1Bag(path);
}

}  // namespace ssta::internal
