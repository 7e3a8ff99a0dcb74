// The files of a sweep folder as typed records (core/record_json.hpp): sweep.json, a line of
// manifest.jsonl, a finished job's job.json, a failed job's failed/ID.json, slurm/slurm.json
// and the merge's summary/metrics.json. Each is written and read through its visit() list;
// docs/metrics-reference.md documents them from the same lists.
#pragma once

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/file_io.hpp"
#include "core/record_json.hpp"
#include "study/sweep_design.hpp"

namespace driftlab::study {

using record_json::Named;

// ---------------------------------------------------------------------------
// sweep.json: what was planned.

struct SweepAxisRecord {
  std::string key;   // scenario key path
  std::string name;  // column name in merged tables
  AxisSpec spec = AxisSpec::kValues;
  bool numeric = false;
  std::optional<std::array<double, 2>> interval;
  std::optional<std::vector<nlohmann::json>> values;

  template <class A>
  void visit(A& a) {
    a("key", key, "scenario key path the axis sets");
    a("name", name, "its column in the merged tables");
    a("spec", spec, "how the sweep file lists its values");
    a("numeric", numeric, "every value is a number");
    a("interval", interval, "[start, stop] of a continuous axis (random design)");
    a("values", values, "every value, in order (a listed axis)");
  }
};

struct SweepInfoRecord {
  int format = 1;
  std::string name, description;
  std::string sweep_file, base, base_dir;
  std::string scenario = "scenario.yaml";
  SweepDesign design = SweepDesign::kGrid;
  std::optional<std::size_t> samples;
  std::size_t replicates = 1;
  std::uint64_t seed = 0;
  std::size_t points = 0, jobs = 0;
  std::map<std::string, nlohmann::json> set;
  std::vector<SweepAxisRecord> axes;
  std::string driftlab_version;

  template <class A>
  void visit(A& a) {
    a("format", format, "version of this file's layout");
    a("name", name, "the sweep's name");
    a("description", description, "the sweep's description");
    a("sweep_file", sweep_file, "the sweep file, absolute");
    a("base", base, "the base scenario, absolute");
    a("base_dir", base_dir, "where relative files of the overrides resolve");
    a("scenario", scenario, "the resolved base scenario in the folder");
    a("design", design, "how the axes combine");
    a("samples", samples, "points drawn (random design)");
    a("replicates", replicates, "runs per point, each with its own seed");
    a("seed", seed, "the sweep seed");
    a("points", points, "points of the design");
    a("jobs", jobs, "points x replicates");
    a("set", set, "keys the sweep sets for every job");
    a("axes", axes, "the swept axes, in order");
    a("driftlab_version", driftlab_version, "the version that planned it");
  }
};

// ---------------------------------------------------------------------------
// manifest.jsonl, job.json, failed/ID.json, slurm/slurm.json.

struct ManifestJobRecord {
  std::string id;
  std::size_t index = 0, point = 0, replicate = 0;
  std::uint64_t seed = 0;
  Named<nlohmann::json> params;
  std::vector<std::string> overrides;
  std::string hash;

  template <class A>
  void visit(A& a) {
    a("id", id, "p<point>-r<replicate>");
    a("index", index, "line number from 0");
    a("point", point, "point of the design");
    a("replicate", replicate, "replicate of the point");
    a("seed", seed, "the run's seed");
    a("params", params, "each axis's value, by column name");
    a("overrides", overrides, "KEY=VALUE overrides of scenario.yaml: one per axis, then seed");
    a("hash", hash, "FNV-1a 64 of the job's resolved scenario");
  }
};

/// runs/ID/job.json, written last: the run is complete.
struct JobMarkerRecord {
  std::string id, status = "done", hash;
  std::uint64_t seed = 0;
  Named<nlohmann::json> params;
  std::string host;
  double wall_s = 0;
  std::string driftlab_version;

  template <class A>
  void visit(A& a) {
    a("id", id, "the job");
    a("status", status, "done");
    a("hash", hash, "the manifest's parameter hash it ran with");
    a("seed", seed, "the run's seed");
    a("params", params, "each axis's value, by column name");
    a("host", host, "the machine that ran it");
    a("wall_s", wall_s, "wall time of the job [s]");
    a("driftlab_version", driftlab_version, "the version that ran it");
  }
};

/// failed/ID.json: a job that ended without its marker.
struct FailureRecord {
  std::string id, status = "failed", error;
  std::optional<std::string> log_tail;
  std::string hash, host, log;

