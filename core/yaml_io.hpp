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

#include <memory>

#include "core/yaml_common.hpp"
#include "core/yaml_reader.hpp"
#include "core/yaml_schema.hpp"
#include "core/yaml_validator.hpp"
#include "core/yaml_writer.hpp"

namespace driftlab::yaml {

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
