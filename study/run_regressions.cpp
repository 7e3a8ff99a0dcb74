#include "study/run_regressions.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>

#include "core/error.hpp"
#include "core/record_json.hpp"
#include "study/sweep_merge.hpp"

namespace driftlab::study {

namespace {

// The value of a --regress metric in one run: a run metric by name, else a key path of the
// algorithm's record (docs/metrics-reference.md, under algorithms.NAME).
double regression_metric_value(const record::RunRecord& metrics, const std::string& algorithm,
                               const std::string& metric) {
  for (const auto& rm : run_metrics())
    if (rm.name == metric) return run_metric_value(metrics, algorithm, rm);
  const auto it = metrics.algorithms.find(algorithm);
  if (it == metrics.algorithms.end()) return std::numeric_limits<double>::quiet_NaN();
  return json_number(record_json::to_json(it->second), metric);
}

// The pieces of `text` between the separators (empty pieces kept).
std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> out;
  for (std::size_t start = 0;;) {
    const auto at = text.find(separator, start);
    out.push_back(text.substr(start, at == std::string::npos ? at : at - start));
    if (at == std::string::npos) return out;
    start = at + 1;
  }
}

// Whether a job's parameter text equals a condition's value: as text, or as numbers.
bool same_value(const std::string& param, const std::string& value) {
  if (param == value) return true;
  char* end_p = nullptr;
  char* end_v = nullptr;
  const double p = std::strtod(param.c_str(), &end_p), v = std::strtod(value.c_str(), &end_v);
  return !param.empty() && !value.empty() && *end_p == '\0' && *end_v == '\0' && p == v;
}

// Whether a job meets every condition of a --regress.
bool meets(const SweepJob& job, const std::vector<std::pair<std::string, std::string>>& where) {
  for (const auto& [axis, value] : where) {
    bool ok = false;
    for (const auto& [name, param] : job.params)
      ok = ok || (name == axis && same_value(param, value));
    if (!ok) return false;
  }
  return true;
}

// The AXIS=VALUE conditions after '@', each checked against the sweep's axes and jobs.
std::vector<std::pair<std::string, std::string>> parse_conditions(const std::string& spec,
                                                                  const std::string& text,
                                                                  const SweepManifest& m) {
  std::vector<std::pair<std::string, std::string>> out;
  for (const std::string& c : split(text, ',')) {
    const auto eq = c.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == c.size())
      throw UserError(
          fmt::format("--regress '{}': got condition '{}', expected AXIS=VALUE", spec, c));
    const std::string axis = c.substr(0, eq), value = c.substr(eq + 1);
    std::vector<std::string> names, values;
    for (const auto& ax : m.axes) names.push_back(ax.name);
    if (std::find(names.begin(), names.end(), axis) == names.end())
      throw UserError(
          fmt::format("--regress '{}': got condition axis '{}', expected an axis of "
                      "the sweep: {}",
                      spec, axis, fmt::join(names, ", ")));
    bool found = false;
    for (const auto& job : m.jobs)
      for (const auto& [name, param] : job.params) {
        if (name != axis) continue;
        found = found || same_value(param, value);
        if (std::find(values.begin(), values.end(), param) == values.end()) values.push_back(param);
      }
    if (!found)
      throw UserError(
          fmt::format("--regress '{}': got {} = {}, expected one of the axis's "
                      "values: {}",
                      spec, axis, value, fmt::join(values, ", ")));
    out.emplace_back(axis, value);
  }
  return out;
}

}  // namespace