  template <class A>
  void visit(A& a) {
    a("id", id, "the job");
    a("status", status, "failed, timeout or killed");
    a("error", error, "what went wrong");
    a("log_tail", log_tail, "the end of its output");
    a("hash", hash, "the manifest's parameter hash");
    a("host", host, "the machine that ran it");
    a("log", log, "its log, relative to the sweep folder");
  }
};

/// slurm/slurm.json: the array script of `driftlab sweep slurm-script`.
struct SlurmRecord {
  std::string script;
  std::size_t shards = 0, max_parallel = 0, cpus_per_task = 1;
  std::string partition, time;

  template <class A>
  void visit(A& a) {
    a("script", script, "the sbatch script");
    a("shards", shards, "array tasks");
    a("max_parallel", max_parallel, "array tasks at once; 0: no limit");
    a("cpus_per_task", cpus_per_task, "CPUs (and jobs at once) per task");
    a("partition", partition, "the partition; empty: the cluster's default");
    a("time", time, "time limit per task; empty: the default");
  }
};

// ---------------------------------------------------------------------------
// summary/metrics.json: the merge.

/// Mean over runs with its 95 % interval (null where there are too few runs).
struct RunStatRecord {
  std::size_t n = 0;
  double mean = 0, sd = 0, ci95_low = 0, ci95_high = 0;

  template <class A>
  void visit(A& a) {
    a("n", n, "runs with a value");
    a("mean", mean, "mean");
    a("sd", sd, "sample standard deviation");
    a("ci95_low", ci95_low, "95 % interval of the mean, low end");
    a("ci95_high", ci95_high, "95 % interval of the mean, high end");
  }
};

/// One section error over the pooled sections.
struct SectionErrorStatsRecord {
  std::size_t n = 0;
  double min = 0, mean = 0, median = 0, sd = 0, rmse = 0, max = 0;

  template <class A>
  void visit(A& a) {
    a("n", n, "sections with a value");
    a("min", min, "minimum");
    a("mean", mean, "mean");
    a("median", median, "median");
    a("sd", sd, "sample standard deviation");
    a("rmse", rmse, "root mean square");
    a("max", max, "maximum");
  }
};

/// River paper Table 1 over the pooled sections; each field's doc is its column label.
struct PooledSectionsRecord {
  std::size_t count = 0;
  SectionErrorStatsRecord p_m_per_m, x_m_per_m, y_m_per_m, z_m_per_m, roll_deg_per_m,
      pitch_deg_per_m, yaw_deg_per_m;

  template <class A>
  void visit(A& a) {
    a("count", count, "pooled sections");
    a("p_m_per_m", p_m_per_m, "ε'_p [m/m]");
    a("x_m_per_m", x_m_per_m, "ε'_x [m/m]");
    a("y_m_per_m", y_m_per_m, "ε'_y [m/m]");
    a("z_m_per_m", z_m_per_m, "ε'_z [m/m]");
    a("roll_deg_per_m", roll_deg_per_m, "ε'_roll [deg/m]");
    a("pitch_deg_per_m", pitch_deg_per_m, "ε'_pitch [deg/m]");
    a("yaw_deg_per_m", yaw_deg_per_m, "ε'_yaw [deg/m]");
  }
};

struct CoefficientRecord {
  double estimate = 0, std_error = 0, t = 0, p = 0, vif = 0;
  bool significant = false;

  template <class A>
  void visit(A& a) {
    a("estimate", estimate, "the coefficient");
    a("std_error", std_error, "its standard error");
    a("t", t, "t statistic");
    a("p", p, "two-sided p-value");
    a("vif", vif, "variance inflation factor");
    a("significant", significant, "p < 0.05");
  }
};

/// An OLS fit, or why none was made (then only `skipped` is written).
struct OlsFitRecord {
  std::size_t n = 0;
  double r2 = 0, adj_r2 = 0, f = 0, f_p = 0, sigma = 0;
  Named<CoefficientRecord> coefficients;
  std::vector<std::string> warnings;
  std::optional<std::string> skipped;

  template <class A>
  void visit(A& a) {
    if (!record_json::is_writer<A> || !skipped) {
      a("n", n, "observations fitted");
      a("r2", r2, "R^2");
      a("adj_r2", adj_r2, "adjusted R^2");
      a("f", f, "F statistic");
      a("f_p", f_p, "p-value of F");
      a("sigma", sigma, "residual standard error");
      a("coefficients", coefficients, "each term, Intercept first");
      a("warnings", warnings, "what the fit found doubtful");
    }
    a("skipped", skipped, "why no fit was made");
  }
};

/// The river paper's Eq. (13) over the pooled sections.
struct PooledRegressionRecord {
  std::string response;
  std::vector<std::string> covariates;
  std::size_t dropped_sections = 0;
  OlsFitRecord fit;

