#include "ssta/core/json_writer.h"

#include "core/json_escape.h"

#include <charconv>
#include <cmath>
#include <cstdio>

#include "ssta/core/error.h"

namespace ssta::internal {

std::string JsonQuote(std::string_view text) { return "\"" + JsonEscape(text) + "\""; }

void JsonWriter::NewLine() {
  out_ += '\n';
  out_.append(2 * scopes_.size(), ' ');
}

void JsonWriter::BeforeValue() {
  if (scopes_.empty()) {
    SSTA_CHECK(out_.empty(), "JsonWriter: one top-level value only");
    return;
  }
  Scope& scope = scopes_.back();
  if (scope.is_object) {
    SSTA_CHECK(after_key_, "JsonWriter: a value inside an object needs a key");
    after_key_ = false;
    return;
  }
  if (!scope.empty) out_ += scope.is_inline ? ", " : ",";
  if (!scope.is_inline) NewLine();
  scope.empty = false;
}

void JsonWriter::Key(std::string_view key) {
  SSTA_CHECK(!scopes_.empty() && scopes_.back().is_object && !after_key_,
             "JsonWriter: a key belongs directly inside an object");
  Scope& scope = scopes_.back();
  if (!scope.empty) out_ += ',';
  NewLine();
  scope.empty = false;
  out_ += JsonQuote(key);
  out_ += ": ";
  after_key_ = true;
}

void JsonWriter::Begin(char bracket, bool is_object, bool is_inline) {
  BeforeValue();
  out_ += bracket;
  scopes_.push_back({is_object, is_inline, true});
}

void JsonWriter::End(char bracket, bool is_object) {
  SSTA_CHECK(!scopes_.empty() && scopes_.back().is_object == is_object && !after_key_,
             "JsonWriter: unbalanced End");
  const Scope scope = scopes_.back();
  scopes_.pop_back();
  if (!scope.empty && !scope.is_inline) NewLine();
  out_ += bracket;
}

void JsonWriter::BeginObject() { Begin('{', true, false); }
void JsonWriter::EndObject() { End('}', true); }
void JsonWriter::BeginArray() { Begin('[', false, false); }
void JsonWriter::BeginInlineArray() { Begin('[', false, true); }
void JsonWriter::EndArray() { End(']', false); }

void JsonWriter::String(std::string_view value) {
  BeforeValue();
  out_ += JsonQuote(value);
}

void JsonWriter::Number(double value) {
  BeforeValue();
  if (!std::isfinite(value)) {
    out_ += "null";
    return;
  }
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  out_.append(buffer, result.ptr);
}

void JsonWriter::Integer(std::int64_t value) {
  BeforeValue();
  out_ += std::to_string(value);
}

void JsonWriter::Null() {
  BeforeValue();
  out_ += "null";
}

void JsonWriter::Bool(bool value) {
  BeforeValue();
  out_ += value ? "true" : "false";
}

std::string JsonWriter::Take() {
  SSTA_CHECK(scopes_.empty() && !after_key_, "JsonWriter: document not closed");
  out_ += '\n';
  return std::move(out_);
}

void JsonWriter::MatrixRows(const Eigen::MatrixXd& m) {
  BeginArray();
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    BeginInlineArray();
    for (Eigen::Index c = 0; c < m.cols(); ++c) Number(m(r, c));
    EndArray();
  }
  EndArray();
}

}  // namespace ssta::internal
