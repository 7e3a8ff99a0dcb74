// Typed records <-> JSON, driven by the same visit() lists as the options (core/yaml_io.hpp).
//
// A record lists its fields once:
//
//   struct TrackRecord {
//     std::size_t n = 0;
//     double rmse_3d_m = 0;
//     template <class A> void visit(A& a) {
//       a("n", n, "poses compared");
//       a("rmse_3d_m", rmse_3d_m, "3D position error, RMS [m]");
//     }
//   };
//
// and that one list writes it (record_json::to_json), reads it back strictly
// (record_json::from_json: a wrong type or an unknown key is an error naming the source, the
// key path, the value and what was expected) and documents it (record_json::fields_of, for
// docs/metrics-reference.md). A visit() may call a member's visit() to lay its fields out
// flat in the same object.
//
// Field types: bool, integers, double, std::string, enums with an ADL `enum_table` (by
// name), nested records, std::vector<T>, std::array<T, N>, std::map<std::string, T> (an
// object of names of the run's choosing), Named<T> (the same, its names in the order they
// were added), std::optional<T> (absent when empty; null reads as empty) and nlohmann::json
// (any JSON, kept as it is). A double that is not finite is written as null, and the writer
// names it; null reads back as NaN.
//
// to_json writes objects with their keys sorted (nlohmann::json); to_ordered_json keeps the
// order of the visit() lists and of Named<T> (nlohmann::ordered_json), for files a person reads
// top to bottom.
#pragma once

#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "core/yaml_io.hpp"

namespace driftlab::record_json {

template <class T>
struct is_string_map : std::false_type {};
template <class T, class Cmp, class Alloc>
struct is_string_map<std::map<std::string, T, Cmp, Alloc>> : std::true_type {};

/// An object of names chosen at run time, kept in the order they were added: a JSON object
/// whose keys keep their order under to_ordered_json.
template <class T>
struct Named {
  std::vector<std::pair<std::string, T>> items;

  /// The value under `name`, added (default) at the end when absent.
  T& operator[](const std::string& name) {
    for (auto& [n, v] : items)
      if (n == name) return v;
    return items.emplace_back(name, T{}).second;
  }
  const T* find(const std::string& name) const {
    for (const auto& [n, v] : items)
      if (n == name) return &v;
    return nullptr;
  }
  bool empty() const { return items.empty(); }
  std::size_t size() const { return items.size(); }
  auto begin() const { return items.begin(); }
  auto end() const { return items.end(); }
};

template <class T>
struct is_named : std::false_type {};
template <class T>
struct is_named<Named<T>> : std::true_type {};

/// A number the writer wrote as null, by its key path ("ape.trans_m.rmse").
struct NonFinite {
  std::string key;
  double value = 0;
};

// ---------------------------------------------------------------------------
// Writer: every field, under its key; Json is nlohmann::json (keys sorted) or
// nlohmann::ordered_json (keys in the order written).

template <class Json>
class BasicWriter : public yaml::IgnoresRules {
 public:
  BasicWriter(Json* out, std::string prefix, std::vector<NonFinite>* nonfinite)
      : out_(out), prefix_(std::move(prefix)), nonfinite_(nonfinite) {}

  template <class T>
  void operator()(const char* key, const T& value, const char*, const yaml::Check& = {}) {
    if constexpr (yaml::is_std_optional<T>::value) {
      if (!value) return;
    }
    (*out_)[key] = value_json(value, path(key), nonfinite_);
  }

  template <class T>
  static Json value_json(const T& value, const std::string& at, std::vector<NonFinite>* nonfinite);

 private:
  std::string path(const char* key) const { return prefix_.empty() ? key : prefix_ + "." + key; }

