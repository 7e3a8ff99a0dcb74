#include "record/run_record.hpp"

#include <fmt/format.h>

#include "core/error.hpp"
#include "core/file_io.hpp"
#include "core/record_json.hpp"

namespace driftlab::record {

std::string metrics_text(const RunRecord& record) {
  return record_json::to_json(record).dump(2) + "\n";
}

RunRecord run_record_from_json(const nlohmann::json& j, const std::string& source) {
  if (!j.is_object())
    throw UserError(
        fmt::format("{}: got {}, expected a run's metrics (a JSON object)", source, j.type_name()));
  if (j.contains("sweep"))
    throw UserError(fmt::format(
        "{}: a sweep's merged metrics (it has `sweep`), expected a run's metrics.json", source));
  const auto v = j.find("metrics_version");
  if (v != j.end() && v->is_number_integer() && v->get<int>() > kMetricsVersion)
    throw UserError(fmt::format(
        "{}: metrics_version {} was written by a newer driftlab; this one reads versions 1 to {}",
        source, v->get<int>(), kMetricsVersion));
  RunRecord r = record_json::from_json<RunRecord>(j, source);
  if (v == j.end()) r.metrics_version = 1;
  return r;
}

RunRecord read_run_record(const std::filesystem::path& path) {
  const std::filesystem::path file =
      std::filesystem::is_directory(path) ? path / "metrics.json" : path;
  const std::string text = read_text_file(file, "run metrics");
  const auto j = record_json::parse_json<nlohmann::json>(text, file.string(), "a run's metrics");
  return run_record_from_json(j, file.string());
}

std::string metrics_reference_markdown() {
  return record_json::fields_markdown(record_json::fields_of<RunRecord>());
}

}  // namespace driftlab::record
