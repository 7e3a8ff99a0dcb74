#include "report/paper_compare.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string_view>
#include <vector>

#include "core/error.hpp"

namespace driftlab::report {
namespace {

constexpr double kNa = std::numeric_limits<double>::quiet_NaN();

// A distribution as the paper's tables give it: min, mean, median, SD, max.
struct Stats {
  double min, mean, median, sd, max;
};

struct Coefficient {
  double beta, t, p;
};

// Table 2: RMSE and maximum of the 3D and 2D position errors [m] and [% of
// the track], and the frames N.
struct TrackErrors {
  double rmse_3d, rmse_3d_pct, max_3d, max_3d_pct, rmse_2d, rmse_2d_pct, max_2d, max_2d_pct;
  double n, length_error_pct;
};

// One algorithm's columns of the river paper's Tables 1-4 (Kriechbaumer et
// al. 2015, Section 3), as printed there.
struct PaperColumn {
  const char* algorithm;
  Stats ep, x, y, z, roll, pitch, yaw;  // Table 1 (the paper's phi is pitch, rho roll: Fig. 7)
  int sections;
  TrackErrors discharge, total;             // Table 2
  std::array<Coefficient, 5> coefficients;  // Table 3: Intercept, v, h, f, d
  double f, f_p, r2;                        // Table 3
  Stats v, h, features, depth;              // Table 4
};

constexpr std::array<const char*, 5> kTerms{"Intercept", "v", "h", "f", "d"};

// The paper prints no maximum of the dense e'_p (Table 1) and no length
// error for the discharge track; those cells stay empty.
constexpr std::array<PaperColumn, 2> kPaper{{
    {"sparse",
     {0.004, 0.067, 0.048, 0.060, 0.345},
     {-0.197, 0.001, -0.003, 0.064, 0.229},
     {-0.180, -0.002, -0.005, 0.054, 0.209},
     {-0.117, 0.002, 0.002, 0.033, 0.263},
     {-3.95, 0.00, 0.03, 1.25, 3.13},
     {-4.16, -0.01, 0.07, 1.39, 3.87},
     {-3.44, 0.03, 0.13, 0.70, 2.24},
     96,
     {1.08, 1.99, 1.51, 2.80, 0.83, 1.54, 1.21, 2.25, 1265, kNa},
     {13.36, 2.01, 25.01, 3.77, 9.56, 1.44, 18.03, 2.72, 7491, 2.1},
     {{{-2.23e-2, 0.82, 0.42},
       {5.22e-4, 0.04, 0.97},
       {2.33e-3, 9.53, 0.00},
       {6.84e-5, 1.12, 0.27},
       {1.46e-3, 2.73, 0.01}}},
     28.70,
     0.00,
     0.56,
     {0.10, 0.57, 0.53, 0.37, 1.49},
     {0.33, 17.42, 10.45, 18.37, 75.08},
     {40, 233, 238, 90, 422},
     {4.13, 21.60, 20.53, 9.30, 39.38}},
    {"dense",
     {0.007, 0.177, 0.139, 0.149, kNa},
     {-0.563, 0.002, -0.002, 0.151, 0.564},
     {-0.755, -0.010, -0.002, 0.152, 0.505},
     {-0.366, 0.005, -0.000, 0.089, 0.278},
     {-8.48, 0.10, 0.05, 2.94, 8.46},
     {-7.10, -0.14, -0.14, 2.84, 6.54},
     {-5.27, 0.23, 0.40, 1.51, 4.20},
     92,
     {3.10, 5.74, 4.56, 8.44, 1.94, 3.58, 3.08, 5.69, 1265, kNa},
     {31.49, 4.75, 65.43, 9.87, 21.53, 3.25, 56.83, 8.57, 7491, -6.1},
     {{{-3.51e-2, -0.20, 0.85},
       {1.24e-1, 2.06, 0.04},
       {1.39e-3, 1.24, 0.22},
       {-1.08e-7, -0.43, 0.67},
       {9.84e-3, 3.52, 0.00}}},
     7.10,
     0.00,
     0.25,
     {0.10, 0.56, 0.53, 0.35, 1.42},
     {0.33, 17.79, 11.13, 18.48, 75.08},
     {306400, 540700, 568000, 88598, 656400},
     {6.13, 20.75, 20.03, 7.90, 36.85}},
}};

using eval::SampleStats;
using record::AlgorithmRecord;
using record::RunRecord;

// The run's algorithm `a` (one that twin_algorithms() found).
const AlgorithmRecord& algo(const RunRecord& m, const std::string& a) { return m.algorithms.at(a); }

// A covariate's statistics over the sections, NaN where the run has not that covariate.
SampleStats covariate(const AlgorithmRecord& a, const char* name) {
  const auto it = a.evaluation.covariates.find(name);
  if (it != a.evaluation.covariates.end()) return it->second;
  return {{0, kNa, kNa, kNa, kNa, kNa}, kNa};
}

// A regression term's coefficient, NaN where the regression did not fit it.
eval::CoefficientRecord coefficient(const AlgorithmRecord& a, const char* term) {
  const auto& c = a.evaluation.regression.coefficients;
  if (c) {
    const auto it = c->find(term);
    if (it != c->end()) return it->second;
  }
  return {kNa, kNa, kNa, kNa, kNa, false};
}

std::string num(double v, const char* spec = "{:.3f}") {
  return std::isfinite(v) ? fmt::format(fmt::runtime(spec), v) : std::string("—");
}

// One column of a side-by-side table: a header and a cell per row.
struct Column {
  std::string header;
  std::vector<std::string> cells;
};

std::string table(const std::vector<std::string>& rows, const std::vector<Column>& columns) {
  std::string out = "| |";
  std::string rule = "|---|";
  for (const Column& c : columns) {
    out += " " + c.header + " |";
    rule += "---|";
  }
  out += "\n" + rule + "\n";
  for (std::size_t r = 0; r < rows.size(); ++r) {
    out += "| " + rows[r] + " |";
    for (const Column& c : columns) out += " " + c.cells[r] + " |";
    out += "\n";
  }
  return out + "\n";
}

// The suffix of an algorithm measured at the paper's prism (app/paper_command.hpp).
constexpr std::string_view kPrism = " (prism)";

bool at_prism(std::string_view a) { return a.ends_with(kPrism); }

// The VO an algorithm's column is: sparse, sparse_kf or dense.
std::string_view vo_of(std::string_view a) {
  return at_prism(a) ? a.substr(0, a.size() - kPrism.size()) : a;
}

// The run's algorithms that the paper's columns compare with, in order: each VO at the camera,
// then at the prism when the run has it there too.
std::vector<std::string> twin_algorithms(const RunRecord& metrics) {
  std::vector<std::string> out;
  for (const std::string a : {"sparse", "sparse_kf", "dense"})
    for (const std::string& name : {a, a + std::string(kPrism)})
      if (metrics.algorithms.count(name)) out.push_back(name);
  if (out.empty())
    throw UserError(
        "driftlab paper: the run has none of the algorithms sparse, sparse_kf and dense "
        "(metrics.json 'algorithms')");
  return out;
}

// Columns in the order paper sparse, twin sparse, twin sparse_kf, paper dense, twin dense.
template <class PaperCells, class TwinCells>
std::vector<Column> columns(const std::vector<std::string>& twins, PaperCells paper,
                            TwinCells twin) {
  std::vector<Column> out;
  for (const PaperColumn& p : kPaper) {
    out.push_back({fmt::format("paper {}", p.algorithm), paper(p)});
    for (const std::string& a : twins) {
      const bool belongs = (vo_of(a) == "dense") == (std::string_view(p.algorithm) == "dense");
      if (belongs) out.push_back({fmt::format("twin {}", a), twin(a)});
    }
  }
  return out;
}

std::vector<std::string> stats_cells(const Stats& s, double n, const char* spec) {
  return {num(s.min, spec), num(s.mean, spec), num(s.median, spec),
          num(s.sd, spec),  num(s.max, spec),  num(n, "{:.0f}")};
}

std::vector<std::string> twin_stats_cells(const SampleStats& d, const char* spec) {
  return stats_cells({d.min, d.mean, d.median, d.sd, d.max}, static_cast<double>(d.n), spec);
}

const std::vector<std::string> kStatRows{"Min", "Mean", "Median", "SD", "Max", "n"};

// A row of mean (SD) cells: the paper's statistics and the run's, a member of the rows `group`
// gives of an algorithm.
template <class Rows>
struct MeanSdRow {
  const char* name;
  Stats PaperColumn::*paper;
  SampleStats Rows::*twin;
};

template <class Rows, std::size_t N, class Group>
std::string mean_sd_table(const RunRecord& m, const std::vector<std::string>& twins,
                          const std::array<MeanSdRow<Rows>, N>& rows, Group group) {
  std::vector<std::string> names;
  for (const MeanSdRow<Rows>& r : rows) names.push_back(std::string(r.name) + ", mean (SD)");
  return table(names,
               columns(
                   twins,
                   [&](const PaperColumn& p) {
                     std::vector<std::string> c;
                     for (const MeanSdRow<Rows>& r : rows)
                       c.push_back(num((p.*r.paper).mean) + " (" + num((p.*r.paper).sd) + ")");
                     return c;
                   },
                   [&](const std::string& a) {
                     std::vector<std::string> c;
                     const Rows& g = group(algo(m, a));
                     for (const MeanSdRow<Rows>& r : rows)
                       c.push_back(num((g.*r.twin).mean) + " (" + num((g.*r.twin).sd) + ")");
                     return c;
                   }));
}

// The columns with the paper's attitude comparison: not the (prism) ones, whose truth differs
// from the camera's in position only.
std::vector<std::string> attitude_twins(const RunRecord& m, const std::vector<std::string>& twins) {
  std::vector<std::string> out;
  for (const std::string& a : twins)
    if (!at_prism(a) && algo(m, a).evaluation.paper_attitude) out.push_back(a);
  return out;
}

// Table 1's angle rows as the paper computed them (Eq. (11)): the run's AHRS against the VO's
// angles in its first camera's frame. The paper's cells are its Table 1, computed that way.
std::string paper_attitude_rows(const RunRecord& m, const std::vector<std::string>& all) {
  const std::vector<std::string> twins = attitude_twins(m, all);
  if (twins.empty()) return "";
  using Rows = eval::PaperAttitudeRecord;
  const std::array<MeanSdRow<Rows>, 3> rows{
      {{"e'_roll, AHRS − VO (deg/m)", &PaperColumn::roll, &Rows::roll_deg_per_m},
       {"e'_pitch, AHRS − VO (deg/m)", &PaperColumn::pitch, &Rows::pitch_deg_per_m},
       {"e'_yaw, AHRS − VO (deg/m)", &PaperColumn::yaw, &Rows::yaw_deg_per_m}}};
  return "The angle rows above compare the VO's rotation with the true one in the same camera "
         "axes. The paper compared the x-IMU's Euler angles in its own frame with the VO's in "
         "its first camera's frame (Eq. (11)); the twin's AHRS (`sensors.ahrs`) compared the "
         "same way:\n\n" +
         mean_sd_table(m, twins, rows, [](const AlgorithmRecord& a) -> const Rows& {
           return *a.evaluation.paper_attitude;
         });
}

// Section 3.1: the largest pitch and roll errors over the four crossings, compared as the
// paper compared them (sparse 17.78 and 13.88 deg, dense 45.48 and 40.56 deg).
std::string attitude_maxima(const RunRecord& m, const std::vector<std::string>& all) {
  const std::vector<std::string> twins = attitude_twins(m, all);
  if (twins.empty()) return "";
  std::string out =
      "## Section 3.1. Largest pitch and roll errors along the track, AHRS − VO (deg)\n\n";
  out += table(
      {"pitch", "roll"},
      columns(
          twins,
          [](const PaperColumn& p) -> std::vector<std::string> {
            const bool sparse = std::string_view(p.algorithm) == "sparse";
            return {num(sparse ? 17.78 : 45.48, "{:.2f}"), num(sparse ? 13.88 : 40.56, "{:.2f}")};
          },
          [&](const std::string& a) -> std::vector<std::string> {
            const eval::EulerDeg& d = algo(m, a).evaluation.paper_attitude->max_abs_deg;
            return {num(d.pitch, "{:.2f}"), num(d.roll, "{:.2f}")};
          }));
  return out;
}

std::string table1(const RunRecord& m, const std::vector<std::string>& twins) {
  std::string out =
      "## Table 1. Position error over displacement e'_p (m/m) over the 6.5 m sections\n\n";
  out +=
      table(kStatRows,
            columns(
                twins, [](const PaperColumn& p) { return stats_cells(p.ep, p.sections, "{:.3f}"); },
                [&](const std::string& a) {
                  return twin_stats_cells(algo(m, a).evaluation.sections.rows.p_m_per_m, "{:.3f}");
                }));
  // The components: mean and SD (each work defines its axes: the twin's x is
  // the optical axis, y right, z down).
  using Rows = eval::Table1Rows;
  const std::array<MeanSdRow<Rows>, 6> rows{
      {{"e'_x (m/m)", &PaperColumn::x, &Rows::x_m_per_m},
       {"e'_y (m/m)", &PaperColumn::y, &Rows::y_m_per_m},
       {"e'_z (m/m)", &PaperColumn::z, &Rows::z_m_per_m},
       {"e'_roll (deg/m)", &PaperColumn::roll, &Rows::roll_deg_per_m},
       {"e'_pitch (deg/m)", &PaperColumn::pitch, &Rows::pitch_deg_per_m},
       {"e'_yaw (deg/m)", &PaperColumn::yaw, &Rows::yaw_deg_per_m}}};
  out += mean_sd_table(m, twins, rows, [](const AlgorithmRecord& a) -> const Rows& {
    return a.evaluation.sections.rows;
  });
  out += paper_attitude_rows(m, twins);
  return out;
}

std::string metres_pct(double m, double pct) {
  return num(m, "{:.2f}") + " (" + num(pct, "{:.2f}") + ")";
}

std::string table2(const RunRecord& m, const std::vector<std::string>& twins,
                   RiverPaperTrack track) {
  const bool discharge = track == RiverPaperTrack::kDischarge;
  std::string out =
      fmt::format("## Table 2. Position errors, m (% of track length), {}\n\n",
                  discharge ? "discharge measurement (four crossings)" : "total trajectory");
  const std::vector<std::string> rows{"3D RMSE", "3D max", "2D RMSE",
                                      "2D max",  "N",      "track length error (%)"};
  out += table(
      rows, columns(
                twins,
                [&](const PaperColumn& p) -> std::vector<std::string> {
                  const TrackErrors& e = discharge ? p.discharge : p.total;
                  return {metres_pct(e.rmse_3d, e.rmse_3d_pct),
                          metres_pct(e.max_3d, e.max_3d_pct),
                          metres_pct(e.rmse_2d, e.rmse_2d_pct),
                          metres_pct(e.max_2d, e.max_2d_pct),
                          num(e.n, "{:.0f}"),
                          num(e.length_error_pct, "{:+.1f}")};
                },
                [&](const std::string& a) -> std::vector<std::string> {
                  const eval::TrackRecord& t = algo(m, a).evaluation.track;
                  return {
                      metres_pct(t.rmse_3d_m, t.rmse_3d_pct),  metres_pct(t.max_3d_m, t.max_3d_pct),
                      metres_pct(t.rmse_2d_m, t.rmse_2d_pct),  metres_pct(t.max_2d_m, t.max_2d_pct),
                      num(static_cast<double>(t.n), "{:.0f}"), num(t.length_error_pct, "{:+.1f}")};
                }));
  return out;
}

std::string coefficient_cell(double beta, double t, double p) {
  if (!std::isfinite(beta)) return "—";
  return fmt::format("{:.2e} (t {:.2f}, p {:.2f}){}", beta, t, p, p < 0.05 ? " *" : "");
}

std::string table3(const RunRecord& m, const std::vector<std::string>& twins) {
  std::string out =
      "## Table 3. Regression of e'_p on the covariates: beta (t, p); * significant at 0.05\n\n";
  std::vector<std::string> rows(kTerms.begin(), kTerms.end());
  rows.insert(rows.end(), {"F (p)", "R²"});
  out += table(rows, columns(
                         twins,
                         [](const PaperColumn& p) {
                           std::vector<std::string> c;
                           for (const Coefficient& k : p.coefficients)
                             c.push_back(coefficient_cell(k.beta, k.t, k.p));
                           c.push_back(fmt::format("{:.2f} ({:.2f})", p.f, p.f_p));
                           c.push_back(num(p.r2, "{:.2f}"));
                           return c;
                         },
                         [&](const std::string& a) {
                           const AlgorithmRecord& al = algo(m, a);
                           const eval::RegressionRecord& r = al.evaluation.regression;
                           std::vector<std::string> c;
                           for (const char* term : kTerms) {
                             const eval::CoefficientRecord k = coefficient(al, term);
                             c.push_back(coefficient_cell(k.estimate, k.t, k.p));
                           }
                           c.push_back(num(r.f.value_or(kNa), "{:.2f}") + " (" +
                                       num(r.f_p.value_or(kNa), "{:.2f}") + ")");
                           c.push_back(num(r.r2.value_or(kNa), "{:.2f}"));
                           return c;
                         }));
  return out;
}

std::string table4(const RunRecord& m, const std::vector<std::string>& twins) {
  std::string out = "## Table 4. The covariates over the sections: mean (median; min-max)\n\n";
  const std::vector<std::string> rows{"v (m/s)", "h (deg)", "f (inliers; dense: pixels)", "d (m)"};
  constexpr std::array<const char*, 4> kKeys{"v", "h", "f", "d"};
  constexpr std::array<const char*, 4> kSpecs{"{:.2f}", "{:.2f}", "{:.0f}", "{:.2f}"};
  auto cell = [&](const Stats& s, std::size_t row) {
    const char* f = kSpecs[row];
    return fmt::format("{} ({}; {}-{})", num(s.mean, f), num(s.median, f), num(s.min, f),
                       num(s.max, f));
  };
  out +=
      table(rows, columns(
                      twins,
                      [&](const PaperColumn& p) -> std::vector<std::string> {
                        return {cell(p.v, 0), cell(p.h, 1), cell(p.features, 2), cell(p.depth, 3)};
                      },
                      [&](const std::string& a) {
                        std::vector<std::string> c;
                        for (std::size_t r = 0; r < kKeys.size(); ++r) {
                          const SampleStats d = covariate(algo(m, a), kKeys[r]);
                          c.push_back(cell({d.min, d.mean, d.median, d.sd, d.max}, r));
                        }
                        return c;
                      }));
  return out;
}

// The paper's findings, each checked on the twin.
std::string findings(const RunRecord& m, const std::vector<std::string>& twins) {
  std::string out = "## The paper's findings on the twin\n\n";
  auto ep = [&](const char* a) { return algo(m, a).evaluation.sections.rows.p_m_per_m.mean; };
  auto has = [&](const char* a) { return std::find(twins.begin(), twins.end(), a) != twins.end(); };
  if (has("dense") && has("sparse"))
    out += fmt::format(
        "- Sparse beats dense (Table 1, mean e'_p): paper yes (0.067 against 0.177 m/m); twin {} "
        "({} against {} m/m).\n",
        ep("sparse") < ep("dense") ? "yes" : "no", num(ep("sparse")), num(ep("dense")));
  for (const std::string& a : twins) {
    if (vo_of(a) == "sparse_kf") continue;
    auto significant = [&](const char* term) {
      const double p = coefficient(algo(m, a), term).p;
      return std::isfinite(p) ? (p < 0.05 ? "significant" : "not significant") : "not fitted";
    };
    out += fmt::format("- {} (Table 3): paper finds {}; twin: h {}, d {}, v {}.\n", a,
                       vo_of(a) == "sparse" ? "h and d significant" : "v and d significant",
                       significant("h"), significant("d"), significant("v"));
  }
  return out + "\n";
}

// Where the twin's truth was measured, when not at the camera (eval.reference_point_m): the
// paper's truth was a prism the total station tracked, not its camera.
std::string reference_point_note(const AlgorithmRecord& algorithm, std::string_view whose) {
  const std::array<double, 3>& l = algorithm.evaluation.association.reference_point_m;
  if (l == std::array<double, 3>{0.0, 0.0, 0.0}) return "";
  return fmt::format(
      "{} truth is measured {:.2f} m from its camera, at [{:.3g}, {:.3g}, {:.3g}] m in the "
      "camera's "
      "frame (x right, y down, z forward; `eval.reference_point_m`, `driftlab paper --prism`), "
      "as the paper's total station tracked a prism on the vessel; the estimates are the "
      "camera's, with no lever-arm correction.\n\n",
      whose, std::hypot(l[0], l[1], l[2]), l[0], l[1], l[2]);
}

}  // namespace

std::optional<RiverPaperTrack> river_paper_track_of(const std::string& scenario_name) {
  if (scenario_name == "river_crossing") return RiverPaperTrack::kDischarge;
  if (scenario_name == "river_survey") return RiverPaperTrack::kTotal;
  return std::nullopt;
}

std::string river_paper_side_by_side(const RunRecord& metrics, RiverPaperTrack track) {
  const std::vector<std::string> twins = twin_algorithms(metrics);
  std::string out = fmt::format(
      "# River paper (Kriechbaumer et al. 2015, Tables 1-4) and the twin run '{}' side by side\n\n"
      "Paper: the real River Great Ouse, 96 sections (dense: 92). Twin: {} sections of {} m. "
      "`sparse` is the paper's method on both sides; `sparse_kf` (keyframes) is ours.\n\n",
      metrics.scenario.value_or("?"),
      num(static_cast<double>(algo(metrics, twins.front()).evaluation.sections.count), "{:.0f}"),
      num(algo(metrics, twins.front()).evaluation.sections.section_length_m, "{:.1f}"));
  out += reference_point_note(algo(metrics, twins.front()), "The twin's");
  for (const std::string& a : twins)
    if (at_prism(a)) {
      out += reference_point_note(algo(metrics, a), "In the (prism) columns the");
      break;
    }
  out += table1(metrics, twins);
  out += table2(metrics, twins, track);
  if (track == RiverPaperTrack::kDischarge) out += attitude_maxima(metrics, twins);
  out += table3(metrics, twins);
  out += table4(metrics, twins);
  out += findings(metrics, twins);
  return out;
}

}  // namespace driftlab::report
