// Strict YAML <-> options-struct mapping (Drake's yaml_io in spirit, our own code).
//
// An options struct lists its fields once, in a `visit` member template:
//
//   struct RigOptions {
//     double baseline_m = 0.12;
//     int width_px = 640;
//     template <class A> void visit(A& a) {
//       a("baseline_m", baseline_m, "Stereo baseline [m]", yaml::positive());
//       a("width_px", width_px, "Image width [px]", yaml::at_least(1));
//       a.require(width_px % 2 == 0, "width_px", "an even width");
//     }
//   };
//
// and that one list drives reading (strict: unknown keys, wrong types, NaN and
// out-of-range values are errors naming file, line, key path, value and what
// was expected), writing (every field, defaults filled in), validation of a
// struct built in code, and the generated reference documentation.
//
// Supported field types: bool, int, int64_t, uint64_t, double, std::string, enums
// with an ADL `enum_table(E)` (array of {E, "name"} pairs), nested visitable
// structs, std::vector<T> and std::array<T, N> of any of these, std::optional<T>
// (absent or null: nullopt), yaml::Any (any YAML value, kept as written) and
// yaml::Entries<T> (a mapping of names of the user's choosing to T, in file order).
//
// Besides fields, visit() may state rules across them, which only the archives that need
// them act on:
//   a.require(ok, "key", "what is expected");       // reader, validator, reference
//   a.exactly_one_of({"values", "range"});           // reader (presence), reference
//   a.location(&where); a.location("key", &where);   // reader: "FILE:LINE:COL" of the
//                                                    // mapping, or of a key's value
// Every input file is read this way (scenarios, sweeps, CI baselines): one strict reader.
#pragma once

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include "core/enum_names.hpp"
#include "core/error.hpp"
#include "core/yaml_rules.hpp"

namespace driftlab::yaml {

// ---------------------------------------------------------------------------
// Type traits.

template <class T>
struct is_std_vector : std::false_type {};
template <class T, class Alloc>
struct is_std_vector<std::vector<T, Alloc>> : std::true_type {};

template <class T>
struct is_std_array : std::false_type {};
template <class T, std::size_t N>
struct is_std_array<std::array<T, N>> : std::true_type {};

template <class T>
struct is_std_optional : std::false_type {};
template <class T>
struct is_std_optional<std::optional<T>> : std::true_type {};

/// Any YAML value, kept as written, with where it was ("FILE:LINE:COL"): sweep levels and
/// fixed scenario values, read and checked later against the scenario they apply to.
struct Any {
  YAML::Node node;
  std::string where;

  Any() = default;
  Any(const Any& o) : node(o.node), where(o.where) {}
  // yaml-cpp's Node::operator= writes through to the node it refers to; reset() rebinds.
  Any& operator=(const Any& o) {
    node.reset(o.node);
    where = o.where;
    return *this;
  }
  /// YAML text for a KEY=VALUE override: a scalar as written, lists and mappings in flow
  /// style ("[1, 2]", "{a: 1}").
  std::string flow_text() const;
};

/// One entry of a mapping whose keys the user names (e.g. scenario key paths -> values).
template <class T>
struct Entry {
  std::string key;
  T value{};
  std::string where;  ///< "FILE:LINE:COL" of the key
};
template <class T>
using Entries = std::vector<Entry<T>>;

template <class T>
struct is_entries : std::false_type {};
template <class T, class Alloc>
struct is_entries<std::vector<Entry<T>, Alloc>> : std::true_type {};

class Reader;
class Writer;
class Validator;
class SchemaBuilder;

/// A mapping of names to options structs whose type each name decides at run time: the
/// options of plug-ins registered by name (pipeline.plugins.my_vo.KEY). Read, written,
/// validated and documented like nested structs; reading a name again reads onto what it
/// holds, so `--set a.NAME.KEY=V` changes one key and keeps the rest.
class NamedOptions {
 public:
  /// One name's options struct (make_options<T>() makes one).
  class Holder {
   public:
    virtual ~Holder() = default;
    virtual std::unique_ptr<Holder> clone() const = 0;
    virtual void accept(Reader& archive) = 0;
    virtual void accept(Writer& archive) const = 0;
    virtual void accept(Validator& archive) const = 0;
    virtual void accept(SchemaBuilder& archive) const = 0;
  };
  /// The options of `name` at their defaults, or null for a name without options.
  using Maker = std::function<std::unique_ptr<Holder>(const std::string& name)>;
  /// Every name with options (for messages and the reference).
  using Names = std::function<std::vector<std::string>()>;

