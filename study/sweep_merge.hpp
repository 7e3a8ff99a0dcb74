// `driftlab sweep merge`: pools the sections of every run of a sweep folder
// into one table (each run's swept parameters as extra covariate columns),
// fits river paper Eq. (13) by OLS on the pool, summarises every design point
// over its replicates (mean and 95% confidence interval) and plots the error
// against each swept parameter. Writes DIR/summary/:
//   sections.csv   every section of every run: job, point, replicate, seed,
//                  one column per axis, then the run's sections.csv columns
//   runs.csv       one row per run and algorithm: parameters and run metrics
//   points.csv     one row per point and algorithm: mean, SD, 95% CI per metric
//   metrics.json   the pool per algorithm (section errors, regression, run
//                  metrics over all runs) and every point; `driftlab regress` reads it
//   summary.md     the same for people, with the plots
//   plots/         AXIS__METRIC.png (gnuplot), with the .dat and .gp that made them
// Rows, columns and numbers depend only on the runs' outputs and the manifest
// order, never on which job finished first: the same sweep merges to the same bytes.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "record/run_record.hpp"
#include "study/sweep.hpp"

namespace driftlab::study {

struct MergeOptions {
  /// Regression covariates: columns of the pooled table (section covariates
  /// such as v, h, f, d, or axis names). Empty: the base scenario's
  /// eval.regression_covariates that the pool has, plus every numeric axis
  /// that varies.
  std::vector<std::string> covariates;
  /// The regression's response: a column of the pooled table.
  std::string response = "p_m_per_m";
  /// Run-level regressions, "METRIC~AXIS[+AXIS...][@AXIS=VALUE,...]": a run metric (a
  /// runs.csv column such as basin_north_rmse_m, or a key path under algorithms.ALGO of a run's
  /// metrics.json) on swept axes, by OLS over the runs of each algorithm (metrics.json
  /// run_regressions); after '@', only over the runs with those parameter values.
  std::vector<std::string> run_regressions;
  /// Merge the finished jobs even when some are not done.
  bool allow_missing = false;
  /// Make PNG plots with gnuplot (skipped, with a warning, when not installed).
  bool plots = true;
  /// gnuplot to use; empty: `gnuplot` on PATH.
  std::filesystem::path gnuplot;
};

struct MergeSummary {
  std::filesystem::path dir;  // DIR/summary
  std::size_t runs = 0;       // merged (done) runs
  std::size_t sections = 0;   // pooled rows
  std::vector<std::string> algorithms;
  std::vector<std::string> plots;     // PNG files written (relative to dir)
  std::vector<std::string> warnings;  // skipped plots, regressions not fitted, ...
  std::string brief() const;
};

/// Merges the sweep folder into DIR/summary (written aside, renamed into
/// place). Throws UserError, writing nothing, when jobs are not done (unless
/// allow_missing), a requested covariate or response is not a column, or a --regress names
/// no numeric axis.
MergeSummary merge_sweep(const SweepManifest& m, const MergeOptions& options = {});

/// The run metrics that points.csv and runs.csv summarise: name, and its value in one
/// algorithm's record of a run's metrics.json.
struct RunMetric {
  const char* name;
  const char* label;  // axis label of plots
  bool of_sections;   // a section statistic: missing for a run without sections
  double (*value)(const record::AlgorithmRecord&);
};
const std::vector<RunMetric>& run_metrics();
/// A run metric of one algorithm in a run's metrics.json; NaN (missing) when absent, and for
/// the section statistics of a run that has no section.
double run_metric_value(const record::RunRecord& metrics, const std::string& algorithm,
                        const RunMetric& metric);

}  // namespace driftlab::study
