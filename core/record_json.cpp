#include "core/record_json.hpp"

#include <fmt/format.h>

#include "core/markup.hpp"

namespace driftlab::record_json {

template <class Json>
void BasicReader<Json>::fail(const Json& j, const std::string& at,
                             const std::string& expected) const {
  std::string value = j.dump();
  if (value.size() > 60) value = value.substr(0, 57) + "...";
  throw UserError(fmt::format("{}: {}: got {}, expected {}", source_, at.empty() ? "(top)" : at,
                              value, expected));
}

template <class Json>
void BasicReader<Json>::reject_unknown_keys() const {
  for (const auto& [key, _] : in_.items()) {
    if (seen_.count(key)) continue;
    std::string known;
    for (const auto& k : seen_) known += (known.empty() ? "" : ", ") + k;
    throw UserError(fmt::format("{}: {}: unknown key, expected one of: {}", source_,
                                prefix_.empty() ? key : prefix_ + "." + key, known));
  }
}

template class BasicReader<nlohmann::json>;  // the two JSON types from_json accepts
template class BasicReader<nlohmann::ordered_json>;

std::string fields_markdown(const std::vector<FieldRow>& rows) {
  std::string out = "| key | type | meaning |\n|---|---|---|\n";
  for (const auto& r : rows)
    out += fmt::format("| `{}` | {} | {} |\n", r.key_path, markdown_cell(r.type),
                       markdown_cell(r.doc));
  return out;
}

}  // namespace driftlab::record_json
