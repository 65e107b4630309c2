#pragma once

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <map>
#include <string>
#include <system_error>

#include "ssta/core/error.h"

namespace ssta::internal {

/// The PNG files of a folder (extension in any case) by file name; throws ssta::Error naming the
/// folder when it cannot be listed.
inline std::map<std::string, std::filesystem::path> ListPngs(const std::filesystem::path& dir) {
  std::map<std::string, std::filesystem::path> files;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    if (!entry.is_regular_file()) continue;
    std::string ext = entry.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (ext == ".png") files.emplace(entry.path().filename().string(), entry.path());
  }
  if (ec) throw Error(dir.string() + ": cannot list folder: " + ec.message());
  return files;
}

}  // namespace ssta::internal
