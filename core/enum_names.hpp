// Enum names, written once: an enum lists its values' names in an ADL `enum_table(E)` (an
// array of {E, "name"} pairs beside the enum), and every reader, writer, message and reference
// takes them from there.
#pragma once

#include <algorithm>
#include <cctype>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>

#include "core/error.hpp"

namespace driftlab::yaml {

template <class T>
concept Enum = std::is_enum_v<T> && requires(T e) {
  enum_table(e);
};

/// Name of an enum value from its ADL enum_table.
template <Enum E>
std::string_view enum_name(E value) {
  for (const auto& [v, name] : enum_table(E{}))
    if (v == value) return name;
  DRIFTLAB_DEMAND_MSG(false, "enum value without a name in enum_table");
  return {};
}

/// Comma-separated list of an enum's names, for "expected one of ..." messages.
template <Enum E>
std::string enum_choices() {
  std::string out;
  for (const auto& [v, name] : enum_table(E{})) {
    if (!out.empty()) out += ", ";
    out += name;
  }
  return out;
}

/// Parses an enum by name; returns nullopt if unknown.
template <Enum E>
std::optional<E> enum_from_name(std::string_view text) {
  for (const auto& [v, name] : enum_table(E{}))
    if (text == name) return v;
  return std::nullopt;
}

/// Parses an enum by name in any case ("KITTI" for "kitti"); nullopt if unknown.
template <Enum E>
std::optional<E> enum_from_name_any_case(std::string_view text) {
  std::string lower(text);
  for (char& ch : lower) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  return enum_from_name<E>(lower);
}

}  // namespace driftlab::yaml
