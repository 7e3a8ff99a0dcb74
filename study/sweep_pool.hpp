// The pool a sweep's merge works on (study/sweep_merge.cpp) and plots (study/sweep_plots.cpp):
// every done run of the sweep folder with its typed metrics and its sections, and the
// statistics of a metric over runs.
#pragma once

#include <cstddef>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "study/run_regressions.hpp"
#include "study/sweep.hpp"

namespace driftlab::study {

// One row of a run's sections.csv in the pool.
struct PooledSection {
  std::size_t run;
  std::map<std::string, std::string> cells;
};

// Every done run in manifest order, its sections, and the pooled table's columns.
struct Pool {
  std::vector<RunData> runs;
  std::vector<PooledSection> sections;
  std::vector<std::string> algorithms;  // in order of first appearance
  std::vector<std::string> header;      // job, point, replicate, seed, axes, run columns

  // A cell of the pooled table: the job's own columns, its parameters, then the run's cells.
  std::string value_of(const PooledSection& s, const std::string& column) const {
    const RunData& r = runs[s.run];
    if (column == "job") return r.job->id;
    if (column == "point") return std::to_string(r.job->point);
    if (column == "replicate") return std::to_string(r.job->replicate);
    if (column == "seed") return std::to_string(r.job->seed);
    for (const auto& [name, value] : r.job->params)
      if (name == column) return value;
    const auto it = s.cells.find(column);
    return it == s.cells.end() ? std::string() : it->second;
  }
  bool is_column(const std::string& c) const {
    return std::find(header.begin(), header.end(), c) != header.end();
  }
  std::string column_list() const {
    std::string s;
    for (std::size_t k = 4; k < header.size(); ++k) s += (s.empty() ? "" : ", ") + header[k];
    return s;
  }
  std::vector<const PooledSection*> sections_of(const std::string& algorithm) const {
    std::vector<const PooledSection*> rows;
    for (const auto& s : sections) {
      const auto it = s.cells.find("algorithm");
      if (it != s.cells.end() && it->second == algorithm) rows.push_back(&s);
    }
    return rows;
  }
};

/// Every done job's run (its metrics.json and sections.csv), in manifest order.
Pool gather_runs(const SweepManifest& m, const SweepStatus& status);

/// sections.csv of the pool: its header, then every pooled section.
std::string pooled_sections_csv(const Pool& pool);

/// A table's number, NaN where the cell is empty or not a finite number.
double cell_number(const std::string& s);

/// `v` as a table writes it: shortest round-trip text, empty where not finite.
std::string num(double v);

/// A metric over runs: its count, mean, sample SD and 95 % interval (NaN where undefined).
struct Stat {
  std::size_t n = 0;
  double mean = std::numeric_limits<double>::quiet_NaN(), sd = mean, lo = mean, hi = mean;
};
Stat stat_of(const std::vector<double>& values);

/// `s` with every character but letters, digits, '-', '_' and '.' made '_' (a file name).
std::string file_safe(const std::string& s);

}  // namespace driftlab::study
