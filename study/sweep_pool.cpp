#include "study/sweep_pool.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <tuple>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/file_io.hpp"
#include "core/yaml_io.hpp"
#include "eval/stats.hpp"
#include "gate/paired.hpp"

namespace driftlab::study {

namespace fs = std::filesystem;

namespace {

constexpr double kNoValue = std::numeric_limits<double>::quiet_NaN();

RunData read_run(const SweepManifest& m, const SweepJob& job) {
  RunData rd{&job, {}};
  const fs::path metrics_file = m.run_dir(job.id) / "metrics.json";
  std::error_code ec;
  if (fs::exists(metrics_file, ec)) rd.metrics = record::read_run_record(metrics_file);
  return rd;
}

}  // namespace

Pool gather_runs(const SweepManifest& m, const SweepStatus& status) {
  Pool pool;
  std::vector<std::string> run_columns;  // union of the runs' sections.csv columns
  for (const auto& st : status.jobs) {
    if (st.state != JobState::kDone) continue;
    const SweepJob& job = m.jobs[st.index];
    const fs::path sections_file = m.run_dir(job.id) / "sections.csv";
    std::error_code ec;
    if (fs::exists(sections_file, ec)) {
      const CsvTable t =
          read_csv_table(read_text_file(sections_file, "CSV file"), sections_file.string());
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
        PooledSection s{pool.runs.size(), {}};
        for (std::size_t k = 0; k < row.cells.size(); ++k) s.cells[t.header[k]] = row.cells[k];
        pool.sections.push_back(std::move(s));
      }
    }
    pool.runs.push_back(read_run(m, job));
  }
  // Algorithms, in order of first appearance (runs in manifest order, names sorted).
  auto add_algorithm = [&](const std::string& name) {
    if (std::find(pool.algorithms.begin(), pool.algorithms.end(), name) == pool.algorithms.end())
      pool.algorithms.push_back(name);
  };
  for (const auto& r : pool.runs)
    for (const auto& [name, _] : r.metrics.algorithms) add_algorithm(name);
  for (const auto& s : pool.sections) {
    const auto it = s.cells.find("algorithm");
    if (it != s.cells.end()) add_algorithm(it->second);
  }
  pool.header = {"job", "point", "replicate", "seed"};
  for (const auto& a : m.axes) pool.header.push_back(a.name);
  pool.header.insert(pool.header.end(), run_columns.begin(), run_columns.end());
  return pool;
}

std::string pooled_sections_csv(const Pool& pool) {
  std::string csv = csv_row(pool.header);
  for (const auto& s : pool.sections) {
    std::vector<std::string> row;
    for (const auto& h : pool.header) row.push_back(pool.value_of(s, h));
    csv += csv_row(row);
  }
  return csv;
}

double cell_number(const std::string& s) {
  double v = kNoValue;
  if (s.empty() || !yaml::parse_double(s, &v) || !std::isfinite(v)) return kNoValue;
  return v;
}

std::string num(double v) { return std::isfinite(v) ? yaml::format_double(v) : std::string(); }

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
    std::tie(s.lo, s.hi) = gate::confidence_interval_95(s.mean, s.sd, s.n);
  }
  return s;
}

std::string file_safe(const std::string& s) {
  std::string out;
  for (char c : s)
    out +=
        std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.' ? c : '_';
  return out;
}

}  // namespace driftlab::study
