#include "study/sweep_plots.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/atomic_file.hpp"
#include "report/gnuplot.hpp"
#include "study/sweep_pool.hpp"

namespace driftlab::study {

namespace fs = std::filesystem;

namespace {

// An axis's values in order: numeric ascending, else first appearance.
std::vector<std::string> axis_values(const SweepAxisRecord& a, const Pool& pool) {
  std::vector<std::string> values;
  for (const auto& r : pool.runs)
    for (const auto& [name, value] : r.job->params)
      if (name == a.name && std::find(values.begin(), values.end(), value) == values.end())
        values.push_back(value);
  if (a.numeric)
    std::stable_sort(values.begin(), values.end(), [](const std::string& x, const std::string& y) {
      return cell_number(x) < cell_number(y);
    });
  return values;
}

// One plot's data: per algorithm a block of (x, mean, ci95 low, high, runs, label) over the
// axis values (other axes and replicates pooled); the algorithms that have a block.
std::pair<std::string, std::vector<std::pair<std::size_t, std::string>>> plot_data(
    const SweepAxisRecord& a, const std::vector<std::string>& values, const RunMetric& rm,
    const Pool& pool) {
  std::string dat = fmt::format(
      "# {} vs {}: x, mean, ci95_low, ci95_high, runs, label; one "
      "block per algorithm\n",
      rm.name, a.name);
  std::vector<std::pair<std::size_t, std::string>> series;  // block index, algorithm
  std::size_t block = 0;
  for (const auto& algo : pool.algorithms) {
    std::string rows;
    for (std::size_t k = 0; k < values.size(); ++k) {
      std::vector<double> v;
      for (const auto& r : pool.runs)
        for (const auto& [name, value] : r.job->params)
          if (name == a.name && value == values[k])
            v.push_back(run_metric_value(r.metrics, algo, rm));
      const Stat s = stat_of(v);
      if (s.n == 0) continue;
      std::string label = values[k];
      std::replace(label.begin(), label.end(), '"', '\'');
      rows += fmt::format("{} {} {} {} {} \"{}\"\n",
                          a.numeric ? num(cell_number(values[k])) : std::to_string(k), num(s.mean),
                          num(s.n >= 2 ? s.lo : s.mean), num(s.n >= 2 ? s.hi : s.mean), s.n, label);
    }
    if (rows.empty()) continue;
    dat += fmt::format("# {}\n{}\n\n", algo, rows);
    series.emplace_back(block++, algo);
  }
  return {dat, series};
}

// The gnuplot script of one plot: series side by side (dodged by a little of the x range) so
// that their bars do not hide one another.
std::string plot_script(const SweepAxisRecord& a, const std::vector<std::string>& values,
                        const RunMetric& rm, const std::string& stem, const std::string& terminal,
                        const std::vector<std::pair<std::size_t, std::string>>& series) {
  bool log_x = a.spec == AxisSpec::kLogspace;
  for (const auto& v : values) log_x = log_x && a.numeric && cell_number(v) > 0;
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
  double lo = 0, hi = 1;
  if (a.numeric && !values.empty()) {
    lo = cell_number(values.front());
    hi = cell_number(values.back());
  } else {
    hi = static_cast<double>(values.size());
  }
  const double span = hi > lo ? hi - lo : 1.0;
  for (std::size_t k = 0; k < series.size(); ++k) {
    const double shift = (static_cast<double>(k) - (static_cast<double>(series.size()) - 1) / 2);
    const std::string x = !a.numeric ? fmt::format("($1{:+g})", 0.08 * shift)
                          : log_x    ? fmt::format("($1*{:g})", std::pow(hi / lo, 0.012 * shift))
                                     : fmt::format("($1{:+g})", 0.012 * span * shift);
    gp += fmt::format("{}'{}.dat' index {} using {}:2:3:4{} with yerrorlines title '{}'",
                      k ? ", \\\n     " : "", stem, series[k].first, x, a.numeric ? "" : ":xtic(6)",
                      series[k].second);
  }
  return gp + "\n";
}

}  // namespace

std::vector<std::string> draw_sweep_plots(const SweepManifest& m, const Pool& pool,
                                          const fs::path& gnuplot_executable, const fs::path& plots,
                                          MergeSummary* out) {
  const report::GnuplotLookup lookup = report::find_gnuplot(gnuplot_executable);
  if (!lookup.gnuplot) {
    out->warnings.push_back(lookup.warning + ": plots skipped");
    return {};
  }
  const report::Gnuplot& gnuplot = *lookup.gnuplot;
  std::vector<std::string> plot_md;
  fs::create_directories(plots);
  for (const auto& a : m.axes) {
    const std::vector<std::string> values = axis_values(a, pool);
    for (const RunMetric& rm : run_metrics()) {
      const std::string stem = file_safe(a.name) + "__" + rm.name;
      const auto [dat, series] = plot_data(a, values, rm, pool);
      if (series.empty()) continue;  // a metric the runs do not have
      write_file_atomic(plots / (stem + ".dat"), dat);
      write_file_atomic(plots / (stem + ".gp"),
                        plot_script(a, values, rm, stem, gnuplot.terminal, series));
      const report::GnuplotRun run =
          report::run_gnuplot(gnuplot, plots, stem + ".gp", stem + ".log");
      std::error_code ec;
      if (run.ok && fs::exists(plots / (stem + ".png"), ec)) {
        out->plots.push_back("plots/" + stem + ".png");
        plot_md.push_back(fmt::format("![{} vs {}](plots/{}.png)", rm.name, a.name, stem));
      } else {
        out->warnings.push_back(
            run.ok ? fmt::format("gnuplot drew no image from plots/{}.gp", stem)
                   : fmt::format("gnuplot failed on plots/{}.gp ({}); see summary/plots/{}.log",
                                 stem, run.failure, stem));
      }
    }
  }
  return plot_md;
}

}  // namespace driftlab::study
