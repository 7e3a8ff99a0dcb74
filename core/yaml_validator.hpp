// The validator of core/yaml_io.hpp: a struct built in code checked by the reader's rules.
#pragma once

#include "core/yaml_common.hpp"

namespace driftlab::yaml {

// ---------------------------------------------------------------------------
// Validation of a struct built in code (same rules as the reader).

class Validator : public IgnoresRules {
 public:
  Validator(std::string prefix, ErrorList* errors) : prefix_(std::move(prefix)), errors_(errors) {}

  template <class T>
  void operator()(const char* key, const T& value, const char*, const Check& check = {}) {
    check_value(path(key), value, check);
  }
  void require(bool ok, const char* key, std::string_view expected);

 private:
  std::string path(std::string_view key) const;
  void check_double(const std::string& key_path, double v, const Check& check);
  template <class T>
  void check_value(const std::string& key_path, const T& value, const Check& check);

  std::string prefix_;
  ErrorList* errors_;
};

template <class T>
void Validator::check_value(const std::string& key_path, const T& value, const Check& check) {
  if constexpr (is_std_optional<T>::value) {
    if (value) check_value(key_path, *value, check);
  } else if constexpr (is_entries<T>::value) {
    for (const auto& e : value) check_value(key_path + "." + e.key, e.value, check);
  } else if constexpr (std::is_same_v<T, NamedOptions>) {
    for (const auto& [name, holder] : value.entries()) {
      Validator sub(key_path + "." + name, errors_);
      holder->accept(sub);
    }
  } else if constexpr (std::is_floating_point_v<T> ||
                       (std::is_integral_v<T> && !std::is_same_v<T, bool>)) {
    check_double(key_path, static_cast<double>(value), check);
  } else if constexpr (std::is_same_v<T, std::string>) {
    if (check.non_empty_string && value.empty())
      errors_->add_at(key_path, key_path + ": got an empty string, expected a non-empty string");
    else if (const std::string expected = unknown_choice(check, value); !expected.empty())
      errors_->add_at(key_path, key_path + ": got '" + value + "', expected " + expected);
    else if (const std::string rule = check.text_rule ? check.text_rule(value) : ""; !rule.empty())
      errors_->add_at(key_path, key_path + ": got '" + value + "', expected " + rule);
  } else if constexpr (is_std_vector<T>::value || is_std_array<T>::value) {
    if (value.size() < check.min_size || value.size() > check.max_size) {
      Check size_only{.min_size = check.min_size, .max_size = check.max_size};
      errors_->add_at(key_path, key_path + ": got a list of " + std::to_string(value.size()) +
                                    ", expected a list of " + size_only.describe() + " entries");
    }
    Check element_check = check;
    element_check.min_size = 0;
    element_check.max_size = std::numeric_limits<std::size_t>::max();
    for (std::size_t i = 0; i < value.size(); ++i)
      check_value(key_path + "[" + std::to_string(i) + "]", value[i], element_check);
  } else if constexpr (Visitable<T>) {
    Validator sub(key_path, errors_);
    const_cast<T&>(value).visit(sub);
  }
}

/// Checks every field's constraint and every cross-field rule; returns the
/// problems found, each with the key path it is about.
template <Visitable T>
std::vector<Problem> validation_problems(const T& value, const std::string& prefix = "") {
  ErrorList errors;
  Validator v(prefix, &errors);
  const_cast<T&>(value).visit(v);
  return errors.problems();
}

/// validation_problems() as text: one message per line ("" when valid).
template <Visitable T>
std::string validate(const T& value, const std::string& prefix = "") {
  std::string out;
  for (const Problem& p : validation_problems(value, prefix))
    out += (out.empty() ? "" : "\n") + p.message;
  return out;
}

/// validate() that throws UserError (with `what` as a header) on any problem.
template <Visitable T>
void validate_or_throw(const T& value, const std::string& what) {
  const std::string problems = validate(value);
  if (!problems.empty()) throw UserError(what + ": invalid options:\n" + problems);
}

}  // namespace driftlab::yaml
