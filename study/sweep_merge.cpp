#include "study/sweep_merge.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <boost/math/distributions/students_t.hpp>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include "core/atomic_file.hpp"
#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/file_io.hpp"
#include "core/process.hpp"
#include "core/yaml_io.hpp"
#include "eval/regression.hpp"
#include "eval/stats.hpp"
#include "pipeline/scenario.hpp"

namespace driftlab::study {

using pipeline::parse_scenario;
using pipeline::Scenario;
namespace fs = std::filesystem;

const std::vector<RunMetric>& run_metrics() {
  static const std::vector<RunMetric> metrics = {
      {"p_m_per_m_mean", "sections.p_m_per_m.mean", "mean section position error [m/m]"},
      {"yaw_deg_per_m_mean", "sections.yaw_deg_per_m.mean", "mean section yaw error [deg/m]"},
      {"ape_trans_rmse_m", "ape.trans_m.rmse", "APE translation RMSE [m]"},
      {"ape_rot_rmse_deg", "ape.rot_deg.rmse", "APE rotation RMSE [deg]"},
      {"rpe_trans_rmse_m", "rpe.trans_m.rmse", "RPE translation RMSE [m]"},
      {"rpe_rot_rmse_deg", "rpe.rot_deg.rmse", "RPE rotation RMSE [deg]"},
      {"track_rmse_3d_m", "track.rmse_3d_m", "track RMSE 3D [m]"},
      {"track_length_error_pct", "track.length_error_pct", "track length error [%]"},
      // The basin paper's table (Section 4): what the wave sweeps are for.
      {"basin_north_rmse_m", "basin.north_m.rmse", "basin table: north RMSE [m]"},
      {"basin_east_rmse_m", "basin.east_m.rmse", "basin table: east RMSE [m]"},
      {"basin_heading_rmse_deg", "basin.heading_deg.rmse", "basin table: heading RMSE [deg]"},
  };
  return metrics;
}

std::pair<double, double> confidence_interval_95(double mean, double sd, std::size_t n) {
  if (n < 2) return {mean, mean};
  const boost::math::students_t t(static_cast<double>(n - 1));
  const double half = boost::math::quantile(t, 0.975) * sd / std::sqrt(static_cast<double>(n));
  return {mean - half, mean + half};
}

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string num(double v) { return std::isfinite(v) ? yaml::format_double(v) : std::string(); }

nlohmann::ordered_json jnum(double v) {
  return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json();
}

struct Table {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
};

Table read_csv(const fs::path& path) {
  Table t;
  std::istringstream in(read_text_file(path, "CSV file"));
  std::string line;
  std::size_t line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    auto cells = split_csv_line(line);
    if (t.header.empty()) {
      t.header = std::move(cells);
      continue;
    }
    if (cells.size() != t.header.size())
      throw UserError(fmt::format("{}:{}: got {} cells, expected {} like the header", path.string(),
                                  line_no, cells.size(), t.header.size()));
    t.rows.push_back(std::move(cells));
  }
  return t;
}

double cell_number(const std::string& s) {
  double v = kNaN;
  if (s.empty() || !yaml::parse_double(s, &v) || !std::isfinite(v)) return kNaN;
  return v;
}

