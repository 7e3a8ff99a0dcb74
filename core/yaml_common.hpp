// What every YAML archive of core/yaml_io.hpp shares: the field types' traits, Any and Entry,
// named options, the Visitable concept, the rules every archive accepts, where a document came
// from and the problems found in it.
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

}  // namespace driftlab::yaml