// A number at a dotted key path of a JSON document, NaN when absent or not a number.
double json_number(const nlohmann::json& j, const std::string& dotted) {
  const nlohmann::json* node = &j;
  std::size_t start = 0;
  while (start <= dotted.size()) {
    const auto dot = dotted.find('.', start);
    const std::string key = dotted.substr(start, dot == std::string::npos ? dot : dot - start);
    if (!node->is_object() || !node->contains(key)) return std::numeric_limits<double>::quiet_NaN();
    node = &(*node)[key];
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  return node->is_number() ? node->get<double>() : std::numeric_limits<double>::quiet_NaN();
}

// An OLS fit as metrics.json holds it, and its part of summary.md (a table and the fit's
// paragraph).
OlsFitRecord ols_record(const eval::OlsResult& r, std::string* md) {
  OlsFitRecord out{r.n, r.r2, r.adj_r2, r.f, r.f_p, r.sigma, {}, r.warnings, std::nullopt};
  *md += "| term | estimate | std. error | t | p | VIF |\n|---|---|---|---|---|---|\n";
  for (const auto& c : r.coefficients) {
    out.coefficients[c.name] = {c.estimate, c.std_error, c.t, c.p, c.vif, c.significant};
    *md += fmt::format("| {}{} | {:.4g} | {:.3g} | {:.3g} | {:.3g} | {} |\n", c.name,
                       c.significant ? " *" : "", c.estimate, c.std_error, c.t, c.p,
                       c.name == "Intercept" ? std::string("") : fmt::format("{:.3g}", c.vif));
  }
  *md += "\n" + r.brief() + "\n";
  return out;
}

std::vector<RunRegression> parse_run_regressions(const std::vector<std::string>& specs,
                                                 const SweepManifest& m) {
  std::vector<RunRegression> out;
  for (const auto& spec : specs) {
    RunRegression r{spec, "", {}, {}};
    const auto at = spec.find('@');
    const std::string formula = spec.substr(0, at);
    const auto tilde = formula.find('~');
    if (tilde == std::string::npos || tilde == 0 || tilde + 1 == formula.size())
      throw UserError(
          fmt::format("--regress: got '{}', expected METRIC~AXIS[+AXIS...][@AXIS=VALUE,...], "
                      "e.g. basin_north_rmse_m~amplitude_m@direction_deg=-40",
                      spec));
    if (at != std::string::npos) r.where = parse_conditions(spec, spec.substr(at + 1), m);
    r.metric = formula.substr(0, tilde);
    r.axes = split(formula.substr(tilde + 1), '+');
    for (const auto& a : r.axes) {
      bool known = false;
      std::string names;
      for (const auto& ax : m.axes) {
        known = known || (ax.name == a && ax.numeric);
        if (ax.numeric) names += (names.empty() ? "" : ", ") + ax.name;
      }
      if (!known)
        throw UserError(
            fmt::format("--regress '{}': got axis '{}', expected a numeric axis of the sweep: {}",
                        spec, a, names));
    }
    out.push_back(r);
  }
  return out;
}

// Fits each --regress over the runs of `algorithm` into j and md.
Named<OlsFitRecord> run_regressions(const std::vector<RunRegression>& specs,
                                    const std::vector<RunData>& runs, const std::string& algorithm,
                                    std::string* md, std::vector<std::string>* warnings) {
  Named<OlsFitRecord> fits;
  for (const auto& spec : specs) {
    std::vector<double> y;
    std::vector<std::vector<double>> columns(spec.axes.size());
    for (const auto& r : runs) {
      if (!meets(*r.job, spec.where)) continue;
      const double v = regression_metric_value(r.metrics, algorithm, spec.metric);
      std::vector<double> x;
      for (const auto& axis : spec.axes)
        for (const auto& [name, value] : r.job->params)
          if (name == axis) x.push_back(std::strtod(value.c_str(), nullptr));
      if (!std::isfinite(v) || x.size() != spec.axes.size()) continue;
      y.push_back(v);
      for (std::size_t k = 0; k < x.size(); ++k) columns[k].push_back(x[k]);
    }
    OlsFitRecord fit;
    std::string subset;
    for (const auto& [axis, value] : spec.where)
      subset += (subset.empty() ? " with " : ", ") + axis + " = " + value;
    *md += fmt::format("\nRegression of `{}` on `{}` over the runs{}:\n\n", spec.metric,
                       fmt::join(spec.axes, "`, `"), subset);
    try {
      if (y.size() < spec.axes.size() + 2)
        throw UserError(fmt::format("got {} runs with a value, need at least {}", y.size(),
                                    spec.axes.size() + 2));
      fit = ols_record(eval::ols(y, columns, spec.axes), md);
    } catch (const UserError& e) {
      fit.skipped = e.what();
      *md += std::string("Not fitted: ") + e.what() + "\n";
      warnings->push_back(
          fmt::format("{}: --regress {} not fitted: {}", algorithm, spec.text, e.what()));
    }
    fits[spec.text] = fit;
  }
  return fits;
}

}  // namespace driftlab::study
