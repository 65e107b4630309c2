#pragma once

// One {value, name} table per enum, as written in config files and on the command line: its
// Parse, its Name and its config choice list (option_fields.h's Choice) all read it, so a name
// is written once.

#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

#include "ssta/core/error.h"

namespace ssta {

template <class E>
class EnumTable {
 public:
  /// `key` names the setting in messages ("refinement.robust_loss"); `entries` in the order the
  /// choices are listed.
  EnumTable(std::string key, std::initializer_list<std::pair<E, const char*>> entries) : key_(std::move(key)) {
    for (const auto& [value, name] : entries) entries_.emplace_back(value, name);
  }

  /// The value spelt `name`. Throws ssta::Error "KEY: 'NAME' is not one of A, B, C".
  E Parse(const std::string& name) const {
    for (const auto& [value, n] : entries_) {
      if (n == name) return value;
    }
    throw Error(key_ + ": '" + name + "' is not one of " + NameList());
  }

  /// The name of `value`. Precondition: `value` is in the table (always checked).
  const std::string& Name(E value) const {
    for (const auto& [v, name] : entries_) {
      if (v == value) return name;
    }
    SSTA_CHECK(false, key_ + ": a value outside its enum");
    return entries_.front().second;
  }

  /// "A, B, C".
  std::string NameList() const {
    std::string out;
    for (const auto& [value, name] : entries_) out += (out.empty() ? "" : ", ") + name;
    return out;
  }

  const std::string& key() const { return key_; }
  const std::vector<std::pair<E, std::string>>& entries() const { return entries_; }

 private:
  std::string key_;
  std::vector<std::pair<E, std::string>> entries_;
};

}  // namespace ssta