// A number at a dotted key path of a JSON document, NaN when absent or not a number.
double json_number(const nlohmann::json& j, const std::string& dotted) {
  const nlohmann::json* node = &j;
  std::size_t start = 0;
  while (start <= dotted.size()) {
    const auto dot = dotted.find('.', start);
    const std::string key = dotted.substr(start, dot == std::string::npos ? dot : dot - start);
    if (!node->is_object() || !node->contains(key)) return kNaN;
    node = &(*node)[key];
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  return node->is_number() ? node->get<double>() : kNaN;
}

struct Stat {
  std::size_t n = 0;
  double mean = kNaN, sd = kNaN, lo = kNaN, hi = kNaN;
};

Stat stat_of(const std::vector<double>& values) {
  std::vector<double> v;
  for (double x : values)
    if (std::isfinite(x)) v.push_back(x);
  Stat s;
  s.n = v.size();
  if (v.empty()) return s;
  const eval::Summary sum = eval::summarize(v);
  s.mean = sum.mean;
  if (s.n >= 2) {
    s.sd = sum.sd_sample;
    std::tie(s.lo, s.hi) = confidence_interval_95(s.mean, s.sd, s.n);
  }
  return s;
}

nlohmann::ordered_json stat_json(const Stat& s) {
  return {{"n", s.n},
          {"mean", jnum(s.mean)},
          {"sd", jnum(s.sd)},
          {"ci95_low", jnum(s.lo)},
          {"ci95_high", jnum(s.hi)}};
}

std::string file_safe(const std::string& s) {
  std::string out;
  for (char c : s)
    out +=
        std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.' ? c : '_';
  return out;
}

// One merged run.
struct RunData {
  const SweepJob* job;
  nlohmann::json metrics;
};

// An OLS fit into metrics.json (n, R^2, F, each coefficient) and summary.md (a table and
// the fit's paragraph).
void append_ols(const eval::OlsResult& r, nlohmann::ordered_json* j, std::string* md) {
  (*j)["n"] = r.n;
  (*j)["r2"] = jnum(r.r2);
  (*j)["adj_r2"] = jnum(r.adj_r2);
  (*j)["f"] = jnum(r.f);
  (*j)["f_p"] = jnum(r.f_p);
  (*j)["sigma"] = jnum(r.sigma);
  (*j)["coefficients"] = nlohmann::ordered_json::object();
  *md += "| term | estimate | std. error | t | p | VIF |\n|---|---|---|---|---|---|\n";
  for (const auto& c : r.coefficients) {
    (*j)["coefficients"][c.name] = {{"estimate", jnum(c.estimate)},
                                    {"std_error", jnum(c.std_error)},
                                    {"t", jnum(c.t)},
                                    {"p", jnum(c.p)},
                                    {"vif", jnum(c.vif)},
                                    {"significant", c.significant}};
    *md += fmt::format("| {}{} | {:.4g} | {:.3g} | {:.3g} | {:.3g} | {} |\n", c.name,
                       c.significant ? " *" : "", c.estimate, c.std_error, c.t, c.p,
                       c.name == "Intercept" ? std::string("") : fmt::format("{:.3g}", c.vif));
  }
  (*j)["warnings"] = r.warnings;
  *md += "\n" + r.brief() + "\n";
}

// One --regress: a run metric (its runs.csv name, or a key path under algorithms.ALGO) on
// swept axes.
struct RunRegression {
  std::string text, metric;
  std::vector<std::string> axes;
};

std::vector<RunRegression> parse_run_regressions(const std::vector<std::string>& specs,
                                                 const SweepManifest& m) {
  std::vector<RunRegression> out;
  for (const auto& spec : specs) {
    RunRegression r{spec, "", {}};
    const auto tilde = spec.find('~');
    if (tilde == std::string::npos || tilde == 0 || tilde + 1 == spec.size())
      throw UserError(
          fmt::format("--regress: got '{}', expected METRIC~AXIS[+AXIS...], e.g. "
                      "basin_north_rmse_m~amplitude_m",
                      spec));
    r.metric = spec.substr(0, tilde);
    std::string rest = spec.substr(tilde + 1);
    for (std::size_t start = 0; start <= rest.size();) {
      const auto plus = rest.find('+', start);
      r.axes.push_back(rest.substr(start, plus == std::string::npos ? plus : plus - start));
      if (plus == std::string::npos) break;
      start = plus + 1;
    }
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

// The value of a --regress metric in one run: a run metric by name, else a key path.
double regression_metric_value(const nlohmann::json& metrics, const std::string& algorithm,
                               const std::string& metric);

// Fits each --regress over the runs of `algorithm` into j and md.
void run_regressions(const std::vector<RunRegression>& specs, const std::vector<RunData>& runs,
                     const std::string& algorithm, nlohmann::ordered_json* j, std::string* md,
                     std::vector<std::string>* warnings) {
  for (const auto& spec : specs) {
    std::vector<double> y;
    std::vector<std::vector<double>> columns(spec.axes.size());
    for (const auto& r : runs) {
      const double v = regression_metric_value(r.metrics, algorithm, spec.metric);
      std::vector<double> x;
      for (const auto& axis : spec.axes)
        for (const auto& [name, value] : r.job->params)
          if (name == axis) x.push_back(std::strtod(value.c_str(), nullptr));
      if (!std::isfinite(v) || x.size() != spec.axes.size()) continue;
      y.push_back(v);
      for (std::size_t k = 0; k < x.size(); ++k) columns[k].push_back(x[k]);
    }
    nlohmann::ordered_json jr;
    *md += fmt::format("\nRegression of `{}` on `{}` over the runs:\n\n", spec.metric,
                       fmt::join(spec.axes, "`, `"));
    try {
      if (y.size() < spec.axes.size() + 2)
        throw UserError(fmt::format("got {} runs with a value, need at least {}", y.size(),
                                    spec.axes.size() + 2));
      append_ols(eval::ols(y, columns, spec.axes), &jr, md);
    } catch (const UserError& e) {
      jr["skipped"] = e.what();
      *md += std::string("Not fitted: ") + e.what() + "\n";
      warnings->push_back(
          fmt::format("{}: --regress {} not fitted: {}", algorithm, spec.text, e.what()));
    }
    (*j)[spec.text] = jr;
  }
}

}  // namespace

namespace {

double regression_metric_value(const nlohmann::json& metrics, const std::string& algorithm,
                               const std::string& metric) {
  for (const auto& rm : run_metrics())
    if (rm.name == metric) return run_metric_value(metrics, algorithm, rm);
  return json_number(metrics, "algorithms." + algorithm + "." + metric);
}

}  // namespace

double run_metric_value(const nlohmann::json& metrics, const std::string& algorithm,
                        const RunMetric& metric) {
  const std::string at = "algorithms." + algorithm + ".";
  // A run without sections has no section statistics (its zeros are not errors of 0).
  if (std::string_view(metric.path).starts_with("sections.") &&
      !(json_number(metrics, at + "sections.count") > 0))
    return std::numeric_limits<double>::quiet_NaN();
  return json_number(metrics, at + metric.path);
}

std::string MergeSummary::brief() const {
  std::string algos;
  for (const auto& a : algorithms) algos += (algos.empty() ? "" : ", ") + a;
  return fmt::format("merged {} runs, {} sections ({}) into {}; {} plots", runs, sections,
                     algos.empty() ? "no algorithms" : algos, dir.string(), plots.size());
}

MergeSummary merge_sweep(const SweepManifest& m, const MergeOptions& o) {
  MergeSummary out;
  out.dir = m.dir / "summary";
  const std::vector<RunRegression> regressions = parse_run_regressions(o.run_regressions, m);
  const SweepStatus status = sweep_status(m);
  if (!status.complete() && !o.allow_missing) {
    std::string list;
    std::size_t shown = 0;
    for (const auto& st : status.jobs) {
      if (st.state == JobState::kDone) continue;
      if (shown++ < 5)
        list += fmt::format("{}{} {}", list.empty() ? "" : ", ", st.id, yaml::enum_name(st.state));
    }
    if (shown > 5) list += ", ...";
    throw UserError(fmt::format(
        "{}: {} of {} jobs are not done ({}), expected every job done; finish them with "
        "`driftlab sweep run {}` (see `driftlab sweep status`), or merge the finished ones "
        "with --allow-missing",
        m.dir.string(), status.jobs.size() - status.done, status.jobs.size(), list,
        m.dir.string()));
  }
  if (status.done == 0)
    throw UserError(
        fmt::format("{}: no job is done yet, expected at least one finished run "
                    "to merge",
                    m.dir.string()));

  // -------------------------------------------------------------------------
  // Gather: every done run, in manifest order.
  std::vector<RunData> runs;
  std::vector<std::string> run_columns;  // union of the runs' sections.csv columns
  struct Section {
    std::size_t run;
    std::map<std::string, std::string> cells;
  };
  std::vector<Section> sections;
  for (const auto& st : status.jobs) {
    if (st.state != JobState::kDone) continue;
    const SweepJob& job = m.jobs[st.index];
    RunData rd{&job, nlohmann::json::object()};
    const fs::path metrics_file = m.run_dir(job.id) / "metrics.json";
    std::error_code ec;
    if (fs::exists(metrics_file, ec)) {
      try {
        rd.metrics = nlohmann::json::parse(read_text_file(metrics_file, "metrics.json"));
      } catch (const nlohmann::json::parse_error& e) {
        throw UserError(fmt::format("{}: not valid JSON ({}), expected the run's metrics",
                                    metrics_file.string(), e.what()));
      }
    }
    const fs::path sections_file = m.run_dir(job.id) / "sections.csv";
    if (fs::exists(sections_file, ec)) {
      const Table t = read_csv(sections_file);
      for (const auto& h : t.header) {
        if (std::find(run_columns.begin(), run_columns.end(), h) == run_columns.end())
          run_columns.push_back(h);
        for (const auto& a : m.axes)
          if (a.name == h)
            throw UserError(
                fmt::format("{}: axis name '{}' is also a column of the runs' "
                            "sections.csv, expected a distinct name (set `name:` "
                            "on the axis in the sweep file)",
                            m.dir.string(), h));
      }
      for (const auto& row : t.rows) {
        Section s{runs.size(), {}};
        for (std::size_t k = 0; k < row.size(); ++k) s.cells[t.header[k]] = row[k];
        sections.push_back(std::move(s));
      }
    }
    runs.push_back(std::move(rd));
  }
  out.runs = runs.size();
  out.sections = sections.size();

  // Algorithms, in order of first appearance (runs in manifest order, names sorted).
  for (const auto& r : runs)
    if (r.metrics.contains("algorithms") && r.metrics["algorithms"].is_object())
      for (const auto& [name, _] : r.metrics["algorithms"].items())
        if (std::find(out.algorithms.begin(), out.algorithms.end(), name) == out.algorithms.end())
          out.algorithms.push_back(name);
  for (const auto& s : sections) {
    const auto it = s.cells.find("algorithm");
    if (it != s.cells.end() &&
        std::find(out.algorithms.begin(), out.algorithms.end(), it->second) == out.algorithms.end())
      out.algorithms.push_back(it->second);
  }

  // -------------------------------------------------------------------------
  // The pooled table.
  std::vector<std::string> header = {"job", "point", "replicate", "seed"};
  for (const auto& a : m.axes) header.push_back(a.name);
  header.insert(header.end(), run_columns.begin(), run_columns.end());
  auto value_of = [&](const Section& s, const std::string& column) -> std::string {
    const RunData& r = runs[s.run];
    if (column == "job") return r.job->id;
    if (column == "point") return std::to_string(r.job->point);
    if (column == "replicate") return std::to_string(r.job->replicate);
    if (column == "seed") return std::to_string(r.job->seed);
    for (const auto& [name, value] : r.job->params)
      if (name == column) return value;
    const auto it = s.cells.find(column);
    return it == s.cells.end() ? std::string() : it->second;
  };
  std::string pooled_csv = csv_row(header);
  for (const auto& s : sections) {
    std::vector<std::string> row;
    for (const auto& h : header) row.push_back(value_of(s, h));
    pooled_csv += csv_row(row);
  }

  // -------------------------------------------------------------------------
  // Regression on the pool, per algorithm.
  auto is_column = [&](const std::string& c) {
    return std::find(header.begin(), header.end(), c) != header.end();
  };
  auto column_list = [&] {
    std::string s;
    for (std::size_t k = 4; k < header.size(); ++k) s += (s.empty() ? "" : ", ") + header[k];
    return s;
  };
  if (!is_column(o.response) && !sections.empty())
    throw UserError(
        fmt::format("--response: got '{}', expected a column of the pooled sections: "
                    "{}",
                    o.response, column_list()));
  for (const auto& c : o.covariates)
    if (!is_column(c) || c == "job" || c == "point" || c == "replicate" || c == "seed")
      throw UserError(
          fmt::format("--covariates: got '{}', expected a column of the pooled "
                      "sections: {}",
                      c, sections.empty() ? "(none: no run has sections)" : column_list()));
  for (const auto& c : o.covariates)
    for (const auto& a : m.axes)
      if (a.name == c && !a.numeric)
        throw UserError(
            fmt::format("--covariates: got '{}', expected a numeric column (the "
                        "axis '{}' has values that are not numbers)",
                        c, a.key));
  std::vector<std::string> covariates = o.covariates;
  bool default_covariates = covariates.empty();
  if (default_covariates) {
    std::vector<std::string> base_covariates{"v", "h", "f", "d"};
    try {
      const Scenario base = parse_scenario(read_text_file(m.scenario_file(), "scenario file"),
                                           m.scenario_file().string(), m.base_dir());
      base_covariates = base.eval.regression_covariates;
    } catch (const UserError&) {
      // The plan checked scenario.yaml; if it was edited since, the runs say what is there.
    }
    for (const auto& c : base_covariates) {
      if (is_column(c)) {
        covariates.push_back(c);
      } else if (!sections.empty()) {
        out.warnings.push_back(
            fmt::format("regression: covariate '{}' of the base scenario is "
                        "not in the pooled sections; left out",
                        c));
      }
    }
    for (const auto& a : m.axes) {
      if (!a.numeric) continue;
      std::set<std::string> distinct;
      for (const auto& r : runs)
        for (const auto& [name, value] : r.job->params)
          if (name == a.name) distinct.insert(value);
      if (distinct.size() > 1) covariates.push_back(a.name);
    }
  }

  nlohmann::ordered_json metrics;
  metrics["sweep"] = {{"name", m.info.value("name", "")},
                      {"design", m.info.value("design", "")},
                      {"jobs", m.jobs.size()},
                      {"merged_runs", runs.size()},
                      {"points", m.info.value("points", 0)},
                      {"replicates", m.info.value("replicates", 1)},
                      {"sections", sections.size()}};
  metrics["sweep"]["axes"] = nlohmann::ordered_json::array();
  for (const auto& a : m.axes)
    metrics["sweep"]["axes"].push_back({{"key", a.key}, {"name", a.name}});
  metrics["algorithms"] = nlohmann::ordered_json::object();

  std::string md = fmt::format("# Sweep {}\n\n", m.info.value("name", ""));
  if (!m.info.value("description", "").empty()) md += m.info.value("description", "") + "\n\n";
  md += fmt::format(
      "Design {}, {} points x {} replicates = {} jobs; {} runs merged, {} sections "
      "pooled.\n\nAxes:\n\n",
      m.info.value("design", ""), m.info.value("points", 0), m.info.value("replicates", 1),
      m.jobs.size(), runs.size(), sections.size());
  for (const auto& a : m.axes)
    md += a.name == a.key ? fmt::format("- `{}`\n", a.key)
                          : fmt::format("- `{}` (column `{}`)\n", a.key, a.name);
  if (runs.size() < m.jobs.size())
    md += fmt::format("\n**{} of {} jobs are not done; this summary covers the finished ones.**\n",
                      m.jobs.size() - runs.size(), m.jobs.size());

  const std::vector<std::pair<std::string, std::string>> section_errors = {
      {"p_m_per_m", "ε'_p [m/m]"},           {"x_m_per_m", "ε'_x [m/m]"},
      {"y_m_per_m", "ε'_y [m/m]"},           {"z_m_per_m", "ε'_z [m/m]"},
      {"roll_deg_per_m", "ε'_roll [deg/m]"}, {"pitch_deg_per_m", "ε'_pitch [deg/m]"},
      {"yaw_deg_per_m", "ε'_yaw [deg/m]"}};

  for (const auto& algo : out.algorithms) {
    nlohmann::ordered_json ja;
    std::vector<const Section*> rows;
    for (const auto& s : sections) {
      const auto it = s.cells.find("algorithm");
      if (it != s.cells.end() && it->second == algo) rows.push_back(&s);
    }
    md += fmt::format("\n## {}\n\n", algo);
    // Section errors over the pool (river paper Table 1).
    ja["sections"]["count"] = rows.size();
    md += fmt::format("Pooled section errors, {} sections (river paper Table 1):\n\n", rows.size());
    md += "| error | Min | Mean | Median | SD | Max | n |\n|---|---|---|---|---|---|---|\n";
    for (const auto& [column, label] : section_errors) {
      std::vector<double> v;
      for (const Section* s : rows) {
        const double x = cell_number(value_of(*s, column));
        if (std::isfinite(x)) v.push_back(x);
      }
      const eval::Summary sum = eval::summarize(v);
      ja["sections"][column] = {{"n", sum.n},
                                {"min", jnum(v.empty() ? kNaN : sum.min)},
                                {"mean", jnum(v.empty() ? kNaN : sum.mean)},
                                {"median", jnum(v.empty() ? kNaN : sum.median)},
                                {"sd", jnum(v.size() < 2 ? kNaN : sum.sd_sample)},
                                {"rmse", jnum(v.empty() ? kNaN : sum.rmse)},
                                {"max", jnum(v.empty() ? kNaN : sum.max)}};
      auto f = [&](double x, bool ok) { return ok ? fmt::format("{:.4g}", x) : std::string("—"); };
      md += fmt::format("| {} | {} | {} | {} | {} | {} | {} |\n", label, f(sum.min, sum.n > 0),
                        f(sum.mean, sum.n > 0), f(sum.median, sum.n > 0),
                        f(sum.sd_sample, sum.n > 1), f(sum.max, sum.n > 0), sum.n);
    }

    // OLS of Eq. (13) on the pool.
    nlohmann::ordered_json jr;
    jr["response"] = o.response;
    jr["covariates"] = covariates;
    std::vector<std::string> names;
    for (const auto& c : covariates) {
      bool any = false;
      for (const Section* s : rows) any = any || std::isfinite(cell_number(value_of(*s, c)));
      if (any) {
        names.push_back(c);
      } else if (!default_covariates) {
        names.push_back(c);  // the fit reports it (no values)
      }
    }
    std::vector<double> y;
    std::vector<std::vector<double>> columns(names.size());
    std::size_t dropped = 0;
    for (const Section* s : rows) {
      std::vector<double> x;
      bool complete = std::isfinite(cell_number(value_of(*s, o.response)));
      for (const auto& c : names) {
        x.push_back(cell_number(value_of(*s, c)));
        complete = complete && std::isfinite(x.back());
      }
      if (!complete) {
        ++dropped;
        continue;
      }
      y.push_back(cell_number(value_of(*s, o.response)));
      for (std::size_t k = 0; k < names.size(); ++k) columns[k].push_back(x[k]);
    }
    jr["dropped_sections"] = dropped;
    md += fmt::format(
        "\nRegression of `{}` on {} over the pool (river paper Eq. (13)):\n\n", o.response,
        names.empty() ? std::string("nothing") : fmt::format("`{}`", fmt::join(names, "`, `")));
    std::string skipped;
    if (names.empty()) {
      skipped = "no covariate has values in the pooled sections";
    } else if (y.size() < names.size() + 2) {
      skipped = fmt::format(
          "got {} complete sections, need at least {} for {} covariates and an "
          "intercept",
          y.size(), names.size() + 2, names.size());
    } else {
      try {
        append_ols(eval::ols(y, columns, names), &jr, &md);
      } catch (const UserError& e) {
        skipped = e.what();
      }
    }
    if (!skipped.empty()) {
      jr["skipped"] = skipped;
      md += "Not fitted: " + skipped + "\n";
      out.warnings.push_back(fmt::format("{}: regression not fitted: {}", algo, skipped));
    }
    if (dropped)
      md += fmt::format("\n{} of {} sections lack a value and were left out.\n", dropped,
                        rows.size());
    ja["regression"] = jr;

    // Run metrics over all runs.
    ja["runs"] = nlohmann::ordered_json::object();
    for (const auto& rm : run_metrics()) {
      std::vector<double> v;
      for (const auto& r : runs) v.push_back(run_metric_value(r.metrics, algo, rm));
      ja["runs"][rm.name] = stat_json(stat_of(v));
    }
    if (!o.run_regressions.empty()) {
      ja["run_regressions"] = nlohmann::ordered_json::object();
      run_regressions(regressions, runs, algo, &ja["run_regressions"], &md, &out.warnings);
    }
    metrics["algorithms"][algo] = ja;
  }

  // -------------------------------------------------------------------------
  // Per run and per point.
  std::vector<std::string> run_header = {"job", "point", "replicate", "seed"};
  for (const auto& a : m.axes) run_header.push_back(a.name);
  run_header.push_back("algorithm");
  for (const auto& rm : run_metrics()) run_header.push_back(rm.name);
  std::string runs_csv = csv_row(run_header);
  for (const auto& r : runs)
    for (const auto& algo : out.algorithms) {
      std::vector<std::string> row = {r.job->id, std::to_string(r.job->point),
                                      std::to_string(r.job->replicate),
                                      std::to_string(r.job->seed)};
      for (const auto& [name, value] : r.job->params) row.push_back(value);
      row.push_back(algo);
      for (const auto& rm : run_metrics())
        row.push_back(num(run_metric_value(r.metrics, algo, rm)));
      runs_csv += csv_row(row);
    }

  std::vector<std::string> point_header = {"point"};
  for (const auto& a : m.axes) point_header.push_back(a.name);
  point_header.push_back("algorithm");
  point_header.push_back("runs");
  for (const auto& rm : run_metrics())
    for (const char* suffix : {"_mean", "_sd", "_ci95_low", "_ci95_high"})
      point_header.push_back(std::string(rm.name) + suffix);
  std::string points_csv = csv_row(point_header);
  std::map<std::size_t, std::vector<const RunData*>> by_point;  // ordered by point index
  for (const auto& r : runs) by_point[r.job->point].push_back(&r);
  metrics["points"] = nlohmann::ordered_json::object();
  // The table shows the first run metric the runs have (sections, else the APE, else ...).
  std::string main_metric = run_metrics().front().name;
  for (auto it = run_metrics().rbegin(); it != run_metrics().rend(); ++it)
    for (const auto& r : runs)
      for (const auto& algo : out.algorithms)
        if (std::isfinite(run_metric_value(r.metrics, algo, *it))) main_metric = it->name;
  md +=
      fmt::format("\n## Points\n\n`{}` per point, mean over replicates [95% CI]:\n\n", main_metric);
  md += "| point |";
  for (const auto& a : m.axes) md += " " + a.name + " |";
  for (const auto& algo : out.algorithms) md += " " + algo + " |";
  md += "\n|---|";
  for (std::size_t k = 0; k < m.axes.size() + out.algorithms.size(); ++k) md += "---|";
  md += "\n";
  for (const auto& [point, point_runs] : by_point) {
    const std::string pid = fmt::format("p{:04}", point);
    nlohmann::ordered_json jp;
    jp["params"] = nlohmann::ordered_json::object();
    for (const auto& [name, value] : point_runs.front()->job->params)
      jp["params"][name] = yaml_text_to_json(value);
    jp["runs"] = point_runs.size();
    md += "| " + pid + " |";
    for (const auto& [name, value] : point_runs.front()->job->params) md += " " + value + " |";
    for (const auto& algo : out.algorithms) {
      std::vector<std::string> row = {std::to_string(point)};
      for (const auto& [name, value] : point_runs.front()->job->params) row.push_back(value);
      row.push_back(algo);
      row.push_back(std::to_string(point_runs.size()));
      for (const auto& rm : run_metrics()) {
        std::vector<double> v;
        for (const RunData* r : point_runs) v.push_back(run_metric_value(r->metrics, algo, rm));
        const Stat s = stat_of(v);
        row.push_back(num(s.mean));
        row.push_back(num(s.sd));
        row.push_back(num(s.lo));
        row.push_back(num(s.hi));
        jp["algorithms"][algo][rm.name] = stat_json(s);
        if (rm.name == main_metric)
          md += s.n == 0   ? " — |"
                : s.n == 1 ? fmt::format(" {:.4g} |", s.mean)
                           : fmt::format(" {:.4g} [{:.4g}, {:.4g}] |", s.mean, s.lo, s.hi);
      }
      points_csv += csv_row(row);
    }
    md += "\n";
    metrics["points"][pid] = jp;
  }

  // Plot warnings depend on the machine (is gnuplot installed?), not on the runs.
  metrics["warnings"] = out.warnings;

  // -------------------------------------------------------------------------
  // Write (aside, then rename into place), plots included.
  AtomicDirectory dir(out.dir, /*replace=*/true);
  write_file_atomic(dir.path() / "sections.csv", pooled_csv);
  write_file_atomic(dir.path() / "runs.csv", runs_csv);
  write_file_atomic(dir.path() / "points.csv", points_csv);

  // Plots: for every axis and the first metrics, the marginal mean over all
  // runs at each axis value (other axes and replicates pooled), with its 95% CI.
  std::vector<std::string> plot_md;
  std::optional<fs::path> gnuplot;
  std::string terminal;
  if (o.plots && !out.algorithms.empty()) {
    gnuplot = o.gnuplot.empty() ? find_on_path("gnuplot") : std::optional<fs::path>(o.gnuplot);
    if (!gnuplot) {
      out.warnings.push_back("gnuplot not found on PATH: plots skipped (install gnuplot-nox)");
    } else {
      // pngcairo draws nicer; the libgd `png` terminal is the fallback.
      ProcessSpec probe{*gnuplot, {"-e", "set terminal pngcairo"}, "/dev/null", {}, true};
      try {
        terminal = wait_process(spawn_process(probe)).ok() ? "pngcairo" : "png";
      } catch (const UserError& e) {
        out.warnings.push_back(std::string("gnuplot cannot run: plots skipped: ") + e.what());
        gnuplot.reset();
      }
    }
  }
  if (gnuplot) {
    const fs::path plots = dir.path() / "plots";
    fs::create_directories(plots);
    for (const auto& a : m.axes) {
      // Axis values in order: numeric ascending, else first appearance.
      std::vector<std::string> values;
      for (const auto& r : runs)
        for (const auto& [name, value] : r.job->params)
          if (name == a.name && std::find(values.begin(), values.end(), value) == values.end())
            values.push_back(value);
      if (a.numeric)
        std::stable_sort(values.begin(), values.end(),
                         [](const std::string& x, const std::string& y) {
                           return cell_number(x) < cell_number(y);
                         });
      bool log_x = a.spec == "logspace";
      for (const auto& v : values) log_x = log_x && a.numeric && cell_number(v) > 0;
      for (std::size_t mi = 0; mi < run_metrics().size(); ++mi) {  // those the runs have
        const RunMetric& rm = run_metrics()[mi];
        const std::string stem = file_safe(a.name) + "__" + rm.name;
        std::string dat = fmt::format(
            "# {} vs {}: x, mean, ci95_low, ci95_high, runs, label; one "
            "block per algorithm\n",
            rm.name, a.name);
        std::vector<std::pair<std::size_t, std::string>> series;  // block index, algorithm
        std::size_t block = 0;
        for (const auto& algo : out.algorithms) {
          std::string rows;
          for (std::size_t k = 0; k < values.size(); ++k) {
            std::vector<double> v;
            for (const auto& r : runs)
              for (const auto& [name, value] : r.job->params)
                if (name == a.name && value == values[k])
                  v.push_back(run_metric_value(r.metrics, algo, rm));
            const Stat s = stat_of(v);
            if (s.n == 0) continue;
            std::string label = values[k];
            std::replace(label.begin(), label.end(), '"', '\'');
            rows += fmt::format("{} {} {} {} {} \"{}\"\n",
                                a.numeric ? num(cell_number(values[k])) : std::to_string(k),
                                num(s.mean), num(s.n >= 2 ? s.lo : s.mean),
                                num(s.n >= 2 ? s.hi : s.mean), s.n, label);
          }
          if (rows.empty()) continue;
          dat += fmt::format("# {}\n{}\n\n", algo, rows);
          series.emplace_back(block++, algo);
        }
        if (series.empty()) continue;
        std::string gp = fmt::format(
            "# Regenerate with: gnuplot {stem}.gp (in this folder)\n"
            "set terminal {term} size 900,560 noenhanced\n"
            "set output '{stem}.png'\n"
            "set title \"{metric} vs {axis} (mean over runs, 95% CI)\"\n"
            "set xlabel \"{key}\"\nset ylabel \"{label}\"\n"
            "set grid\nset key outside right top\nset offsets graph 0.05, graph 0.05, 0, 0\n"
            "{logx}{xtics}"
            "plot ",
            fmt::arg("stem", stem), fmt::arg("term", terminal), fmt::arg("metric", rm.name),
            fmt::arg("axis", a.name), fmt::arg("key", a.key), fmt::arg("label", rm.label),
            fmt::arg("logx", log_x ? "set logscale x\n" : ""),
            fmt::arg("xtics", a.numeric ? "" : "set xtics rotate by -30\n"));
        // Series side by side (dodged by a little of the x range) so that their bars do not hide
        // one another.
        double lo = 0, hi = 1;
        if (a.numeric && !values.empty()) {
          lo = cell_number(values.front());
          hi = cell_number(values.back());
        } else {
          hi = static_cast<double>(values.size());
        }
        const double span = hi > lo ? hi - lo : 1.0;
        for (std::size_t k = 0; k < series.size(); ++k) {
          const double shift =
              (static_cast<double>(k) - (static_cast<double>(series.size()) - 1) / 2);
          const std::string x = !a.numeric ? fmt::format("($1{:+g})", 0.08 * shift)
                                : log_x ? fmt::format("($1*{:g})", std::pow(hi / lo, 0.012 * shift))
                                        : fmt::format("($1{:+g})", 0.012 * span * shift);
          gp += fmt::format("{}'{}.dat' index {} using {}:2:3:4{} with yerrorlines title '{}'",
                            k ? ", \\\n     " : "", stem, series[k].first, x,
                            a.numeric ? "" : ":xtic(6)", series[k].second);
        }
        gp += "\n";
        write_file_atomic(plots / (stem + ".dat"), dat);
        write_file_atomic(plots / (stem + ".gp"), gp);
        const fs::path log = plots / (stem + ".log");
        ProcessSpec spec{*gnuplot, {stem + ".gp"}, log, plots, true};
        const ExitStatus st = wait_process(spawn_process(spec));
        std::error_code ec;
        if (st.ok() && fs::exists(plots / (stem + ".png"), ec)) {
          fs::remove(log, ec);
          out.plots.push_back("plots/" + stem + ".png");
          plot_md.push_back(fmt::format("![{} vs {}](plots/{}.png)", rm.name, a.name, stem));
        } else {
          out.warnings.push_back(
              fmt::format("gnuplot failed on plots/{}.gp ({}); see "
                          "summary/plots/{}.log",
                          stem, st.describe(), stem));
        }
      }
    }
  }
  if (!plot_md.empty()) {
    md += "\n## Plots\n\n";
    for (const auto& p : plot_md) md += p + "\n\n";
  }
  if (!out.warnings.empty()) {
    md += "\n## Warnings\n\n";
    for (const auto& w : out.warnings) md += "- " + w + "\n";
  }
  write_file_atomic(dir.path() / "metrics.json", metrics.dump(2) + "\n");
  write_file_atomic(dir.path() / "summary.md", md);
  dir.commit();
  return out;
}

}  // namespace driftlab::study