  Json* out_;
  std::string prefix_;
  std::vector<NonFinite>* nonfinite_;
};

template <class Json>
template <class T>
Json BasicWriter<Json>::value_json(const T& value, const std::string& at,
                                   std::vector<NonFinite>* nonfinite) {
  if constexpr (yaml::is_std_optional<T>::value) {
    return value ? value_json(*value, at, nonfinite) : Json();
  } else if constexpr (std::is_same_v<T, nlohmann::json>) {
    return Json(value);
  } else if constexpr (std::is_same_v<T, double>) {
    if (!std::isfinite(value) && nonfinite) nonfinite->push_back({at, value});
    return std::isfinite(value) ? Json(value) : Json();
  } else if constexpr (std::is_same_v<T, bool> || std::is_integral_v<T> ||
                       std::is_same_v<T, std::string>) {
    return value;
  } else if constexpr (yaml::Enum<T>) {
    return std::string(yaml::enum_name(value));
  } else if constexpr (yaml::Visitable<T>) {
    Json j = Json::object();
    BasicWriter sub(&j, at, nonfinite);
    const_cast<T&>(value).visit(sub);  // the writer only reads the fields
    return j;
  } else if constexpr (is_string_map<T>::value || is_named<T>::value) {
    Json j = Json::object();
    for (const auto& [name, v] : value) j[name] = value_json(v, at + "." + name, nonfinite);
    return j;
  } else if constexpr (yaml::is_std_vector<T>::value || yaml::is_std_array<T>::value) {
    Json j = Json::array();
    for (std::size_t i = 0; i < value.size(); ++i)
      j.push_back(value_json(value[i], at + "[" + std::to_string(i) + "]", nonfinite));
    return j;
  } else {
    static_assert(sizeof(T) == 0, "unsupported record field type");
  }
}

using Writer = BasicWriter<nlohmann::json>;
using OrderedWriter = BasicWriter<nlohmann::ordered_json>;

/// Whether `A` is the writer: for a part a record leaves out of what it writes when unset.
template <class A>
inline constexpr bool is_writer = std::is_same_v<A, Writer> || std::is_same_v<A, OrderedWriter>;

/// The record as JSON, keys sorted; each number written as null is added to `nonfinite` when
/// given.
template <yaml::Visitable T>
nlohmann::json to_json(const T& record, std::vector<NonFinite>* nonfinite = nullptr) {
  return Writer::value_json(record, "", nonfinite);
}

/// The record as JSON, keys in the order of its visit() lists and Named<T>s.
template <yaml::Visitable T>
nlohmann::ordered_json to_ordered_json(const T& record,
                                       std::vector<NonFinite>* nonfinite = nullptr) {
  return OrderedWriter::value_json(record, "", nonfinite);
}

// ---------------------------------------------------------------------------
// Reader: strict on types and keys; an absent key keeps the field's default (an older file
// without a newer block), an absent optional stays empty. Json is nlohmann::json or
// nlohmann::ordered_json (a Named<T> then reads in the file's order).

template <class Json>
class BasicReader : public yaml::IgnoresRules {
 public:
  BasicReader(const Json& in, std::string source, std::string prefix,
              bool ignore_unknown_keys = false)
      : in_(in),
        source_(std::move(source)),
        prefix_(std::move(prefix)),
        ignore_unknown_keys_(ignore_unknown_keys) {}

  template <class T>
  void operator()(const char* key, T& value, const char*, const yaml::Check& = {}) {
    seen_.insert(key);
    const auto it = in_.find(key);
    if (it == in_.end()) return;
    read(*it, path(key), &value);
  }
  /// Fails on a key that no field of the record names.
  void reject_unknown_keys() const;

  template <class T>
  void read(const Json& j, const std::string& at, T* value) const;

 private:
  std::string path(const char* key) const { return prefix_.empty() ? key : prefix_ + "." + key; }
  [[noreturn]] void fail(const Json& j, const std::string& at, const std::string& expected) const;
  template <class T>
  static std::string expected();

