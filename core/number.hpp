// Numbers from text: one rule for every reader (scenarios, trajectories, datasets, tables, the
// frame cache's index). A number is what C++'s std::from_chars reads (decimal or exponent
// notation; for a double also nan, inf and infinity in any case), with an optional leading '+'
// that some writers emit ("+-1" is not a number), and nothing else: a reader trims its own
// spaces first. A format's own spellings (YAML's .nan and .inf) are thin wrappers around it.
#pragma once

#include <cstdint>
#include <limits>
#include <string_view>
#include <type_traits>

namespace driftlab {

enum class NumberStatus {
  kOk,
  kNotNumber,   ///< not one number, or something after it
  kNotFinite,   ///< nan or an infinity (`out` holds it): for readers that refuse them by name
  kOutOfRange,  ///< beyond the type's range (1e400 for a double)
};

NumberStatus read_number(std::string_view text, double* out);
NumberStatus read_number(std::string_view text, std::int64_t* out);
NumberStatus read_number(std::string_view text, std::uint64_t* out);  ///< "-1": kNotNumber

/// Other integer types, through the 64-bit ones and a range check.
template <class T>
requires(std::is_integral_v<T> && !std::is_same_v<T, bool> && !std::is_same_v<T, std::int64_t> &&
         !std::is_same_v<T, std::uint64_t>) NumberStatus
    read_number(std::string_view text, T* out) {
  using Wide = std::conditional_t<std::is_signed_v<T>, std::int64_t, std::uint64_t>;
  Wide wide = 0;
  const NumberStatus s = read_number(text, &wide);
  if (s != NumberStatus::kOk) return s;
  if (wide < static_cast<Wide>(std::numeric_limits<T>::min()) ||
      wide > static_cast<Wide>(std::numeric_limits<T>::max()))
    return NumberStatus::kOutOfRange;
  *out = static_cast<T>(wide);
  return NumberStatus::kOk;
}

}  // namespace driftlab
