#include "yaml_reader.h"

#include <cmath>

namespace ssta::internal {

YAML::Node ParseYaml(const std::string& text, const std::string& file) {
  std::string body = text;
  // OpenCV and EuRoC write "%YAML:1.0", which is not a YAML directive: drop that first line.
  if (body.rfind("%YAML:", 0) == 0) {
    const auto eol = body.find('\n');
    body = eol == std::string::npos ? std::string() : "\n" + body.substr(eol + 1);
  }
  try {
    return YAML::Load(body);
  } catch (const YAML::Exception& e) {
    throw Error(file + ":" + std::to_string(e.mark.line + 1) + ": YAML syntax error: " + e.msg);
  }
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