  template <class A>
  void visit(A& a) {
    a("response", response, "the section error regressed");
    a("covariates", covariates, "the covariates asked for");
    a("dropped_sections", dropped_sections, "sections lacking a value");
    fit.visit(a);
  }
};

struct AlgorithmSummaryRecord {
  PooledSectionsRecord sections;
  PooledRegressionRecord regression;
  Named<RunStatRecord> runs;
  /// Per paired metric, each pair's value: runs by job id, sections by JOB/INDEX.
  Named<Named<double>> pairs;
  std::optional<Named<OlsFitRecord>> run_regressions;

  template <class A>
  void visit(A& a) {
    a("sections", sections, "river paper Table 1 over the pooled sections");
    a("regression", regression, "river paper Eq. (13) over the pooled sections");
    a("runs", runs, "each run metric over the runs");
    a("pairs", pairs, "each paired metric's value per job (sections: per JOB/INDEX)");
    a("run_regressions", run_regressions, "each --regress, by its text");
  }
};

/// B against A over the pairs both have.
struct PairedRowRecord {
  std::size_t pairs = 0;
  double mean_a = 0, mean_b = 0, diff = 0;
  std::array<double, 2> diff_ci95{};
  double rel = 0;
  std::array<double, 2> rel_ci95{};
  double p_signed_rank = 0;

  template <class A>
  void visit(A& a) {
    a("pairs", pairs, "pairs both have");
    a("mean_a", mean_a, "A's mean");
    a("mean_b", mean_b, "B's mean");
    a("diff", diff, "mean of B - A");
    a("diff_ci95", diff_ci95, "its 95 % interval");
    a("rel", rel, "B - A relative to A's mean");
    a("rel_ci95", rel_ci95, "its 95 % interval");
    a("p_signed_rank", p_signed_rank, "two-sided Wilcoxon signed-rank p-value");
  }
};

struct PointRecord {
  Named<nlohmann::json> params;
  std::size_t runs = 0;
  Named<Named<RunStatRecord>> algorithms;

  template <class A>
  void visit(A& a) {
    a("params", params, "each axis's value, by column name");
    a("runs", runs, "runs of the point");
    if (!record_json::is_writer<A> || !algorithms.empty())
      a("algorithms", algorithms, "each run metric of each algorithm over the point's runs");
  }
};

struct SweepSummaryInfoRecord {
  struct Axis {
    std::string key, name;
    template <class A>
    void visit(A& a) {
      a("key", key, "scenario key path");
      a("name", name, "column name");
    }
  };
  std::string name;
  SweepDesign design = SweepDesign::kGrid;
  std::size_t jobs = 0, merged_runs = 0, points = 0, replicates = 1, sections = 0;
  std::vector<Axis> axes;

  template <class A>
  void visit(A& a) {
    a("name", name, "the sweep's name");
    a("design", design, "how the axes combine");
    a("jobs", jobs, "jobs of the plan");
    a("merged_runs", merged_runs, "finished runs merged");
    a("points", points, "points of the design");
    a("replicates", replicates, "runs per point");
    a("sections", sections, "sections pooled");
    a("axes", axes, "the swept axes");
  }
};

/// summary/metrics.json of `driftlab sweep merge`.
struct SweepSummaryRecord {
  SweepSummaryInfoRecord sweep;
  Named<AlgorithmSummaryRecord> algorithms;
  /// "B vs A" -> metric -> row.
  Named<Named<PairedRowRecord>> paired;
  /// algorithm -> "pK vs p0" -> metric -> row.
  Named<Named<Named<PairedRowRecord>>> paired_points;
  /// pNNNN -> the point.
  Named<PointRecord> points;
  std::vector<std::string> warnings;

  template <class A>
  void visit(A& a) {
    a("sweep", sweep, "the sweep merged");
    a("algorithms", algorithms, "the pool per algorithm");
    a("paired", paired, "every two algorithms on the same jobs, per metric");
    a("paired_points", paired_points, "each point against the first, per algorithm and metric");
    a("points", points, "each point's parameters and run metrics");
    a("warnings", warnings, "what the merge could not do");
  }
};

/// The reference of every file above (docs/metrics-reference.md), one section each.
std::string sweep_files_reference_markdown();

/// A record as the sweep folder's files hold it: keys in visit() order, indented by 2.
template <class T>
std::string json_text(const T& record) {
  return record_json::to_ordered_json(record).dump(2) + "\n";
}

/// The record in `file`, read strictly (`unknown`: or leaving keys of a newer writer aside);
/// `what` names the file in errors ("failure record").
template <class T>
T read_json_record(const std::filesystem::path& file, const std::string& what,
                   record_json::UnknownKeys unknown = record_json::UnknownKeys::kReject) {
  const auto j = record_json::parse_json(read_text_file(file, what), file.string(), "a " + what);
  return record_json::from_json<T>(j, file.string(), unknown);
}

}  // namespace driftlab::study
