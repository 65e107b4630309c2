#pragma once

// A small streaming JSON writer (pretty-printed, two-space indent): every JSON file and summary
// SSTA writes (reports, eval metrics, benchmarks) goes through it, so no module needs a JSON
// library. Misuse (a value without a key inside an object, unbalanced
// End calls) is a programmer error and is checked.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

namespace ssta::internal {

class JsonWriter {
 public:
  void BeginObject();
  void EndObject();
  /// An array whose elements go one per line.
  void BeginArray();
  /// An array written on one line (short lists of numbers: matrix rows).
  void BeginInlineArray();
  void EndArray();

  /// The key of the next value; only inside an object.
  void Key(std::string_view key);
  void String(std::string_view value);
  /// Finite numbers in the shortest form that reads back exactly; NaN and infinities as null.
  void Number(double value);
  void Integer(std::int64_t value);
  void Null();
  void Bool(bool value);
  /// A matrix as an array of rows, one row per line (e.g. a 4x4 transform).
  void MatrixRows(const Eigen::MatrixXd& m);

  /// The document; precondition: every Begin has its End.
  std::string Take();

 private:
  struct Scope {
    bool is_object = false;
    bool is_inline = false;
    bool empty = true;
  };
  void BeforeValue();
  void Begin(char bracket, bool is_object, bool is_inline);
  void End(char bracket, bool is_object);
  void NewLine();

  std::string out_;
  std::vector<Scope> scopes_;
  bool after_key_ = false;
};

/// `text` as a quoted JSON string with escapes.
std::string JsonQuote(std::string_view text);

}  // namespace ssta::internal