  NamedOptions() = default;
  NamedOptions(Maker maker, Names names) : maker_(std::move(maker)), names_(std::move(names)) {}
  NamedOptions(const NamedOptions& o);
  NamedOptions& operator=(const NamedOptions& o);
  NamedOptions(NamedOptions&&) noexcept = default;
  NamedOptions& operator=(NamedOptions&&) noexcept = default;

  bool empty() const { return entries_.empty(); }
  /// The options given for `name`, or null when none were.
  const Holder* find(const std::string& name) const;
  /// The options of `name`, made at their defaults when not there yet; null for a name that
  /// has no options.
  Holder* find_or_make(const std::string& name);
  /// Every name with options (not only those given).
  std::vector<std::string> known_names() const {
    return names_ ? names_() : std::vector<std::string>{};
  }
  /// A fresh holder of `name`'s defaults, or null.
  std::unique_ptr<Holder> make(const std::string& name) const {
    return maker_ ? maker_(name) : nullptr;
  }
  /// The names given, in the order first read, with their options.
  const std::vector<std::pair<std::string, std::unique_ptr<Holder>>>& entries() const {
    return entries_;
  }

 private:
  Maker maker_;
  Names names_;
  std::vector<std::pair<std::string, std::unique_ptr<Holder>>> entries_;
};

struct ProbeArchive;  // used only to detect visitable structs

template <class T>
concept Visitable = requires(T& t, ProbeArchive& a) {
  t.visit(a);
};

template <class T>
struct is_vector_of_visitable : std::false_type {};
template <Visitable T, class Alloc>
struct is_vector_of_visitable<std::vector<T, Alloc>> : std::true_type {};

template <class T>
concept OptionalOfVisitable = is_std_optional<T>::value && Visitable<typename T::value_type>;

// The rules and locations every archive accepts; those that do not act on them inherit
// these no-ops.
struct IgnoresRules {
  void require(bool, const char*, std::string_view) {}
  void exactly_one_of(std::initializer_list<const char*>) {}
  void location(std::string*) {}
  void location(const char*, std::string*) {}
  template <class F>
  void when_reading(F&&) {}
};

struct ProbeArchive : IgnoresRules {
  template <class T>
  void operator()(const char*, T&, const char*, const Check& = {}) {}
};

// ---------------------------------------------------------------------------
// Number formatting shared by the writer and the messages.

/// Shortest text that reads back to the same double ("0.1", "1e-09", "nan").
std::string format_double(double v);

/// Edit distance, for "did you mean" suggestions on unknown keys.
std::size_t edit_distance(std::string_view a, std::string_view b);

// ---------------------------------------------------------------------------
// Reader.

/// Where the document came from: a file path or a label such as "--set a.b=1".
struct Source {
  std::string name;
  bool is_file = true;
};

/// One problem: the key path it is about ("mission.waypoints_ne_m[3]"; empty when it names
/// none, or when the message already says where in a file) and the message, which starts
/// with it.
struct Problem {
  std::string path;
  std::string message;
};

/// Collects every problem found while reading, then throws them together.
class ErrorList {
 public:
  void add(std::string message) { add_at({}, std::move(message)); }
  /// A problem about the key at `path`.
  void add_at(std::string path, std::string message) {
    messages_.push_back(message);
    problems_.push_back({std::move(path), std::move(message)});
  }
  bool empty() const { return messages_.empty(); }
  const std::vector<std::string>& messages() const { return messages_; }
  const std::vector<Problem>& problems() const { return problems_; }
  /// Throws UserError with all messages (one per line) if any were added.
  void throw_if_any(std::string_view header = {}) const;

 private:
  std::vector<std::string> messages_;
  std::vector<Problem> problems_;
};

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

// ---------------------------------------------------------------------------
// Writer: every field, in visit order, with its doc as a trailing comment.

class Writer : public IgnoresRules {
 public:
  explicit Writer(int indent = 0, bool comments = true) : indent_(indent), comments_(comments) {}

  template <class T>
  void operator()(const char* key, const T& value, const char* doc, const Check& = {}) {
    write_field(key, value, doc);
  }

  const std::string& str() const { return out_; }

