#include "report/basin_paper_compare.hpp"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <map>

#include "core/error.hpp"

namespace driftlab::report {
namespace {

// One cell of the paper's tables: RMSE (std).
struct Cell {
  double rmse, sd;
};
// A row: N, E [cm], u, v [cm/s], heading [deg].
using Row = std::array<Cell, 5>;

struct Experiment {
  const char* conditions;  // Table 1
  Row kf, pf;              // Tables 2 and 3
};

constexpr std::array<Experiment, 7> kBasinPaper{{
    {"calm",
     {{{1.097, 1.213}, {1.608, 1.408}, {0.078, 0.103}, {0.011, 0.014}, {1.387, 1.643}}},
     {{{1.054, 1.125}, {1.630, 1.441}, {0.072, 0.087}, {0.013, 0.017}, {1.400, 1.784}}}},
    {"40°, 5 mm, 210 mm",
     {{{2.232, 2.411}, {2.302, 2.193}, {0.155, 0.187}, {0.044, 0.046}, {1.370, 1.611}}},
     {{{2.873, 3.022}, {2.881, 2.993}, {0.154, 0.185}, {0.043, 0.046}, {1.399, 1.635}}}},
    {"40°, 7.5 mm, 132 mm",
     {{{4.087, 3.671}, {4.051, 3.321}, {0.269, 0.325}, {0.074, 0.073}, {1.485, 2.342}}},
     {{{4.189, 3.774}, {4.155, 3.391}, {0.273, 0.333}, {0.076, 0.074}, {1.447, 2.039}}}},
    {"40°, 11 mm, 59 mm",
     {{{6.043, 5.015}, {5.116, 4.914}, {0.284, 0.333}, {0.058, 0.067}, {2.170, 3.041}}},
     {{{6.265, 5.180}, {5.126, 4.918}, {0.255, 0.281}, {0.066, 0.074}, {2.277, 3.248}}}},
    {"0°, 5 mm, 210 mm",
     {{{0.761, 1.065}, {3.408, 3.870}, {0.147, 0.148}, {0.021, 0.025}, {1.042, 1.318}}},
     {{{0.801, 1.121}, {3.393, 3.847}, {0.139, 0.142}, {0.022, 0.025}, {1.013, 1.207}}}},
    {"0°, 7.5 mm, 132 mm",
     {{{0.296, 0.293}, {3.934, 4.055}, {0.110, 0.139}, {0.036, 0.042}, {1.551, 1.822}}},
     {{{0.304, 0.302}, {3.757, 3.834}, {0.117, 0.133}, {0.038, 0.045}, {1.580, 1.801}}}},
    {"0°, 11 mm, 59 mm",
     {{{0.320, 0.324}, {4.340, 4.843}, {0.088, 0.091}, {0.044, 0.045}, {1.531, 1.833}}},
     {{{0.298, 0.329}, {4.409, 4.945}, {0.093, 0.100}, {0.045, 0.046}, {1.582, 1.921}}}},
}};

using eval::BasinRow;
using eval::BasinRows;
using record::RunRecord;

constexpr std::array<BasinRow BasinRows::*, 5> kQuantities{
    &BasinRows::north_m, &BasinRows::east_m, &BasinRows::surge_m_s, &BasinRows::sway_m_s,
    &BasinRows::heading_deg};
constexpr std::array<double, 5> kToPaperUnits{100, 100, 100, 100, 1};  // cm, cm/s, deg

// A run's row of the basin table, in the paper's units.
Row twin_row(const BasinRows& t) {
  Row r{};
  for (std::size_t q = 0; q < 5; ++q)
    r[q] = {(t.*kQuantities[q]).rmse * kToPaperUnits[q], (t.*kQuantities[q]).sd * kToPaperUnits[q]};
  return r;
}

// The run's algorithm of a filter: the one whose name ends in `suffix` (pnp_ned_kf).
std::string algorithm_ending(const RunRecord& run, const std::string& suffix) {
  std::string found;
  for (const auto& [name, value] : run.algorithms)
    if (name.size() >= suffix.size() &&
        name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0 &&
        (found.empty() || name.rfind("pnp", 0) == 0))
      found = name;
  return found;
}

std::string cells(const Row& r) {
  std::string s;
  for (const Cell& c : r)
    s += std::isfinite(c.rmse) ? fmt::format(" {:.3f} ({:.3f}) |", c.rmse, c.sd) : " — |";
  return s;
}

struct Source {
  std::string label;
  std::map<int, Row> rows;  // by experiment
};

// The experiment with the largest RMSE of quantity q, and whether calm water is the smallest.
std::string hardest(const Source& s, std::size_t q) {
  int worst = 0, best = 0;
  for (const auto& [exp, r] : s.rows) {
    if (!std::isfinite(r[q].rmse)) continue;
    if (!worst || r[q].rmse > s.rows.at(worst)[q].rmse) worst = exp;
    if (!best || r[q].rmse < s.rows.at(best)[q].rmse) best = exp;
  }
  return worst ? fmt::format("largest in {}, smallest in {}", worst, best) : "—";
}

std::string table(const char* title, const std::string& suffix, const std::vector<RunRecord>& runs,
                  const std::vector<int>& exps, bool kf) {
  Source paper{"paper", {}}, exact{"twin, exact truth", {}}, overhead{"twin, overhead camera", {}};
  std::string algo;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const int e = exps[i];
    paper.rows[e] = kf ? kBasinPaper[static_cast<std::size_t>(e - 1)].kf
                       : kBasinPaper[static_cast<std::size_t>(e - 1)].pf;
    algo = algorithm_ending(runs[i], suffix);
    if (algo.empty()) continue;
    const eval::EvaluationRecord& ev = runs[i].algorithms.at(algo).evaluation;
    exact.rows[e] = twin_row(ev.basin);
    if (ev.basin_overhead) overhead.rows[e] = twin_row(ev.basin_overhead->rows);
  }
  std::string out = fmt::format("## {} ({})\n\n", title, algo.empty() ? "not in the runs" : algo);
  out +=
      "| Exp. | waves (γ, ζa, λ as Table 1 prints it) | against | N [cm] | E [cm] | u [cm/s] | v "
      "[cm/s] | ψ [°] |\n";
  out += "|---|---|---|---|---|---|---|---|\n";
  for (const int e : exps)
    for (const Source* s : {&paper, &exact, &overhead}) {
      const auto it = s->rows.find(e);
      if (it == s->rows.end()) continue;
      out += fmt::format("| {} | {} | {} |{}\n", e,
                         kBasinPaper[static_cast<std::size_t>(e - 1)].conditions, s->label,
                         cells(it->second));
    }
  out += "\nWhich experiment is hardest, by RMSE:\n\n| against | N | E | ψ |\n|---|---|---|---|\n";
  for (const Source* s : {&paper, &exact, &overhead})
    if (!s->rows.empty())
      out += fmt::format("| {} | {} | {} | {} |\n", s->label, hardest(*s, 0), hardest(*s, 1),
                         hardest(*s, 4));
  return out + "\n";
}

}  // namespace

