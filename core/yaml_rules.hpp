// The rules an options struct states on a field's value (`yaml::positive()`, `in_range(0, 1)`,
// `required("...")`, ...): one `Check` per rule, combined with `&`, and each rule written once
// for every archive of core/yaml_io.hpp that acts on it (the reader's messages, the
// validator's, the generated reference). Included by core/yaml_io.hpp; options headers need
// nothing else.
#pragma once

#include <cstddef>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace driftlab::yaml {

/// A value constraint. Numeric bounds apply to numbers (each element of a
/// sequence); size bounds apply to sequences and strings.
struct Check {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_open = false;  // true: value must be > lo
  bool hi_open = false;  // true: value must be < hi
  std::size_t min_size = 0;
  std::size_t max_size = std::numeric_limits<std::size_t>::max();
  bool non_empty_string = false;
  /// Strings (and the strings of a list) must be one of these names, asked for when the
  /// value is checked: a list that grows at run time (e.g. the VOs a program registers).
  std::function<std::vector<std::string>()> choices{};
  /// A rule on a string's text: "" when it holds, else what is expected, in words (e.g. the
  /// placeholders a command may hold). Checked as the value is read, like `choices`.
  std::function<std::string(const std::string&)> text_rule{};
  /// Why the bounds are what they are (a plausible range's reason), shown after them in
  /// messages and in the reference.
  std::string why{};
  /// The key must be present (readers report "missing, expected EXPECTED").
  bool required = false;
  /// What is expected, in words, replacing the generated text in messages (the value is
  /// then quoted as written: "got '-1', expected a number >= 0").
  std::string expected{};

  /// Combine two checks (both must hold).
  Check operator&(const Check& o) const;
  /// Human-readable description of what is expected, e.g. "> 0" or "in [0, 1]".
  std::string describe() const;
  bool has_bounds() const;
  /// The range rule, written once for the reader and the validator: "" when `v` lies within
  /// the bounds, else what is expected in words ("a value in [0, 1] (why)").
  std::string out_of_range(double v) const;
};

inline Check none() { return {}; }
inline Check positive() { return {.lo = 0, .lo_open = true}; }
inline Check non_negative() { return {.lo = 0}; }
inline Check at_least(double v) { return {.lo = v}; }
inline Check greater_than(double v) { return {.lo = v, .lo_open = true}; }
inline Check at_most(double v) { return {.hi = v}; }
inline Check in_range(double lo, double hi) { return {.lo = lo, .hi = hi}; }
inline Check unit_interval() { return in_range(0.0, 1.0); }
/// An upper bound on what a user could mean, with the reason: combine with a lower bound,
/// e.g. `yaml::positive() & yaml::up_to(2000, "wider than any surveyed river")`. Values past
/// it are rejected before any work starts (a 1e308 m river would never finish building).
inline Check up_to(double hi, std::string why) { return {.hi = hi, .why = std::move(why)}; }
/// A closed range of plausible values with the reason.
inline Check plausible(double lo, double hi, std::string why) {
  return {.lo = lo, .hi = hi, .why = std::move(why)};
}
inline Check min_size(std::size_t n) { return {.min_size = n}; }
inline Check size_between(std::size_t lo, std::size_t hi) {
  return {.min_size = lo, .max_size = hi};
}
inline Check non_empty() { return {.min_size = 1, .non_empty_string = true}; }
inline Check one_of(std::function<std::vector<std::string>()> names) {
  return {.choices = std::move(names)};
}
/// A string must satisfy `rule` (see Check::text_rule).
inline Check text_rule(std::function<std::string(const std::string&)> rule) {
  return {.text_rule = std::move(rule)};
}
/// The key must be given; `expected` says what in words.
inline Check required(std::string expected) {
  return {.required = true, .expected = std::move(expected)};
}
/// Messages say `expected` instead of the generated description.
inline Check expecting(std::string expected) { return {.expected = std::move(expected)}; }
/// "one of: a, b, c" when `name` is not among check.choices(); empty when it is (or no choices).
std::string unknown_choice(const Check& check, const std::string& name);

}  // namespace driftlab::yaml
