#include "core/number.hpp"

#include <charconv>
#include <cmath>
#include <system_error>

namespace driftlab {
namespace {

// The text without its leading '+', unless a sign follows it.
std::string_view without_plus(std::string_view text) {
  if (text.size() > 1 && text[0] == '+' && text[1] != '-' && text[1] != '+') text.remove_prefix(1);
  return text;
}

template <class T>
NumberStatus from_chars_status(std::string_view text, T* out) {
  text = without_plus(text);
  if (text.empty()) return NumberStatus::kNotNumber;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, *out);
  if (ec == std::errc::result_out_of_range) return NumberStatus::kOutOfRange;
  if (ec != std::errc() || ptr != end) return NumberStatus::kNotNumber;
  return NumberStatus::kOk;
}

}  // namespace

NumberStatus read_number(std::string_view text, double* out) {
  const NumberStatus s = from_chars_status(text, out);
  return s == NumberStatus::kOk && !std::isfinite(*out) ? NumberStatus::kNotFinite : s;
}

NumberStatus read_number(std::string_view text, std::int64_t* out) {
  return from_chars_status(text, out);
}

NumberStatus read_number(std::string_view text, std::uint64_t* out) {
  if (!text.empty() && text[0] == '-') return NumberStatus::kNotNumber;
  return from_chars_status(text, out);
}

}  // namespace driftlab
