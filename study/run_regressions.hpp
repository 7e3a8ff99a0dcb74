// Regressions over the runs of a sweep (`sweep merge --regress METRIC~AXIS[+AXIS...]`): a run
// metric of each algorithm on swept axes, by OLS (river paper Eq. (13) in form), and the OLS
// block that these and the pooled section regression write into metrics.json and summary.md.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "eval/regression.hpp"
#include "study/sweep.hpp"

namespace driftlab::study {

/// One merged run.
struct RunData {
  const SweepJob* job;
  nlohmann::json metrics;
};

/// One --regress: a run metric (its runs.csv name, or a key path under algorithms.ALGO) on
/// swept axes.
struct RunRegression {
  std::string text, metric;
  std::vector<std::string> axes;
};

/// Checks each METRIC~AXIS[+AXIS...] against the sweep's numeric axes.
std::vector<RunRegression> parse_run_regressions(const std::vector<std::string>& specs,
                                                 const SweepManifest& m);

/// Fits each --regress over the runs of `algorithm` into j and md; a fit that cannot be made
/// is recorded as skipped, with a warning.
void run_regressions(const std::vector<RunRegression>& specs, const std::vector<RunData>& runs,
                     const std::string& algorithm, nlohmann::ordered_json* j, std::string* md,
                     std::vector<std::string>* warnings);

/// An OLS fit into metrics.json (n, R^2, F, each coefficient) and summary.md (a table and
/// the fit's paragraph).
void append_ols(const eval::OlsResult& r, nlohmann::ordered_json* j, std::string* md);

/// A number at a dotted key path of a JSON document, NaN when absent or not a number.
double json_number(const nlohmann::json& j, const std::string& dotted);

}  // namespace driftlab::study
