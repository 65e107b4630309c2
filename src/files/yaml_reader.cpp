#include "ssta/files/yaml_reader.h"

#include <cmath>
#include <set>

namespace ssta::internal {

namespace {

// Deeper than any config, calibration or truth file nests; an alias inside the node its anchor
// names (`&a [*a]`) makes a cycle that would otherwise be walked until the stack runs out.
constexpr int kMaxYamlDepth = 64;

// yaml-cpp keeps both entries of a key written twice and answers lookups with the first, so a
// config whose `vehicle:` appears twice would run half of each: refused, naming the line.
void RejectDuplicateKeys(const YAML::Node& node, const std::string& file, int depth = 0) {
  if (depth > kMaxYamlDepth) {
    throw Error(file + ":" + std::to_string(node.Mark().line + 1) + ": nested more than " +
                std::to_string(kMaxYamlDepth) + " levels deep (an alias inside the node its anchor names?)");
  }
  if (node.IsMap()) {
    std::set<std::string> keys;
    for (const auto& entry : node) {
      if (entry.first.IsScalar() && !keys.insert(entry.first.Scalar()).second) {
        throw Error(file + ":" + std::to_string(entry.first.Mark().line + 1) + ": key '" + entry.first.Scalar() +
                    "' appears twice in the same mapping");
      }
      RejectDuplicateKeys(entry.second, file, depth + 1);
    }
  } else if (node.IsSequence()) {
    for (const auto& item : node) RejectDuplicateKeys(item, file, depth + 1);
  }
}

}  // namespace

YAML::Node ParseYaml(const std::string& text, const std::string& file) {
  std::string body = text;
  // OpenCV and EuRoC write "%YAML:1.0", which is not a YAML directive: drop that first line.
  if (body.rfind("%YAML:", 0) == 0) {
    const auto eol = body.find('\n');
    body = eol == std::string::npos ? std::string() : "\n" + body.substr(eol + 1);
  }
  YAML::Node root;
  try {
    root = YAML::Load(body);
  } catch (const YAML::Exception& e) {
    throw Error(file + ":" + std::to_string(e.mark.line + 1) + ": YAML syntax error: " + e.msg);
  }
  RejectDuplicateKeys(root, file);
  return root;
}

YamlSection::YamlSection(YAML::Node node, std::string file, std::string path)
    : node_(std::move(node)), file_(std::move(file)), path_(std::move(path)) {
  if (node_ && !node_.IsNull() && !node_.IsMap()) {
    throw Error(file_ + ": " + (path_.empty() ? "top level" : path_) + ": expected a mapping");
  }
}

bool YamlSection::Has(const std::string& key) const {
  return node_ && node_.IsMap() && node_[key] && !node_[key].IsNull();
}

void YamlSection::ReadList(const std::string& key, std::vector<double>* values,
                           std::size_t expected_size) {
  used_.insert(key);
  if (!Has(key)) return;
  const YAML::Node list = node_[key];
  if (!list.IsSequence() || list.size() != expected_size) {
    throw Error(Name(key) + ": expected a list of " + std::to_string(expected_size) + " numbers");
  }
  std::vector<double> out;
  for (const auto& item : list) {
    try {
      out.push_back(item.as<double>());
    } catch (const YAML::Exception&) {
      throw Error(Name(key) + ": '" + YAML::Dump(item) + "' is not a number");
    }
  }
  *values = std::move(out);
}

YamlSection YamlSection::Child(const std::string& key) {
  used_.insert(key);
  YAML::Node child = Has(key) ? node_[key] : YAML::Node();
  return YamlSection(child, file_, path_.empty() ? key : path_ + "." + key);
}

void YamlSection::RejectUnknownKeys() const {
  if (!node_ || !node_.IsMap()) return;
  for (const auto& item : node_) {
    if (!item.first.IsScalar()) throw Error(file_ + ": " + (path_.empty() ? "top level" : path_) + ": keys must be plain names");
    const auto key = item.first.Scalar();
    if (used_.count(key) == 0) throw Error(Name(key) + ": unknown key");
  }
}

std::string YamlSection::Name(const std::string& key) const {
  return file_ + ": " + (path_.empty() ? key : path_ + "." + key);
}

}  // namespace ssta::internal
