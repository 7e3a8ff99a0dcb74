#include "study/sweep_merge.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
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
#include "gate/paired.hpp"
#include "pipeline/scenario.hpp"
#include "study/run_regressions.hpp"
#include "study/sweep_plots.hpp"
#include "study/sweep_pool.hpp"

namespace driftlab::study {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

using pipeline::parse_scenario;
using pipeline::Scenario;
namespace fs = std::filesystem;

const std::vector<RunMetric>& run_metrics() {
  using A = const record::AlgorithmRecord&;
  static const std::vector<RunMetric> metrics = {
      {"p_m_per_m_mean", "mean section position error [m/m]", true,
       [](A a) { return a.evaluation.sections.rows.p_m_per_m.mean; }},
      {"yaw_deg_per_m_mean", "mean section yaw error [deg/m]", true,
       [](A a) { return a.evaluation.sections.rows.yaw_deg_per_m.mean; }},
      {"ape_trans_rmse_m", "APE translation RMSE [m]", false,
       [](A a) { return a.evaluation.ape.trans_m.rmse; }},
      {"ape_rot_rmse_deg", "APE rotation RMSE [deg]", false,
       [](A a) { return a.evaluation.ape.rot_deg.rmse; }},
      {"rpe_trans_rmse_m", "RPE translation RMSE [m]", false,
       [](A a) { return a.evaluation.rpe.errors.trans_m.rmse; }},
      {"rpe_rot_rmse_deg", "RPE rotation RMSE [deg]", false,
       [](A a) { return a.evaluation.rpe.errors.rot_deg.rmse; }},
      {"track_rmse_3d_m", "track RMSE 3D [m]", false,
       [](A a) { return a.evaluation.track.rmse_3d_m; }},
      {"track_length_error_pct", "track length error [%]", false,
       [](A a) { return a.evaluation.track.length_error_pct; }},
      // The basin paper's table (Section 4): what the wave sweeps are for.
      {"basin_north_rmse_m", "basin table: north RMSE [m]", false,
       [](A a) { return a.evaluation.basin.north_m.rmse; }},
      {"basin_east_rmse_m", "basin table: east RMSE [m]", false,
       [](A a) { return a.evaluation.basin.east_m.rmse; }},
      {"basin_heading_rmse_deg", "basin table: heading RMSE [deg]", false,
       [](A a) { return a.evaluation.basin.heading_deg.rmse; }},
      {"basin_surge_rmse_m_s", "basin table: surge RMSE [m/s]", false,
       [](A a) { return a.evaluation.basin.surge_m_s.rmse; }},
      {"basin_sway_rmse_m_s", "basin table: sway RMSE [m/s]", false,
       [](A a) { return a.evaluation.basin.sway_m_s.rmse; }},
      // A VO's tracking, and a filter against the raw VO it follows (missing for the others).
      {"lost_fraction", "share of frames without a VO motion", false,
       [](A a) { return a.tracking ? a.tracking->lost_fraction : kNaN; }},
      {"filter_vs_raw_ratio", "filter's APE translation RMSE / its raw VO's (< 1: it helps)", false,
       [](A a) { return a.vs_raw_vo ? a.vs_raw_vo->ratio : kNaN; }},
      {"filter_nonfinite_guards", "filter's non-finite guards", false,
       [](A a) {
         if (!a.filter) return kNaN;
         const auto it = a.filter->find("nonfinite_guards");
         return it == a.filter->end() ? kNaN : static_cast<double>(it->second);
       }},
  };
  return metrics;
}

namespace {

RunStatRecord stat_record(const Stat& s) { return {s.n, s.mean, s.sd, s.lo, s.hi}; }

}  // namespace

double run_metric_value(const record::RunRecord& metrics, const std::string& algorithm,
                        const RunMetric& metric) {
  const auto it = metrics.algorithms.find(algorithm);
  if (it == metrics.algorithms.end()) return kNaN;
  const record::AlgorithmRecord& a = it->second;
  // A run without sections has no section statistics (its zeros are not errors of 0).
  if (metric.of_sections && a.evaluation.sections.count == 0) return kNaN;
  return metric.value(a);
}

std::string MergeSummary::brief() const {
  std::string algos;
  for (const auto& a : algorithms) algos += (algos.empty() ? "" : ", ") + a;
  return fmt::format("merged {} runs, {} sections ({}) into {}; {} plots", runs, sections,
                     algos.empty() ? "no algorithms" : algos, dir.string(), plots.size());
}

namespace {

// Merging needs every job done, unless allow_missing; and at least one.
void require_done_jobs(const SweepManifest& m, const SweepStatus& status, bool allow_missing) {
  if (!status.complete() && !allow_missing) {
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
}

// The covariates of the pooled regression: --covariates, checked against the pool; by default
// the base scenario's eval.regression_covariates that the pool has, and every numeric axis
// that varies.
struct Covariates {
  std::vector<std::string> names;
  bool by_default = false;
};

Covariates pooled_covariates(const SweepManifest& m, const MergeOptions& o, const Pool& pool,
                             std::vector<std::string>* warnings) {
  if (!pool.is_column(o.response) && !pool.sections.empty())
    throw UserError(
        fmt::format("--response: got '{}', expected a column of the pooled sections: "
                    "{}",
                    o.response, pool.column_list()));
  for (const auto& c : o.covariates)
    if (!pool.is_column(c) || c == "job" || c == "point" || c == "replicate" || c == "seed")
      throw UserError(fmt::format(
          "--covariates: got '{}', expected a column of the pooled "
          "sections: {}",
          c, pool.sections.empty() ? "(none: no run has sections)" : pool.column_list()));
  for (const auto& c : o.covariates)
    for (const auto& a : m.axes)
      if (a.name == c && !a.numeric)
        throw UserError(
            fmt::format("--covariates: got '{}', expected a numeric column (the "
                        "axis '{}' has values that are not numbers)",
                        c, a.key));
  Covariates out{o.covariates, o.covariates.empty()};
  if (!out.by_default) return out;
  std::vector<std::string> base_covariates{"v", "h", "f", "d"};
  try {
    const Scenario base = parse_scenario(read_text_file(m.scenario_file(), "scenario file"),
                                         m.scenario_file().string(), m.base_dir());
    base_covariates = base.eval.regression_covariates;
  } catch (const UserError&) {
    // The plan checked scenario.yaml; if it was edited since, the runs say what is there.
  }
  for (const auto& c : base_covariates) {
    if (pool.is_column(c)) {
      out.names.push_back(c);
    } else if (!pool.sections.empty()) {
      warnings->push_back(
          fmt::format("regression: covariate '{}' of the base scenario is "
                      "not in the pooled sections; left out",
                      c));
    }
  }
  for (const auto& a : m.axes) {
    if (!a.numeric) continue;
    std::set<std::string> distinct;
    for (const auto& r : pool.runs)
      for (const auto& [name, value] : r.job->params)
        if (name == a.name) distinct.insert(value);
    if (distinct.size() > 1) out.names.push_back(a.name);
  }
  return out;
}

// metrics.json's `sweep` block.
SweepSummaryInfoRecord sweep_info_record(const SweepManifest& m, const Pool& pool) {
  SweepSummaryInfoRecord r{m.info.name,   m.info.design,     m.jobs.size(),        pool.runs.size(),
                           m.info.points, m.info.replicates, pool.sections.size(), {}};
  for (const auto& a : m.axes) r.axes.push_back({a.key, a.name});
  return r;
}

// summary.md's title, design and axes.
std::string summary_head_md(const SweepManifest& m, const Pool& pool) {
  std::string md = fmt::format("# Sweep {}\n\n", m.info.name);
  if (!m.info.description.empty()) md += m.info.description + "\n\n";
  md += fmt::format(
      "Design {}, {} points x {} replicates = {} jobs; {} runs merged, {} sections "
      "pooled.\n\nAxes:\n\n",
      yaml::enum_name(m.info.design), m.info.points, m.info.replicates, m.jobs.size(),
      pool.runs.size(), pool.sections.size());
  for (const auto& a : m.axes)
    md += a.name == a.key ? fmt::format("- `{}`\n", a.key)
                          : fmt::format("- `{}` (column `{}`)\n", a.key, a.name);
  if (pool.runs.size() < m.jobs.size())
    md += fmt::format("\n**{} of {} jobs are not done; this summary covers the finished ones.**\n",
                      m.jobs.size() - pool.runs.size(), m.jobs.size());
  return md;
}

// A block of metrics.json with its part of summary.md.
template <class Record>
struct Part {
  Record record;
  std::string md;
};

// River paper Table 1 over the pooled sections of one algorithm: each error of the record,
// from the sections.csv column of its key, labelled by its doc.
class SectionErrorsFiller : public yaml::IgnoresRules {
 public:
  SectionErrorsFiller(const Pool& pool, const std::vector<const PooledSection*>& rows,
                      std::string* md)
      : pool_(pool), rows_(rows), md_(md) {}

  void operator()(const char*, std::size_t&, const char*) {}  // the count
  void operator()(const char* column, SectionErrorStatsRecord& r, const char* label) {
    std::vector<double> v;
    for (const PooledSection* s : rows_) {
      const double x = cell_number(pool_.value_of(*s, column));
      if (std::isfinite(x)) v.push_back(x);
    }
    const eval::Summary sum = eval::summarize(v);
    r = {sum.n,
         v.empty() ? kNaN : sum.min,
         v.empty() ? kNaN : sum.mean,
         v.empty() ? kNaN : sum.median,
         v.size() < 2 ? kNaN : sum.sd_sample,
         v.empty() ? kNaN : sum.rmse,
         v.empty() ? kNaN : sum.max};
    auto f = [&](double x, bool ok) { return ok ? fmt::format("{:.4g}", x) : std::string("—"); };
    *md_ += fmt::format("| {} | {} | {} | {} | {} | {} | {} |\n", label, f(sum.min, sum.n > 0),
                        f(sum.mean, sum.n > 0), f(sum.median, sum.n > 0),
                        f(sum.sd_sample, sum.n > 1), f(sum.max, sum.n > 0), sum.n);
  }

 private:
  const Pool& pool_;
  const std::vector<const PooledSection*>& rows_;
  std::string* md_;
};

Part<PooledSectionsRecord> pooled_section_errors(const Pool& pool,
                                                 const std::vector<const PooledSection*>& rows) {
  Part<PooledSectionsRecord> p;
  p.record.count = rows.size();
  p.md = fmt::format("Pooled section errors, {} sections (river paper Table 1):\n\n", rows.size());
  p.md += "| error | Min | Mean | Median | SD | Max | n |\n|---|---|---|---|---|---|---|\n";
  SectionErrorsFiller fill(pool, rows, &p.md);
  p.record.visit(fill);
  return p;
}

// OLS of the river paper's Eq. (13) on the pooled sections of one algorithm.
Part<PooledRegressionRecord> pooled_regression(const Pool& pool,
                                               const std::vector<const PooledSection*>& rows,
                                               const std::string& response,
                                               const Covariates& covariates,
                                               const std::string& algorithm,
                                               std::vector<std::string>* warnings) {
  Part<PooledRegressionRecord> p;
  p.record.response = response;
  p.record.covariates = covariates.names;
  std::vector<std::string> names;
  for (const auto& c : covariates.names) {
    bool any = false;
    for (const PooledSection* s : rows)
      any = any || std::isfinite(cell_number(pool.value_of(*s, c)));
    if (any || !covariates.by_default) names.push_back(c);  // an asked-for one: the fit says
  }
  std::vector<double> y;
  std::vector<std::vector<double>> columns(names.size());
  std::size_t dropped = 0;
  for (const PooledSection* s : rows) {
    std::vector<double> x;
    bool complete = std::isfinite(cell_number(pool.value_of(*s, response)));
    for (const auto& c : names) {
      x.push_back(cell_number(pool.value_of(*s, c)));
      complete = complete && std::isfinite(x.back());
    }
    if (!complete) {
      ++dropped;
      continue;
    }
    y.push_back(cell_number(pool.value_of(*s, response)));
    for (std::size_t k = 0; k < names.size(); ++k) columns[k].push_back(x[k]);
  }
  p.record.dropped_sections = dropped;
  p.md = fmt::format(
      "\nRegression of `{}` on {} over the pool (river paper Eq. (13)):\n\n", response,
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
      p.record.fit = ols_record(eval::ols(y, columns, names), &p.md);
    } catch (const UserError& e) {
      skipped = e.what();
    }
  }
  if (!skipped.empty()) {
    p.record.fit.skipped = skipped;
    p.md += "Not fitted: " + skipped + "\n";
    warnings->push_back(fmt::format("{}: regression not fitted: {}", algorithm, skipped));
  }
  if (dropped)
    p.md +=
        fmt::format("\n{} of {} sections lack a value and were left out.\n", dropped, rows.size());
  return p;
}

// Every job's value of the gate's paired metrics (gate/gate.hpp), by job id, and every
// section's position error by JOB/INDEX: what a baseline and a change are compared on pair by
// pair. Non-finite values are left out.
Named<Named<double>> per_pair_values(const Pool& pool, const std::string& algo,
                                     const std::vector<const PooledSection*>& rows) {
  Named<Named<double>> pairs;
  auto& sections = pairs["p_m_per_m_sections"];
  for (const PooledSection* s : rows) {
    double v = 0;
    const auto it = s->cells.find("p_m_per_m");
    const auto index = s->cells.find("index");
    if (it != s->cells.end() && index != s->cells.end() && yaml::parse_double(it->second, &v) &&
        std::isfinite(v))
      sections[pool.runs[s->run].job->id + "/" + index->second] = v;
  }
  for (const auto& rm : run_metrics()) {
    Named<double> by_job;
    for (const auto& r : pool.runs)
      if (const double v = run_metric_value(r.metrics, algo, rm); std::isfinite(v))
        by_job[r.job->id] = v;
    if (!by_job.empty()) pairs[rm.name] = std::move(by_job);
  }
  return pairs;
}

// The metrics a summary's paired tables show (metrics.json has every one).
bool shown_paired(const std::string& metric) {
  for (const char* m : {"p_m_per_m_sections", "ape_trans_rmse_m", "ape_rot_rmse_deg",
                        "track_length_error_pct", "lost_fraction"})
    if (metric == m) return true;
  return false;
}

// B against A over the pair names both have (`rename` maps a name to the one it pairs under),
// as metrics.json holds it and as a summary row; nothing when no pair is common.
std::optional<Part<PairedRowRecord>> paired_row(const std::string& label, const std::string& metric,
                                                const std::map<std::string, double>& a_values,
                                                const std::map<std::string, double>& b_values) {
  std::vector<double> a, b;
  for (const auto& [id, v] : a_values)
    if (const auto it = b_values.find(id); it != b_values.end()) {
      a.push_back(v);
      b.push_back(it->second);
    }
  if (a.empty()) return std::nullopt;
  const gate::PairedChange c = gate::paired_change(a, b);
  const double p_two = std::min(1.0, 2 * std::min(c.test.p_greater, c.test.p_less));
  Part<PairedRowRecord> r;
  r.record = {c.n,  c.mean_a, c.mean_b, c.diff, {c.diff_lo, c.diff_hi}, c.rel, {c.rel_lo, c.rel_hi},
              p_two};
  r.md = fmt::format("| {} | {} | {} | {:.4g} | {:.4g} | {:+.1f}% [{:+.1f}, {:+.1f}] | {:.2g} |\n",
                     label, metric, c.n, c.mean_a, c.mean_b, 100 * c.rel, 100 * c.rel_lo,
                     100 * c.rel_hi, p_two);
  return r;
}

// The values of one paired metric by pair name; with `point`: only that point's jobs (job
// names, not sections), named by their replicate ("-r01").
std::map<std::string, double> pair_values(const Named<double>& values,
                                          std::optional<std::string> point = std::nullopt) {
  std::map<std::string, double> out;
  for (const auto& [id, v] : values) {
    if (!point) {
      out[id] = v;
      continue;
    }
    const auto dash = id.find('-');
    if (id.find('/') == std::string::npos && dash != std::string::npos &&
        id.substr(0, dash) == *point)
      out[id.substr(dash)] = v;
  }
  return out;
}

const char* kPairedHead =
    "| B vs A | metric | pairs | A | B | B - A | p |\n|---|---|---|---|---|---|---|\n";

// A/B statistics of every two algorithms on the same jobs (summary.md's "Paired comparisons"): for
// each paired metric, the mean of B - A over the pairs both have (sections by JOB/INDEX, run
// metrics by job) with its 95 % interval and the two-sided Wilcoxon signed-rank p-value
// (gate/paired.hpp).
Part<Named<Named<PairedRowRecord>>> paired_algorithms(
    const Named<AlgorithmSummaryRecord>& algorithms) {
  Part<Named<Named<PairedRowRecord>>> p;
  std::vector<const std::pair<std::string, AlgorithmSummaryRecord>*> named;
  for (const auto& entry : algorithms) named.push_back(&entry);
  if (named.size() < 2) return p;
  p.md = std::string(
             "\n## Paired comparisons of the algorithms\n\nEach row compares B with A on the "
             "same jobs (and sections): the mean of B - A over the pairs both have, relative to "
             "A's mean, with its 95% interval, and the two-sided signed-rank p-value (every "
             "metric: metrics.json `paired`).\n\n") +
         kPairedHead;
  for (std::size_t i = 0; i < named.size(); ++i)
    for (std::size_t j = i + 1; j < named.size(); ++j) {
      const std::string label = named[j]->first + " vs " + named[i]->first;
      const auto& b_all = named[j]->second.pairs;
      for (const auto& [metric, a_values] : named[i]->second.pairs) {
        const Named<double>* b_values = b_all.find(metric);
        if (!b_values) continue;
        const auto row = paired_row(label, metric, pair_values(a_values), pair_values(*b_values));
        if (!row) continue;
        p.record[label][metric] = row->record;
        if (shown_paired(metric)) p.md += row->md;
      }
    }
  return p;
}

// Each point against the first, per algorithm, on the replicates both ran: the replicates of
// every point share their seeds (common random numbers), so the runs pair by replicate. Run
// metrics only: an axis that moves the vessel moves the sections too. The summary shows them
// for sweeps of at most 8 points.
Part<Named<Named<Named<PairedRowRecord>>>> paired_points(
    const Named<AlgorithmSummaryRecord>& algorithms, const Pool& pool) {
  Part<Named<Named<Named<PairedRowRecord>>>> p;
  std::vector<std::string> points;
  for (const auto& r : pool.runs) {
    const std::string pid = fmt::format("p{:04}", r.job->point);
    if (std::find(points.begin(), points.end(), pid) == points.end()) points.push_back(pid);
  }
  if (points.size() < 2) return p;
  const bool show = points.size() <= 8;
  if (show)
    p.md = std::string(
               "\n## Paired comparisons of the points\n\nEach point against the first on the "
               "same replicates (their seeds are shared): as above, per algorithm (metrics.json "
               "`paired_points`; the points' parameters: `points`).\n\n") +
           kPairedHead;
  for (const auto& [algo, a] : algorithms) {
    for (std::size_t k = 1; k < points.size(); ++k) {
      const std::string label = algo + ": " + points[k] + " vs " + points[0];
      for (const auto& [metric, values] : a.pairs) {
        const auto row = paired_row(label, metric, pair_values(values, points[0]),
                                    pair_values(values, points[k]));
        if (!row || metric == "p_m_per_m_sections") continue;
        p.record[algo][points[k] + " vs " + points[0]][metric] = row->record;
        if (show && shown_paired(metric)) p.md += row->md;
      }
    }
  }
  return p;
}

// One algorithm: pooled Table 1, the pooled regression, run metrics and --regress fits.
Part<AlgorithmSummaryRecord> merge_algorithm(const Pool& pool, const std::string& algo,
                                             const MergeOptions& o, const Covariates& covariates,
                                             const std::vector<RunRegression>& regressions,
                                             std::vector<std::string>* warnings) {
  const std::vector<const PooledSection*> rows = pool.sections_of(algo);
  Part<AlgorithmSummaryRecord> p;
  p.md = fmt::format("\n## {}\n\n", algo);
  auto errors = pooled_section_errors(pool, rows);
  p.record.sections = errors.record;
  p.md += errors.md;
  auto fit = pooled_regression(pool, rows, o.response, covariates, algo, warnings);
  p.md += fit.md;
  p.record.regression = fit.record;
  for (const auto& rm : run_metrics()) {
    std::vector<double> v;
    for (const auto& r : pool.runs) v.push_back(run_metric_value(r.metrics, algo, rm));
    p.record.runs[rm.name] = stat_record(stat_of(v));
  }
  p.record.pairs = per_pair_values(pool, algo, rows);
  if (!o.run_regressions.empty())
    p.record.run_regressions = run_regressions(regressions, pool.runs, algo, &p.md, warnings);
  return p;
}

// runs.csv: every run metric of every run and algorithm.
std::string runs_csv(const SweepManifest& m, const Pool& pool) {
  std::vector<std::string> header = {"job", "point", "replicate", "seed"};
  for (const auto& a : m.axes) header.push_back(a.name);
  header.push_back("algorithm");
  for (const auto& rm : run_metrics()) header.push_back(rm.name);
  std::string csv = csv_row(header);
  for (const auto& r : pool.runs)
    for (const auto& algo : pool.algorithms) {
      std::vector<std::string> row = {r.job->id, std::to_string(r.job->point),
                                      std::to_string(r.job->replicate),
                                      std::to_string(r.job->seed)};
      for (const auto& [name, value] : r.job->params) row.push_back(value);
      row.push_back(algo);
      for (const auto& rm : run_metrics())
        row.push_back(num(run_metric_value(r.metrics, algo, rm)));
      csv += csv_row(row);
    }
  return csv;
}

// The run metric the points table shows: the first one the runs have (sections, else APE...).
std::string main_run_metric(const Pool& pool) {
  std::string main_metric = run_metrics().front().name;
  for (auto it = run_metrics().rbegin(); it != run_metrics().rend(); ++it)
    for (const auto& r : pool.runs)
      for (const auto& algo : pool.algorithms)
        if (std::isfinite(run_metric_value(r.metrics, algo, *it))) main_metric = it->name;
  return main_metric;
}

// points.csv, metrics.json `points` and the summary's points table: each run metric per point,
// mean over replicates with its 95 % interval.
struct Points {
  std::string csv, md;
  Named<PointRecord> record;
};

Points per_point(const SweepManifest& m, const Pool& pool) {
  std::vector<std::string> header = {"point"};
  for (const auto& a : m.axes) header.push_back(a.name);
  header.push_back("algorithm");
  header.push_back("runs");
  for (const auto& rm : run_metrics())
    for (const char* suffix : {"_mean", "_sd", "_ci95_low", "_ci95_high"})
      header.push_back(std::string(rm.name) + suffix);
  Points out;
  out.csv = csv_row(header);
  std::map<std::size_t, std::vector<const RunData*>> by_point;  // ordered by point index
  for (const auto& r : pool.runs) by_point[r.job->point].push_back(&r);
  const std::string main_metric = main_run_metric(pool);
  out.md =
      fmt::format("\n## Points\n\n`{}` per point, mean over replicates [95% CI]:\n\n", main_metric);
  out.md += "| point |";
  for (const auto& a : m.axes) out.md += " " + a.name + " |";
  for (const auto& algo : pool.algorithms) out.md += " " + algo + " |";
  out.md += "\n|---|";
  for (std::size_t k = 0; k < m.axes.size() + pool.algorithms.size(); ++k) out.md += "---|";
  out.md += "\n";
  for (const auto& [point, point_runs] : by_point) {
    const std::string pid = fmt::format("p{:04}", point);
    const auto& params = point_runs.front()->job->params;
    PointRecord jp;
    for (const auto& [name, value] : params) jp.params[name] = yaml_text_to_json(value);
    jp.runs = point_runs.size();
    out.md += "| " + pid + " |";
    for (const auto& [name, value] : params) out.md += " " + value + " |";
    for (const auto& algo : pool.algorithms) {
      std::vector<std::string> row = {std::to_string(point)};
      for (const auto& [name, value] : params) row.push_back(value);
      row.push_back(algo);
      row.push_back(std::to_string(point_runs.size()));
      for (const auto& rm : run_metrics()) {
        std::vector<double> v;
        for (const RunData* r : point_runs) v.push_back(run_metric_value(r->metrics, algo, rm));
        const Stat s = stat_of(v);
        for (double x : {s.mean, s.sd, s.lo, s.hi}) row.push_back(num(x));
        jp.algorithms[algo][rm.name] = stat_record(s);
        if (rm.name == main_metric)
          out.md += s.n == 0   ? " — |"
                    : s.n == 1 ? fmt::format(" {:.4g} |", s.mean)
                               : fmt::format(" {:.4g} [{:.4g}, {:.4g}] |", s.mean, s.lo, s.hi);
      }
      out.csv += csv_row(row);
    }
    out.md += "\n";
    out.record[pid] = jp;
  }
  return out;
}

}  // namespace

MergeSummary merge_sweep(const SweepManifest& m, const MergeOptions& o) {
  MergeSummary out;
  out.dir = m.dir / "summary";
  const std::vector<RunRegression> regressions = parse_run_regressions(o.run_regressions, m);
  const SweepStatus status = sweep_status(m);
  require_done_jobs(m, status, o.allow_missing);
  const Pool pool = gather_runs(m, status);
  out.runs = pool.runs.size();
  out.sections = pool.sections.size();
  out.algorithms = pool.algorithms;
  const Covariates covariates = pooled_covariates(m, o, pool, &out.warnings);

  SweepSummaryRecord metrics;
  metrics.sweep = sweep_info_record(m, pool);
  std::string md = summary_head_md(m, pool);
  for (const auto& algo : pool.algorithms) {
    auto p = merge_algorithm(pool, algo, o, covariates, regressions, &out.warnings);
    md += p.md;
    metrics.algorithms[algo] = std::move(p.record);
  }
  auto paired = paired_algorithms(metrics.algorithms);
  metrics.paired = std::move(paired.record);
  md += paired.md;
  auto paired_pts = paired_points(metrics.algorithms, pool);
  metrics.paired_points = std::move(paired_pts.record);
  md += paired_pts.md;
  Points points = per_point(m, pool);
  metrics.points = std::move(points.record);
  md += points.md;
  // Plot warnings depend on the machine (is gnuplot installed?), not on the runs.
  metrics.warnings = out.warnings;

  // Write (aside, then rename into place), plots included.
  AtomicDirectory dir(out.dir, /*replace=*/true);
  write_file_atomic(dir.path() / "sections.csv", pooled_sections_csv(pool));
  write_file_atomic(dir.path() / "runs.csv", runs_csv(m, pool));
  write_file_atomic(dir.path() / "points.csv", points.csv);
  std::vector<std::string> plot_md;
  if (o.plots && !pool.algorithms.empty())
    plot_md = draw_sweep_plots(m, pool, o.gnuplot, dir.path() / "plots", &out);
  if (!plot_md.empty()) {
    md += "\n## Plots\n\n";
    for (const auto& p : plot_md) md += p + "\n\n";
  }
  if (!out.warnings.empty()) {
    md += "\n## Warnings\n\n";
    for (const auto& w : out.warnings) md += "- " + w + "\n";
  }
  write_file_atomic(dir.path() / "metrics.json", json_text(metrics));
  write_file_atomic(dir.path() / "summary.md", md);
  dir.commit();
  return out;
}

}  // namespace driftlab::study
