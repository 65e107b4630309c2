// Checks of output paths while the command line is parsed: a run that would fail to write its
// results fails before it does its work.

#include <filesystem>
#include <string>

#include "commands.h"
#include "ssta/files/file_util.h"

namespace ssta::cli {
namespace {

namespace fs = std::filesystem;

// A file to write, or a prefix to which extensions are added: its folder must exist, and the
// path must not name a folder.
CLI::Validator FileOrPrefix(bool prefix) {
  return CLI::Validator(
      [prefix](std::string& path) -> std::string {
        if (prefix && NamesAFolder(path)) {
          return path + ": is a folder; give a prefix such as " + (fs::path(path) / "map").string();
        }
        const std::string problem = OutputFileProblem(path);
        return problem.empty() ? "" : path + ": " + problem;
      },
      prefix ? "PREFIX" : "FILE");
}

}  // namespace

CLI::Validator OutputFile() { return FileOrPrefix(false); }

CLI::Validator OutputPrefix() { return FileOrPrefix(true); }

CLI::Validator OutputFolder() {
  return CLI::Validator(
      [](std::string& path) -> std::string {
        std::error_code ec;
        if (fs::exists(path, ec) && !fs::is_directory(path, ec)) return path + ": is a file, not a folder";
        return "";
      },
      "DIR");
}

}  // namespace ssta::cli
