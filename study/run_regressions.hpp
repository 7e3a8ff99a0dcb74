// Regressions over the runs of a sweep (`sweep merge --regress
// METRIC~AXIS[+AXIS...][@AXIS=VALUE,...]`): a run metric of each algorithm on swept axes, over
// all runs or those with the given parameter values, by OLS (river paper Eq. (13) in form), and the
// OLS block that these and the pooled section regression write into metrics.json and summary.md.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "eval/regression.hpp"
#include "record/run_record.hpp"
#include "study/sweep.hpp"
#include "study/sweep_records.hpp"

namespace driftlab::study {

/// One merged run.
struct RunData {
  const SweepJob* job;
  record::RunRecord metrics;  ///< empty when the run wrote none
};

/// One --regress: a run metric (its runs.csv name, or a key path under algorithms.ALGO) on
/// swept axes, over the runs whose parameters meet every condition (AXIS=VALUE after '@').
struct RunRegression {
  std::string text, metric;
  std::vector<std::string> axes;
  std::vector<std::pair<std::string, std::string>> where;
};

/// Checks each METRIC~AXIS[+AXIS...][@AXIS=VALUE[,AXIS=VALUE...]] against the sweep: the
/// regressors must be numeric axes; a condition's axis must be an axis of the sweep and its
/// value one that some job has (numbers compare by value: -40 matches -40.0).
std::vector<RunRegression> parse_run_regressions(const std::vector<std::string>& specs,
                                                 const SweepManifest& m);

/// Fits each --regress over the runs of `algorithm`, by its text, adding each to md; a fit
/// that cannot be made is recorded as skipped, with a warning.
Named<OlsFitRecord> run_regressions(const std::vector<RunRegression>& specs,
                                    const std::vector<RunData>& runs, const std::string& algorithm,
                                    std::string* md, std::vector<std::string>* warnings);

/// An OLS fit as metrics.json holds it (n, R^2, F, each coefficient), adding its part of
/// summary.md (a table and the fit's paragraph) to md.
OlsFitRecord ols_record(const eval::OlsResult& r, std::string* md);

/// A number at a dotted key path of a JSON document, NaN when absent or not a number.
double json_number(const nlohmann::json& j, const std::string& dotted);

}  // namespace driftlab::study