  const Json& in_;
  std::string source_, prefix_;
  bool ignore_unknown_keys_;
  std::set<std::string> seen_;
};

template <class Json>
template <class T>
std::string BasicReader<Json>::expected() {
  if constexpr (std::is_same_v<T, double>) {
    return "a number or null";
  } else if constexpr (std::is_same_v<T, bool>) {
    return "true or false";
  } else if constexpr (std::is_integral_v<T> && std::is_unsigned_v<T>) {
    return "a whole number >= 0";
  } else if constexpr (std::is_integral_v<T>) {
    return "a whole number";
  } else if constexpr (std::is_same_v<T, std::string>) {
    return "a string";
  } else if constexpr (yaml::Enum<T>) {
    return "one of " + yaml::enum_choices<T>();
  } else if constexpr (yaml::Visitable<T> || is_string_map<T>::value || is_named<T>::value) {
    return "an object";
  } else {
    return "a list";
  }
}

template <class Json>
template <class T>
void BasicReader<Json>::read(const Json& j, const std::string& at, T* value) const {
  if constexpr (yaml::is_std_optional<T>::value) {
    if (j.is_null()) {
      // A number written as null was there but not finite; anything else null is absent.
      if constexpr (std::is_floating_point_v<typename T::value_type>)
        *value = std::numeric_limits<typename T::value_type>::quiet_NaN();
      else
        value->reset();
      return;
    }
    typename T::value_type inner{};
    read(j, at, &inner);
    *value = std::move(inner);
  } else if constexpr (std::is_same_v<T, nlohmann::json>) {
    *value = nlohmann::json(j);
  } else if constexpr (std::is_same_v<T, double>) {
    if (j.is_null()) {
      *value = std::numeric_limits<double>::quiet_NaN();
    } else {
      if (!j.is_number()) fail(j, at, expected<T>());
      *value = j.template get<double>();
    }
  } else if constexpr (std::is_same_v<T, bool>) {
    if (!j.is_boolean()) fail(j, at, expected<T>());
    *value = j.template get<bool>();
  } else if constexpr (std::is_integral_v<T>) {
    if (!j.is_number_integer() ||
        (std::is_unsigned_v<T> && !j.is_number_unsigned() && j.template get<std::int64_t>() < 0))
      fail(j, at, expected<T>());
    const bool fits = j.is_number_unsigned() ? std::in_range<T>(j.template get<std::uint64_t>())
                                             : std::in_range<T>(j.template get<std::int64_t>());
    if (!fits)
      fail(j, at,
           expected<T>() + " from " + std::to_string(std::numeric_limits<T>::min()) + " to " +
               std::to_string(std::numeric_limits<T>::max()));
    *value = j.template get<T>();
  } else if constexpr (std::is_same_v<T, std::string>) {
    if (!j.is_string()) fail(j, at, expected<T>());
    *value = j.template get<std::string>();
  } else if constexpr (yaml::Enum<T>) {
    const auto e =
        j.is_string() ? yaml::enum_from_name<T>(j.template get<std::string>()) : std::nullopt;
    if (!e) fail(j, at, expected<T>());
    *value = *e;
  } else if constexpr (yaml::Visitable<T>) {
    if (!j.is_object()) fail(j, at, expected<T>());
    BasicReader sub(j, source_, at, ignore_unknown_keys_);
    value->visit(sub);
    if (!ignore_unknown_keys_) sub.reject_unknown_keys();
  } else if constexpr (is_string_map<T>::value || is_named<T>::value) {
    if (!j.is_object()) fail(j, at, expected<T>());
    *value = T{};
    for (const auto& [name, v] : j.items()) read(v, at + "." + name, &(*value)[name]);
  } else if constexpr (yaml::is_std_vector<T>::value) {
    if (!j.is_array()) fail(j, at, expected<T>());
    value->assign(j.size(), typename T::value_type{});
    for (std::size_t i = 0; i < j.size(); ++i)
      read(j[i], at + "[" + std::to_string(i) + "]", &(*value)[i]);
  } else if constexpr (yaml::is_std_array<T>::value) {
    if (!j.is_array() || j.size() != value->size())
      fail(j, at, "a list of " + std::to_string(value->size()));
    for (std::size_t i = 0; i < j.size(); ++i)
      read(j[i], at + "[" + std::to_string(i) + "]", &(*value)[i]);
  } else {
    static_assert(sizeof(T) == 0, "unsupported record field type");
  }
}

using Reader = BasicReader<nlohmann::json>;
using OrderedReader = BasicReader<nlohmann::ordered_json>;

/// Whether an unknown key is an error, or left for a newer writer's reader.
enum class UnknownKeys { kReject, kIgnore };

/// Reads a record written by to_json or to_ordered_json; `source` names the file in errors.
/// Throws UserError.
template <yaml::Visitable T, class Json>
requires std::is_same_v<Json, nlohmann::json> || std::is_same_v<Json, nlohmann::ordered_json> T
from_json(const Json& j, const std::string& source, UnknownKeys unknown = UnknownKeys::kReject) {
  T record{};
  BasicReader<Json>(j, source, "", unknown == UnknownKeys::kIgnore).read(j, "", &record);
  return record;
}

/// The top-level keys of a visit() list, in order.
class KeyLister : public yaml::IgnoresRules {
 public:
  template <class V>
  void operator()(const char* key, V&, const char*, const yaml::Check& = {}) {
    keys.push_back(key);
  }
  std::vector<std::string> keys;
};

/// The keys of T's visit() list that the object `j` lacks, in that order (all of them when `j`
/// is not an object): for files whose every key is required.
template <yaml::Visitable T, class Json>
std::vector<std::string> missing_keys(const Json& j) {
  KeyLister lister;
  T{}.visit(lister);
  std::vector<std::string> missing;
  for (const auto& k : lister.keys)
    if (!j.is_object() || !j.contains(k)) missing.push_back(k);
  return missing;
}

/// `text` parsed as JSON (Json: nlohmann::ordered_json keeps the file's key order); anything
/// malformed, or a number past a double's range, is a UserError naming `source` and what was
/// `expected`.
template <class Json = nlohmann::ordered_json>
Json parse_json(const std::string& text, const std::string& source, const std::string& expected) {
  try {
    return Json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw UserError(source + ": not valid JSON (" + e.what() + "), expected " + expected);
  }
}

// ---------------------------------------------------------------------------
// Reference: one row per field, for the generated documentation.

struct FieldRow {
  std::string key_path;
  std::string type;
  std::string doc;
};

class Documenter : public yaml::IgnoresRules {
 public:
  Documenter(std::string prefix, std::vector<FieldRow>* rows)
      : prefix_(std::move(prefix)), rows_(rows) {}

