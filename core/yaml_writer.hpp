// The writer of core/yaml_io.hpp: every field of a visitable struct as YAML, in visit order.
#pragma once

#include "core/yaml_common.hpp"

namespace driftlab::yaml {

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

}  // namespace driftlab::yaml
