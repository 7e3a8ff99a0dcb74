// The CI regression gate (`driftlab regress`): compares chosen metrics.json
// values of a run or of a merged sweep with a committed baseline, each with an
// absolute / relative tolerance and a direction, and reports old, new, change
// and a verdict per metric (a table and JUnit XML).
//
// Baseline file (JSON; read with line numbers, so errors name the line):
//   {
//     "description": "what this gate protects",
//     "metrics": [
//       {"key": "algorithms.sparse.runs.ape_trans_rmse_m.mean", "baseline": 0.0123,
//        "direction": "lower", "abs_tol": 0.001, "rel_tol": 0.1}
//     ]
//   }
// key: a dotted key path into metrics.json, or a JSON pointer ("/a/b.c/0") for
// keys that hold dots. direction: lower (lower is better: an increase beyond the
// tolerance is a regression), higher, or both (any change beyond it is).
// The tolerance is max(abs_tol, rel_tol * |baseline|); both default to 0.
//
// Paired metrics (docs/sweeps.md, "Paired comparisons"): where the results hold a metric per job or
// per section of a job (a merged sweep's algorithms.NAME.pairs.METRIC, an object
// {"p0000-r00/3": value, ...}), the entry keeps every pair's value
// ("pairs": [{"id": ..., "value": ...}]) and the gate compares the new values with them pair by
// pair (gate/paired.hpp): a regression is a change in the bad direction that a one-sided Wilcoxon
// signed-rank test finds at level `alpha` AND that moves the mean by more than `min_effect` of the
// baseline's. A pair the new results lack is a failure (MISSING): a VO that loses sections must
// not pass by losing its worst ones.
#pragma once

#include <array>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/yaml_io.hpp"
#include "gate/paired.hpp"

namespace driftlab::gate {

enum class MetricDirection { kLower, kHigher, kBoth };
constexpr auto enum_table(MetricDirection) {
  return std::array{std::pair{MetricDirection::kLower, "lower"},
                    std::pair{MetricDirection::kHigher, "higher"},
                    std::pair{MetricDirection::kBoth, "both"}};
}

/// One job's (or section's) value of a paired metric.
struct PairValue {
  std::string id;  ///< "JOB" or "JOB/SECTION"
  double value = 0;

  template <class A>
  void visit(A& a) {
    a("id", id, "The pair's name: a sweep job (p0000-r00) or a job's section (p0000-r00/3)",
      yaml::non_empty() & yaml::required("the pair's name, e.g. p0000-r00/3"));
    a("value", value, "The baseline's value for it",
      yaml::required("a finite number") & yaml::expecting("a finite number"));
  }
};

/// One gated metric of a baseline file.
struct BaselineMetric {
  std::string key;
  std::optional<double> baseline;  // absent: not yet recorded (run with --update)
  MetricDirection direction = MetricDirection::kLower;
  double abs_tol = 0;
  double rel_tol = 0;
  std::vector<PairValue> pairs;  // empty: compared by tolerance
  double min_effect = 0.05;      // paired: the smallest relative change of the mean that counts
  double alpha = 0.01;           // paired: the signed-rank test's level
  std::string where;             // FILE:LINE:COL of the entry
  std::string key_where;         // FILE:LINE:COL of its key
  double tolerance() const;

  template <class A>
  void visit(A& a) {
    a.location(&where);
    a.location("key", &key_where);
    a("key", key,
      "A metrics.json key path (dotted, e.g. algorithms.sparse.ape.trans_m.rmse), or a JSON "
      "pointer (/a/b.c/0) for keys that hold dots",
      yaml::non_empty() & yaml::required("a metrics.json key path such as "
                                         "algorithms.sparse.ape.trans_m.rmse"));
    a("baseline", baseline,
      "The accepted value (null: not recorded yet; `driftlab regress --update` writes it)",
      yaml::expecting("a finite number"));
    a("direction", direction,
      "lower: lower is better (an increase beyond the tolerance is a regression); higher: "
      "higher is better; both: any change beyond the tolerance is one");
    a("abs_tol", abs_tol, "Absolute tolerance; the tolerance is max(abs_tol, rel_tol * |baseline|)",
      yaml::non_negative() & yaml::expecting("a number >= 0"));
    a("rel_tol", rel_tol, "Relative tolerance, a fraction of |baseline|",
      yaml::non_negative() & yaml::expecting("a number >= 0"));
    a("pairs", pairs,
      "Paired metrics: the baseline's value of every job or section; the gate then decides by "
      "a paired test instead of the tolerances (docs/sweeps.md: the CI regression gate)");
    a("min_effect", min_effect,
      "Paired metrics: the smallest change of the mean, a fraction of the baseline's, that can "
      "fail the gate",
      yaml::non_negative() & yaml::expecting("a number >= 0"));
    a("alpha", alpha, "Paired metrics: the level of the one-sided signed-rank test",
      yaml::in_range(0.0, 0.5));
  }
};

/// The mean of the pairs' values (0 for none).
double pairs_mean(const std::vector<PairValue>& pairs);

/// A baseline file, read by the strict reader like scenarios and sweeps.
struct Baseline {
  std::filesystem::path file;
  std::string description;
  std::vector<BaselineMetric> metrics;

