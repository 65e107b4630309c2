#pragma once

// Each Options struct describes its fields once, as a list of OptionField: the YAML key, the
// unit, the values it takes and one line of meaning. Reading and writing config files, the map
// file's metadata, validation (IsValid) and `ssta config` (config/default.yaml) all come from
// that list, so a key is written in one place.

#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include <Eigen/Core>

#include "ssta/core/enum_table.h"
#include "ssta/core/error.h"

namespace ssta {

/// What kind of value a field holds, and how files spell it.
enum class OptionKind {
  kReal,     ///< a number
  kInteger,  ///< a whole number
  kFlag,     ///< true or false
  kChoice,   ///< one of a few names
  kVector3,  ///< [x, y, z]
};

/// A field's value as files hold it: numbers (whole ones too) as double, flags as bool, choices
/// as their name, vectors as Vector3d.
using OptionValue = std::variant<double, bool, std::string, Eigen::Vector3d>;

/// The shortest decimal text that reads back as exactly `v` ("0.1", "30", "1e-07").
std::string ShortestDecimal(double v);

/// `value` as a YAML scalar or flow list of `kind` (numbers by ShortestDecimal).
std::string FormatOptionValue(const OptionValue& value, OptionKind kind);

/// An interval of allowed numbers, each end open or closed.
struct Interval {
  double lo = -HUGE_VAL, hi = HUGE_VAL;
  bool lo_open = false, hi_open = false;
  bool Contains(double v) const {
    return (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
  }
  /// "[0, 90)", "(0, inf)".
  std::string Text() const;
};
inline Interval Closed(double lo, double hi) { return {lo, hi, false, false}; }
inline Interval Open(double lo, double hi) { return {lo, hi, true, true}; }
inline Interval OpenClosed(double lo, double hi) { return {lo, hi, true, false}; }
inline Interval ClosedOpen(double lo, double hi) { return {lo, hi, false, true}; }
inline Interval AtLeast(double lo) { return {lo, HUGE_VAL, false, true}; }
inline Interval Above(double lo) { return {lo, HUGE_VAL, true, true}; }

/// One field of an Options struct `O`.
template <class O>
struct OptionField {
  std::string key;
  OptionKind kind = OptionKind::kReal;
  std::string unit;     ///< "m", "deg", "px", "%", ...; empty when it has none
  std::string meaning;  ///< what it does, for people (one sentence or two)
  std::vector<std::string> choices;  ///< kChoice: the names it takes
  std::function<OptionValue(const O&)> get;
  std::function<void(O*, const OptionValue&)> set;
  /// Checked in order by CheckOptions; the message completes "key: ...".
  std::vector<std::pair<std::function<bool(const O&)>, std::function<std::string(const O&)>>> requirements;
  /// Map files written before this key existed omit it and meant this value: writers of map
  /// metadata leave the key out while it holds this value, readers take it when it is absent.
  std::optional<OptionValue> absent_means;