 private:
  template <class T>
  static std::string scalar(const T& value);
  template <class T>
  void write_field(const char* key, const T& value, const char* doc);
  void write_named(const char* key, const NamedOptions& value, const char* doc);
  void line(const std::string& text, const char* doc);

  int indent_;
  bool comments_;
  std::string out_;
};

/// Quotes a string for YAML when needed (plain when unambiguous).
std::string quote_string(const std::string& s);

template <class T>
std::string Writer::scalar(const T& value) {
  if constexpr (is_std_optional<T>::value) {
    return value ? scalar(*value) : "null";
  } else if constexpr (std::is_same_v<T, Any>) {
    return value.node ? value.flow_text() : "null";
  } else if constexpr (std::is_same_v<T, bool>) {
    return value ? "true" : "false";
  } else if constexpr (std::is_same_v<T, double>) {
    return format_double(value);
  } else if constexpr (std::is_integral_v<T>) {
    return std::to_string(value);
  } else if constexpr (std::is_same_v<T, std::string>) {
    return quote_string(value);
  } else if constexpr (Enum<T>) {
    return std::string(enum_name(value));
  } else if constexpr (is_std_vector<T>::value || is_std_array<T>::value) {
    std::string s = "[";
    for (std::size_t i = 0; i < value.size(); ++i) {
      if (i) s += ", ";
      s += scalar(value[i]);
    }
    return s + "]";
  } else {
    static_assert(sizeof(T) == 0, "not a scalar or list of scalars");
  }
}

template <class T>
void Writer::write_field(const char* key, const T& value, const char* doc) {
  if constexpr (is_std_optional<T>::value) {
    if (value)
      write_field(key, *value, doc);
    else
      line(std::string(key) + ": null", doc);
  } else if constexpr (is_entries<T>::value) {
    if (value.empty()) {
      line(std::string(key) + ": {}", doc);
      return;
    }
    line(std::string(key) + ":", doc);
    Writer sub(indent_ + 2, comments_);
    for (const auto& e : value) sub.write_field(e.key.c_str(), e.value, nullptr);
    out_ += sub.str();
  } else if constexpr (std::is_same_v<T, NamedOptions>) {
    write_named(key, value, doc);
  } else if constexpr (Visitable<T>) {
    line(std::string(key) + ":", doc);
    Writer sub(indent_ + 2, comments_);
    const_cast<T&>(value).visit(sub);  // the writer only reads the fields
    out_ += sub.str();
  } else if constexpr (is_vector_of_visitable<T>::value) {
    if (value.empty()) {
      line(std::string(key) + ": []", doc);
      return;
    }
    line(std::string(key) + ":", doc);
    for (const auto& element : value) {
      Writer sub(indent_ + 4, comments_);
      const_cast<typename T::value_type&>(element).visit(sub);
      std::string body = sub.str();
      // Turn the first line's indentation into "- ".
      body.replace(static_cast<std::size_t>(indent_ + 2), 2, "- ");
      out_ += body;
    }
  } else {
    line(std::string(key) + ": " + scalar(value), doc);
  }
}

/// YAML text of a visitable struct with every field.
template <Visitable T>
std::string to_yaml(const T& value, bool comments = true) {
  Writer w(0, comments);
  const_cast<T&>(value).visit(w);
  return w.str();
}

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

// ---------------------------------------------------------------------------
// Schema: one row per field, for the generated reference documentation.

struct SchemaRow {
  std::string key_path;
  std::string type;
  std::string default_value;
  std::string constraint;
  std::string doc;
};

class SchemaBuilder : public IgnoresRules {
 public:
  SchemaBuilder(std::string prefix, std::vector<SchemaRow>* rows)
      : prefix_(std::move(prefix)), rows_(rows) {}

  template <class T>
  void operator()(const char* key, const T& value, const char* doc, const Check& check = {}) {
    add(key, value, doc, check);
  }
  void require(bool, const char* key, std::string_view expected);
  void exactly_one_of(std::initializer_list<const char*> keys);

 private:
  template <class T>
  static std::string type_name();
  template <class T>
  void add(const char* key, const T& value, const char* doc, const Check& check);
  void add_named(const std::string& key_path, const NamedOptions& value, const char* doc);

