// The schema of core/yaml_io.hpp: one row per field of a visitable struct, for the generated
// references (its defaults written by the writer).
#pragma once

#include "core/yaml_common.hpp"
#include "core/yaml_writer.hpp"

namespace driftlab::yaml {

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

}  // namespace driftlab::yaml
