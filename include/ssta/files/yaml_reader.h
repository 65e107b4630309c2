#pragma once

// Reads a YAML mapping key by key, names every key it reports on with its full path
// ("stereo.num_disparities"), and reports keys that nobody asked for: the config, sensor.yaml,
// rosbag2 metadata and map metadata readers share it. Includes yaml-cpp (link yaml-cpp).

#include <cctype>
#include <set>
#include <string>
#include <type_traits>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "ssta/core/error.h"
#include "ssta/core/option_fields.h"

namespace ssta::internal {

/// Parses YAML text; OpenCV's `%YAML:1.0` first line is accepted. Throws ssta::Error naming
/// `file` and the line on a syntax error.
YAML::Node ParseYaml(const std::string& text, const std::string& file);

class YamlSection {
 public:
  /// `node` must be a map or null; `file` and `path` only name things in messages.
  YamlSection(YAML::Node node, std::string file, std::string path);

  bool Has(const std::string& key) const;
  /// Overwrites `*value` when the key is present; throws naming the key on a type error.
  template <typename T>
  void Read(const std::string& key, T* value);
  /// Reads a fixed-length numeric list.
  void ReadList(const std::string& key, std::vector<double>* values, std::size_t expected_size);
  /// Like Read but the key must exist.
  template <typename T>
  T Require(const std::string& key);
  /// Child section (an empty one when absent).
  YamlSection Child(const std::string& key);

  /// Throws naming the first key of this section that no Read/Child call asked for.
  void RejectUnknownKeys() const;
  /// Marks keys as known without reading them (keys documented but ignored).
  void Ignore(const std::string& key) { used_.insert(key); }

  /// "file: path.key" for messages.
  std::string Name(const std::string& key) const;
  const std::string& file() const { return file_; }

 private:
  YAML::Node node_;
  std::string file_;
  std::string path_;
  std::set<std::string> used_;
};

template <typename T>
void YamlSection::Read(const std::string& key, T* value) {
  used_.insert(key);
  if (!node_ || !node_[key]) return;
  if constexpr (std::is_arithmetic_v<T>) {
    // yaml-cpp reads a quote left open on the last line ('max_slope_deg: "20' + newline) as
    // the scalar "20 " and converts it: a number with white space around it is a mistake.
    const YAML::Node n = node_[key];
    if (n.IsScalar()) {  // other kinds fail the conversion below
      const std::string& text = n.Scalar();
      if (text.empty() || std::isspace(static_cast<unsigned char>(text.front())) ||
          std::isspace(static_cast<unsigned char>(text.back()))) {
        throw Error(Name(key) + ": wrong type (value '" + YAML::Dump(n) +
                    "': a number with white space around it; is a quote left open?)");
      }
    }
  }
  try {
    *value = node_[key].template as<T>();
  } catch (const YAML::Exception&) {
    throw Error(Name(key) + ": wrong type (value '" + YAML::Dump(node_[key]) + "')");
  }
}

template <typename T>
T YamlSection::Require(const std::string& key) {
  if (!Has(key)) throw Error(Name(key) + ": missing key");
  T value{};
  Read(key, &value);
  return value;
}

/// Reads every key of `fields` that `section` holds into `*options`, each by its kind; a choice
/// outside its names is an error naming the key and the names. Keys the section holds that
/// `fields` does not know are left for RejectUnknownKeys.
template <class O>
void ReadOptions(YamlSection& section, const OptionFields<O>& fields, O* options) {
  for (const OptionField<O>& f : fields) {
    if (!section.Has(f.key)) {
      section.Ignore(f.key);
      continue;
    }
    switch (f.kind) {
      case OptionKind::kReal: {
        double v = 0.0;
        section.Read(f.key, &v);
        f.set(options, v);
        break;
      }
      case OptionKind::kInteger: {
        int v = 0;
        section.Read(f.key, &v);
        f.set(options, static_cast<double>(v));
        break;
      }
      case OptionKind::kFlag: {
        bool v = false;
        section.Read(f.key, &v);
        f.set(options, v);
        break;
      }
      case OptionKind::kChoice: {
        const auto v = section.Require<std::string>(f.key);
        std::string names;
        bool known = false;
        for (const std::string& c : f.choices) {
          names += (names.empty() ? "" : ", ") + c;
          known = known || c == v;
        }
        if (!known) throw Error(section.Name(f.key) + ": unknown value '" + v + "' (" + names + ")");
        f.set(options, v);
        break;
      }
      case OptionKind::kVector3: {
        std::vector<double> v;
        section.ReadList(f.key, &v, 3);
        f.set(options, Eigen::Vector3d(v[0], v[1], v[2]));
        break;
      }
    }
  }
}

}  // namespace ssta::internal
