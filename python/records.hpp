// Typed records (core/record_json.hpp's field types) as Python objects, walked through the same
// visit() lists that write metrics.json: a record becomes a driftlab.Record whose attributes
// are its keys, an object of names a dict, a list a list, a number a float (NaN where the file
// has null), an enum its name, an absent optional None.
#pragma once

#include <pybind11/pybind11.h>

#include <nlohmann/json.hpp>
#include <string>
#include <type_traits>

#include "core/record_json.hpp"

namespace driftlab::python {

namespace py = pybind11;

/// The Python class records become (driftlab._record.Record).
py::object record_class();

template <class T>
py::object to_python(const T& value);

/// Sets each field of a record as an attribute of a Python object.
class AttributeWriter : public yaml::IgnoresRules {
 public:
  explicit AttributeWriter(py::object* out) : out_(out) {}

  template <class T>
  void operator()(const char* key, const T& value, const char*, const yaml::Check& = {}) {
    py::setattr(*out_, key, to_python(value));
  }

 private:
  py::object* out_;
};

template <class T>
py::object to_python(const T& value) {
  if constexpr (yaml::is_std_optional<T>::value) {
    return value ? to_python(*value) : py::none();
  } else if constexpr (std::is_same_v<T, nlohmann::json>) {
    return py::module_::import("json").attr("loads")(value.dump());
  } else if constexpr (std::is_same_v<T, double>) {
    return py::float_(value);
  } else if constexpr (std::is_same_v<T, bool>) {
    return py::bool_(value);
  } else if constexpr (std::is_integral_v<T>) {
    return py::int_(value);
  } else if constexpr (std::is_same_v<T, std::string>) {
    return py::str(value);
  } else if constexpr (yaml::Enum<T>) {
    return py::str(std::string(yaml::enum_name(value)));
  } else if constexpr (yaml::Visitable<T>) {
    py::object out = record_class()();
    AttributeWriter writer(&out);
    const_cast<T&>(value).visit(writer);  // the walk only reads the fields
    return out;
  } else if constexpr (record_json::is_string_map<T>::value || record_json::is_named<T>::value) {
    py::dict d;
    for (const auto& [name, v] : value) d[py::str(name)] = to_python(v);
    return d;
  } else if constexpr (yaml::is_std_vector<T>::value || yaml::is_std_array<T>::value) {
    py::list l;
    for (const auto& v : value) l.append(to_python(v));
    return l;
  } else {
    static_assert(sizeof(T) == 0, "unsupported record field type");
  }
}

/// The reference rows of a record: (key path, type, meaning) tuples.
template <yaml::Visitable T>
py::list fields_to_python() {
  py::list rows;
  for (const auto& r : record_json::fields_of<T>())
    rows.append(py::make_tuple(r.key_path, r.type, r.doc));
  return rows;
}

}  // namespace driftlab::python
