// The strict reader of core/yaml_io.hpp: a YAML document onto a visitable struct, every problem
// named with its file, line, key path, value and what was expected.
#pragma once

#include "core/yaml_common.hpp"

namespace driftlab::yaml {

/// Reads a YAML map onto a visitable struct. Keys absent in the document keep
/// the struct's current values (defaults, or values read earlier), so the same
/// reader applies `--set` overrides on top of a loaded file.
class Reader {
 public:
  Reader(const YAML::Node& map, const Source& source, std::string key_prefix, ErrorList* errors);

  template <class T>
  void operator()(const char* key, T& value, const char* /*doc*/, const Check& check = {}) {
    YAML::Node node = find(key);
    if (!node) {
      if (check.required && check_rules_) missing(key, check);  // partial documents: later
      return;
    }
    read_value(node, path(key), value, check);
  }

  /// Cross-field rule, evaluated with the values read so far (write it after the fields).
  /// Skipped for a required key found missing (that message already says what is expected).
  void require(bool ok, const char* key, std::string_view expected);
  /// Exactly one of these keys must be present ("got both values and range").
  void exactly_one_of(std::initializer_list<const char*> keys);
  /// "FILE:LINE:COL" of the mapping being read, or of the value of `key` (the mapping's
  /// when the key is absent).
  void location(std::string* out) const { *out = where(map_); }
  void location(const char* key, std::string* out) const;
  void set_check_rules(bool on) { check_rules_ = on; }

  /// Runs `f` now: lets a struct react to a value just read (e.g. a preset
  /// that resets the fields read after it). Other archives ignore it.
  template <class F>
  void when_reading(F&& f) {
    f();
  }

  /// Reports keys of the map that no field consumed.
  void finish();

  /// "FILE:LINE:COL" (or the source label) of a node.
  std::string where(const YAML::Node& node) const;

 private:
  YAML::Node find(const char* key);
  YAML::Node value_of(std::string_view key) const;  // Undefined when absent
  void missing(const char* key, const Check& check);
  std::string path(std::string_view key) const;
  void fail(const YAML::Node& node, const std::string& key_path, const std::string& got,
            const std::string& expected);

  template <class T>
  void read_value(const YAML::Node& node, const std::string& key_path, T& value,
                  const Check& check);
  template <class T>
  void read_entries(const YAML::Node& node, const std::string& key_path, Entries<T>& value,
                    const Check& check);
  void read_named(const YAML::Node& node, const std::string& key_path, NamedOptions& value);

  bool read_scalar_text(const YAML::Node& node, const std::string& key_path, const char* expected,
                        std::string* text);
  void check_number(const YAML::Node& node, const std::string& key_path, double v,
                    const Check& check);