  std::string prefix_;
  std::vector<SchemaRow>* rows_;
};

template <class T>
std::string SchemaBuilder::type_name() {
  if constexpr (is_std_optional<T>::value) {
    return type_name<typename T::value_type>() + " or null";
  } else if constexpr (std::is_same_v<T, Any>) {
    return "any value";
  } else if constexpr (is_entries<T>::value) {
    return "mapping of names to " +
           type_name<decltype(std::declval<typename T::value_type>().value)>();
  } else if constexpr (std::is_same_v<T, bool>) {
    return "bool";
  } else if constexpr (std::is_same_v<T, double>) {
    return "number";
  } else if constexpr (std::is_integral_v<T>) {
    return "integer";
  } else if constexpr (std::is_same_v<T, std::string>) {
    return "string";
  } else if constexpr (Enum<T>) {
    return "one of: " + enum_choices<T>();
  } else if constexpr (is_std_array<T>::value) {
    return "list of " + std::to_string(std::tuple_size_v<T>) + " " +
           type_name<typename T::value_type>();
  } else if constexpr (is_std_vector<T>::value) {
    return "list of " + type_name<typename T::value_type>();
  } else if constexpr (Visitable<T>) {
    return "mapping";
  } else {
    static_assert(sizeof(T) == 0, "unsupported field type");
  }
}

template <class T>
void SchemaBuilder::add(const char* key, const T& value, const char* doc, const Check& check) {
  const std::string key_path = prefix_.empty() ? key : prefix_ + "." + key;
  if constexpr (std::is_same_v<T, NamedOptions>) {
    add_named(key_path, value, doc);
  } else if constexpr (OptionalOfVisitable<T>) {
    rows_->push_back({key_path, "mapping or null", "null", check.describe(), doc});
    typename T::value_type inner{};
    SchemaBuilder sub(key_path, rows_);
    inner.visit(sub);
  } else if constexpr (Visitable<T>) {
    rows_->push_back({key_path, "mapping", "", "", doc});
    SchemaBuilder sub(key_path, rows_);
    const_cast<T&>(value).visit(sub);
  } else if constexpr (is_vector_of_visitable<T>::value) {
    rows_->push_back({key_path, "list of mappings", value.empty() ? "[]" : "(see scenario)",
                      check.describe(), doc});
    typename T::value_type element{};
    SchemaBuilder sub(key_path + "[]", rows_);
    element.visit(sub);
  } else {
    Writer w(0, false);
    w(key, value, doc);
    std::string text = w.str();
    const auto colon = text.find(": ");
    std::string def = colon == std::string::npos ? "" : text.substr(colon + 2);
    while (!def.empty() && def.back() == '\n') def.pop_back();
    rows_->push_back({key_path, type_name<T>(), def, check.describe(), doc});
  }
}

/// Rows describing every field of T (default-constructed).
template <Visitable T>
std::vector<SchemaRow> schema_of(const T& value) {
  std::vector<SchemaRow> rows;
  SchemaBuilder b("", &rows);
  const_cast<T&>(value).visit(b);
  return rows;
}

/// Markdown table of schema rows.
std::string schema_markdown(const std::vector<SchemaRow>& rows);

// ---------------------------------------------------------------------------
// NamedOptions' holder of one options struct.

template <Visitable T>
class TypedOptions final : public NamedOptions::Holder {
 public:
  explicit TypedOptions(T value) : value_(std::move(value)) {}
  std::unique_ptr<NamedOptions::Holder> clone() const override {
    return std::make_unique<TypedOptions>(value_);
  }
  void accept(Reader& a) override { value_.visit(a); }
  void accept(Writer& a) const override { const_cast<T&>(value_).visit(a); }
  void accept(Validator& a) const override { const_cast<T&>(value_).visit(a); }
  void accept(SchemaBuilder& a) const override { const_cast<T&>(value_).visit(a); }
  const T& value() const { return value_; }

 private:
  T value_;
};

/// A holder of `value` (by default T's defaults), for a NamedOptions::Maker.
template <Visitable T>
std::unique_ptr<NamedOptions::Holder> make_options(T value = T{}) {
  return std::make_unique<TypedOptions<T>>(std::move(value));
}

/// The struct `holder` holds, or null when it holds another type (or is null).
template <Visitable T>
const T* options_of(const NamedOptions::Holder* holder) {
  const auto* typed = dynamic_cast<const TypedOptions<T>*>(holder);
  return typed ? &typed->value() : nullptr;
}

}  // namespace driftlab::yaml