  template <class T>
  void operator()(const char* key, const T&, const char* doc, const yaml::Check& = {}) {
    add<T>(prefix_.empty() ? key : prefix_ + "." + key, doc, false);
  }

 private:
  template <class T>
  void add(const std::string& at, const char* doc, bool optional);
  template <class T>
  static std::string type_name();
  template <class T>
  void add_named_value(const std::string& at);

  std::string prefix_;
  std::vector<FieldRow>* rows_;
};

template <class T>
std::string Documenter::type_name() {
  if constexpr (std::is_same_v<T, nlohmann::json>) {
    return "any JSON";
  } else if constexpr (std::is_same_v<T, double>) {
    return "number";
  } else if constexpr (std::is_same_v<T, bool>) {
    return "bool";
  } else if constexpr (std::is_integral_v<T>) {
    return "integer";
  } else if constexpr (std::is_same_v<T, std::string>) {
    return "string";
  } else if constexpr (yaml::Enum<T>) {
    return "one of: " + yaml::enum_choices<T>();
  } else if constexpr (yaml::Visitable<T>) {
    return "object";
  } else if constexpr (is_string_map<T>::value) {
    return "object of names to " + type_name<typename T::mapped_type>();
  } else if constexpr (is_named<T>::value) {
    return "object of names (in order) to " +
           type_name<typename decltype(T::items)::value_type::second_type>();
  } else if constexpr (yaml::is_std_array<T>::value) {
    return "list of " + std::to_string(std::tuple_size_v<T>) + " " +
           type_name<typename T::value_type>();
  } else if constexpr (yaml::is_std_vector<T>::value) {
    return "list of " + type_name<typename T::value_type>();
  } else {
    static_assert(sizeof(T) == 0, "unsupported record field type");
  }
}

template <class T>
void Documenter::add(const std::string& at, const char* doc, bool optional) {
  if constexpr (yaml::is_std_optional<T>::value) {
    add<typename T::value_type>(at, doc, true);
  } else {
    rows_->push_back({at, type_name<T>() + (optional ? " or absent" : ""), doc});
    if constexpr (yaml::Visitable<T>) {
      Documenter sub(at, rows_);
      T{}.visit(sub);
    } else if constexpr (is_string_map<T>::value || is_named<T>::value) {
      add_named_value<T>(at);
    } else if constexpr (yaml::is_std_vector<T>::value || yaml::is_std_array<T>::value) {
      using V = typename T::value_type;
      if constexpr (yaml::Visitable<V>) {
        Documenter sub(at + "[]", rows_);
        V{}.visit(sub);
      }
    }
  }
}

// The fields of the values of an object of names, under NAME (a Named of Named: NAME.NAME).
template <class T>
void Documenter::add_named_value(const std::string& at) {
  using V = typename decltype(std::declval<T>().begin())::value_type::second_type;
  if constexpr (yaml::Visitable<V>) {
    Documenter sub(at + ".NAME", rows_);
    V{}.visit(sub);
  } else if constexpr (is_string_map<V>::value || is_named<V>::value) {
    add_named_value<V>(at + ".NAME");
  }
}

/// Rows describing every field of T.
template <yaml::Visitable T>
std::vector<FieldRow> fields_of() {
  std::vector<FieldRow> rows;
  Documenter d("", &rows);
  T{}.visit(d);
  return rows;
}

/// Markdown table of field rows: key, type, meaning.
std::string fields_markdown(const std::vector<FieldRow>& rows);

}  // namespace driftlab::record_json