  YAML::Node map_;
  std::vector<std::pair<YAML::Node, YAML::Node>> entries_;
  Source source_;
  std::string prefix_;
  ErrorList* errors_;
  std::vector<std::string> seen_;
  std::vector<std::string> missing_;  // required keys found missing
  bool check_rules_ = true;
};

// Parsing helpers (strict): return false on any trailing garbage.
bool parse_double(std::string_view text, double* out);
bool parse_int64(std::string_view text, std::int64_t* out);
bool parse_uint64(std::string_view text, std::uint64_t* out);
/// Describes a scalar for messages: 'abc', or "NaN" for a non-finite value.
std::string describe_node(const YAML::Node& node);

template <class T>
void Reader::read_value(const YAML::Node& node, const std::string& key_path, T& value,
                        const Check& check) {
  if constexpr (is_std_optional<T>::value) {
    // Null is "not given", and so is a value that did not read (its error is reported).
    if (node.IsNull()) {
      value.reset();
      return;
    }
    typename T::value_type v = value.value_or(typename T::value_type{});
    const std::size_t errors_before = errors_->messages().size();
    read_value(node, key_path, v, check);
    if (errors_->messages().size() == errors_before)
      value = std::move(v);
    else
      value.reset();
  } else if constexpr (std::is_same_v<T, Any>) {
    value.node.reset(node);
    value.where = where(node);
  } else if constexpr (is_entries<T>::value) {
    read_entries(node, key_path, value, check);
  } else if constexpr (std::is_same_v<T, NamedOptions>) {
    read_named(node, key_path, value);
  } else if constexpr (std::is_same_v<T, bool>) {
    std::string text;
    if (!read_scalar_text(node, key_path, "true or false", &text)) return;
    if (text == "true") {
      value = true;
    } else if (text == "false") {
      value = false;
    } else {
      fail(node, key_path, "'" + text + "'", "true or false");
    }
  } else if constexpr (std::is_same_v<T, double>) {
    const std::string said = check.expected.empty() ? "a number" : check.expected;
    std::string text;
    if (!read_scalar_text(node, key_path, said.c_str(), &text)) return;
    double v = 0;
    if (!parse_double(text, &v)) {
      fail(node, key_path, "'" + text + "'", said);
      return;
    }
    if (!std::isfinite(v)) {
      fail(node, key_path, "'" + text + "'",
           check.expected.empty() ? "a finite number" : check.expected);
      return;
    }
    check_number(node, key_path, v, check);
    value = v;
  } else if constexpr (std::is_integral_v<T>) {
    std::string text;
    if (!read_scalar_text(node, key_path,
                          check.expected.empty() ? "an integer" : check.expected.c_str(), &text))
      return;
    std::int64_t v = 0;
    if constexpr (std::is_unsigned_v<T>) {
      std::uint64_t u = 0;
      if (!parse_uint64(text, &u) || u > std::numeric_limits<T>::max()) {
        fail(node, key_path, "'" + text + "'",
             check.expected.empty() ? "a non-negative integer" : check.expected);
        return;
      }
      check_number(node, key_path, static_cast<double>(u), check);
      value = static_cast<T>(u);
    } else {
      if (!parse_int64(text, &v) || v < std::numeric_limits<T>::min() ||
          v > std::numeric_limits<T>::max()) {
        fail(node, key_path, "'" + text + "'",
             check.expected.empty() ? "an integer" : check.expected);
        return;
      }
      check_number(node, key_path, static_cast<double>(v), check);
      value = static_cast<T>(v);
    }
  } else if constexpr (std::is_same_v<T, std::string>) {
    std::string text;
    if (!read_scalar_text(node, key_path,
                          check.expected.empty() ? "a string" : check.expected.c_str(), &text))
      return;
    if (check.non_empty_string && text.empty()) {
      fail(node, key_path, "an empty string",
           check.expected.empty() ? "a non-empty string" : check.expected);
      return;
    }
    if (const std::string expected = unknown_choice(check, text); !expected.empty()) {
      fail(node, key_path, "'" + text + "'", expected);
      return;
    }
    if (const std::string expected = check.text_rule ? check.text_rule(text) : "";
        !expected.empty()) {
      fail(node, key_path, "'" + text + "'", expected);
      return;
    }
    value = text;
  } else if constexpr (Enum<T>) {
    const std::string expected = "one of: " + enum_choices<T>();
    std::string text;
    if (!read_scalar_text(node, key_path, expected.c_str(), &text)) return;
    auto v = enum_from_name<T>(text);
    if (!v) {
      fail(node, key_path, "'" + text + "'", expected);
      return;
    }
    value = *v;
  } else if constexpr (is_std_vector<T>::value || is_std_array<T>::value) {
    if (!node.IsSequence()) {
      fail(node, key_path, describe_node(node), "a list");
      return;
    }
    const std::size_t n = node.size();
    if constexpr (is_std_array<T>::value) {
      if (n != std::tuple_size_v<T>) {
        fail(node, key_path, "a list of " + std::to_string(n),
             "a list of exactly " + std::to_string(std::tuple_size_v<T>) + " values");
        return;
      }
    } else {
      if (n < check.min_size || n > check.max_size) {
        Check size_only{.min_size = check.min_size, .max_size = check.max_size};
        fail(node, key_path, "a list of " + std::to_string(n),
             "a list of " + size_only.describe() + " entries");
        return;
      }
    }
    T out{};
    if constexpr (is_std_vector<T>::value) out.resize(n);
    Check element_check = check;
    element_check.min_size = 0;
    element_check.max_size = std::numeric_limits<std::size_t>::max();
    for (std::size_t i = 0; i < n; ++i)
      read_value(node[i], key_path + "[" + std::to_string(i) + "]", out[i], element_check);
    value = std::move(out);
  } else if constexpr (Visitable<T>) {
    if (!node.IsMap()) {
      fail(node, key_path, describe_node(node), "a mapping of keys to values");
      return;
    }
    Reader sub(node, source_, key_path, errors_);
    sub.set_check_rules(check_rules_);
    value.visit(sub);
    sub.finish();
  } else {
    static_assert(sizeof(T) == 0, "unsupported field type for yaml::Reader");
  }
}

template <class T>
void Reader::read_entries(const YAML::Node& node, const std::string& key_path, Entries<T>& value,
                          const Check& check) {
  if (!node.IsMap()) {
    fail(node, key_path, describe_node(node),
         check.expected.empty() ? "a mapping of names to values" : check.expected);
    return;
  }
  Entries<T> out;
  for (const auto& kv : node) {
    const YAML::Node k = kv.first;
    if (!k.IsScalar() || k.Scalar().empty()) {
      fail(k, key_path, describe_node(k), "a plain, non-empty name");
      continue;
    }
    const std::string name = k.Scalar();
    if (std::any_of(out.begin(), out.end(), [&](const auto& e) { return e.key == name; })) {
      errors_->add(where(k) + ": " + key_path + "." + name +
                   ": duplicate key, expected each key once");
      continue;
    }
    Entry<T> e{.key = name, .where = where(k)};
    Check element_check = check;
    element_check.expected.clear();
    read_value(kv.second, key_path + "." + name, e.value, element_check);
    out.push_back(std::move(e));
  }
  value = std::move(out);
}

/// Reads `node` (a map) onto `value`, throwing UserError listing every problem.
/// With `check_rules` false the cross-field rules (require()) are skipped: for
/// partial documents such as one `--set` among several, whose rules only hold
/// once all are applied (validate() checks them at the end).
template <Visitable T>
void read_into(const YAML::Node& node, const Source& source, T* value, bool check_rules = true) {
  ErrorList errors;
  if (!node.IsMap()) {
    errors.add(source.name + ": expected a mapping of keys to values at the top level, got " +
               describe_node(node));
  } else {
    Reader reader(node, source, "", &errors);
    reader.set_check_rules(check_rules);
    value->visit(reader);
    reader.finish();
  }
  errors.throw_if_any();
}

/// Loads a YAML file (clear errors for a missing file and for syntax errors).
YAML::Node load_file(const std::string& path);
/// Parses YAML text; `label` names it in errors.
YAML::Node load_string(const std::string& text, const std::string& label);

/// Builds the one-key document {a: {b: {c: VALUE}}} for an override "a.b.c=VALUE".
/// VALUE is parsed as YAML, so lists ("[sparse, pnp]") and numbers work.
YAML::Node override_document(const std::string& assignment);

}  // namespace driftlab::yaml