  /// Adds a requirement: `ok(options)` must hold, else "key: message".
  OptionField& Require(std::function<bool(const O&)> ok, std::string message) {
    requirements.emplace_back(std::move(ok), [message](const O&) { return message; });
    return *this;
  }
  /// The same with a message made from the options: a limit set by another key names both
  /// values, since either may be the one at fault.
  OptionField& Require(std::function<bool(const O&)> ok, std::function<std::string(const O&)> message) {
    requirements.emplace_back(std::move(ok), std::move(message));
    return *this;
  }
  OptionField& AbsentMeans(OptionValue value) {
    absent_means = std::move(value);
    return *this;
  }
  /// The same field on a struct that holds an `O` in `member` (a section made of two structs).
  template <class Outer>
  OptionField<Outer> Within(O Outer::*member) const;
};

template <class O>
using OptionFields = std::vector<OptionField<O>>;

namespace internal {
inline std::string IntervalMessage(const Interval& range, const std::string& unit, const char* what) {
  return std::string("must be ") + what + " in " + range.Text() + (unit.empty() ? "" : " " + unit);
}
}  // namespace internal

/// A number in `range`.
template <class O>
OptionField<O> Real(std::string key, double O::*member, Interval range, std::string unit, std::string meaning) {
  OptionField<O> f;
  f.key = std::move(key);
  f.kind = OptionKind::kReal;
  f.unit = std::move(unit);
  f.meaning = std::move(meaning);
  f.get = [member](const O& o) { return OptionValue(o.*member); };
  f.set = [member](O* o, const OptionValue& v) { o->*member = std::get<double>(v); };
  f.Require([member, range](const O& o) { return std::isfinite(o.*member) && range.Contains(o.*member); },
            internal::IntervalMessage(range, f.unit, "a number"));
  return f;
}

/// A whole number in `range`.
template <class O>
OptionField<O> Integer(std::string key, int O::*member, Interval range, std::string unit, std::string meaning) {
  OptionField<O> f;
  f.key = std::move(key);
  f.kind = OptionKind::kInteger;
  f.unit = std::move(unit);
  f.meaning = std::move(meaning);
  f.get = [member](const O& o) { return OptionValue(static_cast<double>(o.*member)); };
  f.set = [member](O* o, const OptionValue& v) { o->*member = static_cast<int>(std::get<double>(v)); };
  f.Require([member, range](const O& o) { return range.Contains(o.*member); },
            internal::IntervalMessage(range, f.unit, "a whole number"));
  return f;
}

/// 0 (off) or an odd whole number in `range` (a window side).
template <class O>
OptionField<O> OddOrOff(std::string key, int O::*member, Interval range, std::string unit, std::string meaning) {
  OptionField<O> f = Integer<O>(std::move(key), member, range, std::move(unit), std::move(meaning));
  f.requirements.clear();
  f.Require([member, range](const O& o) { return o.*member == 0 || (o.*member % 2 == 1 && range.Contains(o.*member)); },
            "must be 0 (off) or odd in " + range.Text() + (f.unit.empty() ? "" : " " + f.unit));
  return f;
}

/// true or false.
template <class O>
OptionField<O> Flag(std::string key, bool O::*member, std::string meaning) {
  OptionField<O> f;
  f.key = std::move(key);
  f.kind = OptionKind::kFlag;
  f.meaning = std::move(meaning);
  f.get = [member](const O& o) { return OptionValue(o.*member); };
  f.set = [member](O* o, const OptionValue& v) { o->*member = std::get<bool>(v); };
  return f;
}

/// One of the names in `names` (value, name), for an enum field.
template <class O, class E>
OptionField<O> Choice(std::string key, E O::*member, std::vector<std::pair<E, std::string>> names,
                      std::string meaning) {
  OptionField<O> f;
  f.key = std::move(key);
  f.kind = OptionKind::kChoice;
  f.meaning = std::move(meaning);
  for (const auto& n : names) f.choices.push_back(n.second);
  f.get = [member, names](const O& o) {
    for (const auto& n : names) {
      if (n.first == o.*member) return OptionValue(n.second);
    }
    return OptionValue(std::string("?"));
  };
  f.set = [member, names](O* o, const OptionValue& v) {
    for (const auto& n : names) {
      if (n.second == std::get<std::string>(v)) o->*member = n.first;
    }
  };
  return f;
}

/// One of `values`, spelt as `name` spells them.
template <class O, class E, class NameOf>
OptionField<O> Choice(std::string key, E O::*member, const std::vector<E>& values, NameOf name,
                      std::string meaning) {
  std::vector<std::pair<E, std::string>> names;
  for (const E& v : values) names.emplace_back(v, std::string(name(v)));
  return Choice<O, E>(std::move(key), member, std::move(names), std::move(meaning));
}

/// One of the names of `table` (enum_table.h), in its order.
template <class O, class E>
OptionField<O> Choice(std::string key, E O::*member, const EnumTable<E>& table, std::string meaning) {
  return Choice<O, E>(std::move(key), member, table.entries(), std::move(meaning));
}

/// A 3-vector of finite numbers.
template <class O>
OptionField<O> Vector3(std::string key, Eigen::Vector3d O::*member, std::string unit, std::string meaning) {
  OptionField<O> f;
  f.key = std::move(key);
  f.kind = OptionKind::kVector3;
  f.unit = std::move(unit);
  f.meaning = std::move(meaning);
  f.get = [member](const O& o) { return OptionValue(Eigen::Vector3d(o.*member)); };
  f.set = [member](O* o, const OptionValue& v) { o->*member = std::get<Eigen::Vector3d>(v); };
  f.Require([member](const O& o) { return (o.*member).allFinite(); }, "must be three finite numbers");
  return f;
}

template <class O>
template <class Outer>
OptionField<Outer> OptionField<O>::Within(O Outer::*member) const {
  OptionField<Outer> f;
  f.key = key;
  f.kind = kind;
  f.unit = unit;
  f.meaning = meaning;
  f.choices = choices;
  f.absent_means = absent_means;
  f.get = [member, get = get](const Outer& o) { return get(o.*member); };
  f.set = [member, set = set](Outer* o, const OptionValue& v) { set(&(o->*member), v); };
  for (const auto& [ok, message] : requirements) {
    f.requirements.emplace_back([member, ok = ok](const Outer& o) { return ok(o.*member); },
                                [member, message = message](const Outer& o) { return message(o.*member); });
  }
  return f;
}

/// The first requirement of `fields` that `options` breaks, as "key: message" in `*error`;
/// true when there is none.
template <class O>
bool CheckOptions(const O& options, const OptionFields<O>& fields, std::string* error) {
  for (const OptionField<O>& f : fields) {
    for (const auto& [ok, message] : f.requirements) {
      if (!ok(options)) return Fail(error, f.key + ": " + message(options));
    }
  }
  return true;
}

/// The first field whose values differ between `a` and `b` (numbers by a relative tolerance of
/// 1e-9); null when none does.
template <class O>
const OptionField<O>* FirstDifferingField(const O& a, const O& b, const OptionFields<O>& fields) {
  for (const OptionField<O>& f : fields) {
    const OptionValue va = f.get(a), vb = f.get(b);
    if (const double* x = std::get_if<double>(&va)) {
      const double y = std::get<double>(vb);
      if (std::abs(*x - y) > 1e-9 * std::max(1.0, std::abs(y))) return &f;
    } else if (va != vb) {
      return &f;
    }
  }
  return nullptr;
}

}  // namespace ssta
