#include "ssta/pipeline/config.h"

#include <sstream>

#include "ssta/files/yaml_reader.h"
#include "pipeline/config_text.h"
#include "ssta/files/file_util.h"
#include "ssta/io/sequence.h"

namespace ssta {
namespace {

using internal::YamlSection;

/// `text` broken into lines of at most `width` characters at spaces.
std::vector<std::string> Wrap(const std::string& text, std::size_t width) {
  std::vector<std::string> lines(1);
  std::istringstream words(text);
  std::string word;
  while (words >> word) {
    if (!lines.back().empty() && lines.back().size() + 1 + word.size() > width) lines.emplace_back();
    lines.back() += (lines.back().empty() ? "" : " ") + word;
  }
  return lines;
}

template <class O>
void WriteSection(const char* name, const char* what, const O& options, bool comments, std::ostream* out) {
  constexpr std::size_t kCommentColumn = 29, kLineWidth = 100;
  std::string head = std::string(name) + ":";
  if (comments && *what) head += std::string(kCommentColumn - std::min(kCommentColumn - 1, head.size()), ' ') + "# " + what;
  *out << head << "\n";
  for (const OptionField<O>& f : O::Fields()) {
    std::string line = "  " + f.key + ": " + FormatOptionValue(f.get(options), f.kind);
    if (comments) {
      const std::string text = (f.unit.empty() ? "" : "[" + f.unit + "] ") + f.meaning;
      const std::size_t column = std::max(kCommentColumn, line.size() + 1);
      const std::vector<std::string> lines = Wrap(text, kLineWidth - kCommentColumn - 4);
      for (std::size_t i = 0; i < lines.size(); ++i) {
        if (i == 0) {
          line += std::string(column - line.size(), ' ') + "# " + lines[i];
        } else {
          line += "\n" + std::string(kCommentColumn, ' ') + "#   " + lines[i];
        }
      }
    }
    *out << line << "\n";
  }
}

std::string WriteConfig(const Config& config, bool comments) {
  std::ostringstream y;
  bool first = true;
  ForEachConfigSection(config, [&](const char* name, const char* what, const auto& section) {
    if (comments && !first) y << "\n";
    first = false;
    WriteSection(name, what, section, comments, &y);
  });
  return y.str();
}

}  // namespace

bool Config::IsValid(std::string* error) const {
  bool valid = true;
  ForEachConfigSection(*this, [&](const char* name, const char*, const auto& section) {
    std::string e;
    if (valid && !section.IsValid(&e)) valid = Fail(error, std::string(name) + "." + e);
  });
  return valid;
}

void ApplyConfigFile(const std::string& path, Config* config) {
  internal::ApplyConfigText(ReadTextFile(path), path, config);
}

void internal::ApplyConfigText(const std::string& text, const std::string& path, Config* config) {
  YamlSection root(internal::ParseYaml(text, path), path, "");
  Config c = *config;
  ForEachConfigSection(c, [&](const char* name, const char*, auto& section) {
    YamlSection s = root.Child(name);
    ReadOptions(s, std::decay_t<decltype(section)>::Fields(), &section);
    if (std::string(name) == "vehicle") {  // labels for people (config/vehicles/*.yaml)
      s.Ignore("name");
      s.Ignore("description");
    }
    s.RejectUnknownKeys();
  });
  root.RejectUnknownKeys();
  std::string error;
  if (!c.IsValid(&error)) throw Error(path + ": " + error);
  *config = c;
}

Config LoadLayeredConfig(const Sequence* sequence, const std::vector<std::string>& files) {
  Config config;
  if (sequence && sequence->vehicle_config()) ApplyConfigFile(*sequence->vehicle_config(), &config);
  for (const std::string& file : files) ApplyConfigFile(file, &config);
  return config;
}

Config LoadConfig(const std::string& path) {
  Config config;
  ApplyConfigFile(path, &config);
  return config;
}

std::string ConfigToYaml(const Config& config) { return WriteConfig(config, false); }

std::string ConfigToCommentedYaml(const Config& config) {
  return "# Every SSTA setting with its unit, range and meaning, as `ssta config` prints it. A config\n"
         "# file may hold any subset of these; what it leaves out keeps the value here. Unknown keys\n"
         "# and out-of-range values are errors that name the key. A test keeps config/default.yaml\n"
         "# equal to the built-in defaults.\n\n" +
         WriteConfig(config, true);
}

}  // namespace ssta