std::optional<int> basin_paper_experiment_of(const std::string& name) {
  const std::string prefix = "basin_exp";
  if (name.size() != prefix.size() + 1 || name.rfind(prefix, 0) != 0) return std::nullopt;
  const int e = name.back() - '0';
  return e >= 1 && e <= 7 ? std::optional<int>(e) : std::nullopt;
}

std::string basin_paper_side_by_side(const std::vector<RunRecord>& runs) {
  std::vector<int> exps;
  for (const RunRecord& run : runs) {
    const std::string name = run.scenario.value_or("");
    const auto e = basin_paper_experiment_of(name);
    if (!e)
      throw UserError(fmt::format(
          "driftlab paper: scenario '{}' is not a twin of the basin paper (basin_exp1 ... "
          "basin_exp7); give basin runs only",
          name));
    if (algorithm_ending(run, "ned_kf").empty() && algorithm_ending(run, "ned_pf").empty())
      throw UserError(fmt::format(
          "driftlab paper: the run of '{}' has neither filter of the paper (an algorithm "
          "ending in ned_kf or ned_pf; pipeline.fusion)",
          name));
    exps.push_back(*e);
  }
  std::string out =
      "# Basin paper (Kučić and Valčić 2020, Tables 2-3) and the twin runs side by side\n\n"
      "RMSE (std) of each filter's errors. The paper measured against its overhead camera, "
      "which tracked a red and a green marker on the model. The twin is measured against the "
      "exact truth and against that camera, simulated (`sensors.overhead`). The waves are "
      "Table 1's as it prints them; the shipped scenarios draw its wavelengths as centimetres "
      "(scenarios/basin_exp4.yaml says why).\n\n";
  out += table("Table 2. Kalman filter", "ned_kf", runs, exps, true);
  out += table("Table 3. Particle filter", "ned_pf", runs, exps, false);
  return out;
}

}  // namespace driftlab::report
