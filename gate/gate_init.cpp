// `driftlab regress init`: a baseline from results (gate.hpp).
#include <fmt/format.h>

#include <cmath>

#include "core/error.hpp"
#include "gate/gate.hpp"

namespace driftlab::gate {
namespace {

// The value and, for a pooled sweep metric ({n, mean, sd, ...}), its spread.
struct Found {
  double value = 0;
  std::optional<double> sd;
  std::size_t n = 0;
};

std::optional<Found> find(const nlohmann::json& doc, const std::string& key) {
  std::string why;
  const auto v = metric_value(doc, key, &why);
  if (!v) return std::nullopt;
  Found f{*v, std::nullopt, 0};
  // A pooled sweep statistic "....M.mean" has its sd and n beside it.
  if (key.size() > 5 && key.ends_with(".mean")) {
    const std::string parent = key.substr(0, key.size() - 5);
    const auto sd = metric_value(doc, parent + ".sd", &why);
    const auto n = metric_value(doc, parent + ".n", &why);
    if (sd && n && *n >= 2) {
      f.sd = *sd;
      f.n = static_cast<std::size_t>(*n);
    }
  }
  return f;
}

void add_if_present(const nlohmann::json& doc, const std::string& key,
                    std::vector<std::string>* keys) {
  std::string why;
  if (const auto v = metric_value(doc, key, &why); v && std::isfinite(*v)) keys->push_back(key);
}

}  // namespace

std::vector<std::string> default_gate_keys(const nlohmann::json& results) {
  std::vector<std::string> keys;
  if (!results.contains("algorithms") || !results["algorithms"].is_object()) return keys;
  const bool sweep = results.contains("sweep");
  for (const auto& [name, a] : results["algorithms"].items()) {
    const std::string at = "algorithms." + name;
    if (sweep && a.contains("pairs")) {  // a merged sweep with per-job values: compared in pairs
      std::string why;
      for (const char* m : {"p_m_per_m_sections", "ape_trans_rmse_m", "ape_rot_rmse_deg"})
        if (const auto p = metric_pairs(results, at + ".pairs." + m, &why); p && !p->empty())
          keys.push_back(at + ".pairs." + m);
      continue;
    }
    if (sweep) {  // a merged sweep of an older driftlab: the pooled run statistics
      for (const char* m : {"ape_trans_rmse_m", "ape_rot_rmse_deg", "p_m_per_m_mean"})
        add_if_present(results, at + ".runs." + m + ".mean", &keys);
      continue;
    }
    add_if_present(results, at + ".ape.trans_m.rmse", &keys);
    add_if_present(results, at + ".ape.rot_deg.rmse", &keys);
    add_if_present(results, at + ".track.rmse_3d_m", &keys);
    if (a.contains("sections") && a["sections"].value("count", 0) > 0)
      add_if_present(results, at + ".sections.p_m_per_m.mean", &keys);
    for (const char* m : {"north_m", "east_m", "heading_deg"})
      add_if_present(results, at + ".basin." + m + ".rmse", &keys);
  }
  return keys;
}

Baseline baseline_from_results(const nlohmann::json& results, const std::vector<std::string>& keys,
                               const InitOptions& options) {
  if (keys.empty())
    throw UserError(
        "regress init: no metric to gate (the results hold no algorithm with an APE, "
        "section or basin error); name them with --keys");
  Baseline b;
  b.description = options.description;
  std::string missing;
  for (const auto& key : keys) {
    std::string why;
    if (const nlohmann::json* node = metric_node(results, key, &why); node && node->is_object()) {
      const auto pairs = metric_pairs(results, key, &why);
      if (!pairs || pairs->empty()) {
        missing += (missing.empty() ? "" : ", ") + key;
        continue;
      }
      BaselineMetric m;
      m.key = key;
      m.pairs = *pairs;
      m.baseline = pairs_mean(m.pairs);
      m.direction = MetricDirection::kLower;
      b.metrics.push_back(m);
      continue;
    }
    const auto f = find(results, key);
    if (!f) {
      missing += (missing.empty() ? "" : ", ") + key;
      continue;
    }
    BaselineMetric m;
    m.key = key;
    m.baseline = f->value;
    m.direction = MetricDirection::kLower;
    m.rel_tol = options.rel_tol;
    // Replicates: a change within twice the standard error of the pooled mean is noise-level.
    if (f->sd) m.abs_tol = 2 * *f->sd / std::sqrt(static_cast<double>(f->n));
    b.metrics.push_back(m);
  }
  if (!missing.empty())
    throw UserError(fmt::format("regress init: the results have no number at: {}", missing));
  return b;
}

}  // namespace driftlab::gate