  template <class A>
  void visit(A& a) {
    a("description", description, "What this gate protects, in words");
    a("metrics", metrics, "The gated metrics",
      yaml::required("a list of {\"key\": ..., \"baseline\": ..., \"direction\": ..., "
                     "\"abs_tol\": ..., \"rel_tol\": ...}"));
    a.require(!metrics.empty(), "metrics", "a list of at least one metric");
  }
};

/// Reads a baseline file. Throws UserError naming file, line, field, value and
/// what was expected (unknown keys, wrong types, negative tolerances, an empty
/// metrics list, duplicate keys).
Baseline load_baseline(const std::filesystem::path& file);
/// The reference of every baseline key (Markdown), generated from the reader's own field list:
/// `driftlab regress schema`, docs/baseline-reference.md.
std::string baseline_reference_markdown();

/// The baseline as JSON text (what --update writes).
std::string baseline_json(const Baseline& b);

enum class Verdict { kPass, kImproved, kRegressed, kMissing, kNoBaseline };
constexpr auto enum_table(Verdict) {
  return std::array{std::pair{Verdict::kPass, "pass"}, std::pair{Verdict::kImproved, "improved"},
                    std::pair{Verdict::kRegressed, "REGRESSED"},
                    std::pair{Verdict::kMissing, "MISSING"},
                    std::pair{Verdict::kNoBaseline, "NO BASELINE"}};
}

struct MetricCheck {
  BaselineMetric metric;
  std::optional<double> value;         // the new value (paired: the new mean over the pairs)
  std::optional<PairedChange> paired;  // paired metrics: the comparison
  std::vector<PairValue> new_pairs;    // paired metrics: the new value of every pair
  Verdict verdict = Verdict::kPass;
  std::string note;  // why MISSING
  bool failed() const {
    return verdict == Verdict::kRegressed || verdict == Verdict::kMissing ||
           verdict == Verdict::kNoBaseline;
  }
};

struct GateResult {
  std::filesystem::path baseline_file;
  std::filesystem::path results_file;  // the metrics.json compared
  std::vector<MetricCheck> checks;
  std::size_t failures() const;
  /// metric | baseline | new | change | tolerance | verdict, aligned.
  std::string table() const;
  /// "5 metrics: 3 pass, 1 improved, 1 REGRESSED".
  std::string brief() const;
  /// JUnit XML: one test case per metric, a <failure> for each failed one.
  std::string junit_xml() const;
};

/// The metrics.json that `results` stands for: the file itself, DIR/metrics.json
/// (a run), or DIR/summary/metrics.json (a merged sweep). Throws UserError
/// otherwise (a sweep folder not yet merged is named as such).
std::filesystem::path find_results_metrics(const std::filesystem::path& results);

/// The JSON of a metrics.json; UserError naming the file when it is not valid JSON.
nlohmann::json read_results_metrics(const std::filesystem::path& file);

/// The node at a dotted key path or JSON pointer; null with `why` when absent.
const nlohmann::json* metric_node(const nlohmann::json& doc, const std::string& key,
                                  std::string* why);

/// The pairs at a key that holds an object {id: number}, each finite value a pair (a merged
/// sweep's algorithms.NAME.pairs.METRIC); nullopt with `why` otherwise.
std::optional<std::vector<PairValue>> metric_pairs(const nlohmann::json& doc,
                                                   const std::string& key, std::string* why);

/// The value at a dotted key path or JSON pointer; nullopt with `why` when
/// absent, null or not a number.
std::optional<double> metric_value(const nlohmann::json& doc, const std::string& key,
                                   std::string* why);

GateResult check_baseline(const Baseline& baseline, const nlohmann::json& results,
                          const std::filesystem::path& results_file);

/// The baseline with only the metrics whose key, as written in the file, starts with one of
/// `prefixes` (`regress --only`: a gate of one VO's metrics, e.g. "algorithms.sparse."). Throws
/// UserError naming the file and the prefixes when no metric is left.
Baseline only_metrics(Baseline baseline, const std::vector<std::string>& prefixes);

/// How `regress init` sets the tolerances.
struct InitOptions {
  double rel_tol = 0.1;     ///< of each value
  std::string description;  ///< written into the baseline
};

/// The metrics a baseline of these results gates when none are named: per algorithm the APE
/// translation and rotation RMSE, the 3D track RMSE, the mean section error (when there are
/// sections) and the basin table's north, east and heading RMSE (when present); for a merged
/// sweep the pooled means of the APE RMSEs and of the mean section error. Only keys with a
/// finite number.
std::vector<std::string> default_gate_keys(const nlohmann::json& results);

/// A baseline of `keys` with the values of `results`, lower is better, rel_tol of each value
/// and, for a pooled sweep mean of n >= 2 runs, abs_tol = 2 sd / sqrt(n) (the mean's 95 %
/// half-width: a change within it is at the level of the replicate noise). UserError naming
/// every key the results lack, or when `keys` is empty.
Baseline baseline_from_results(const nlohmann::json& results, const std::vector<std::string>& keys,
                               const InitOptions& options);

/// The baseline with every value replaced by the new one. Throws UserError
/// naming the metrics the results lack (nothing is updated then).
Baseline updated_baseline(const Baseline& baseline, const GateResult& result);

}  // namespace driftlab::gate
