#include "report/run_report.hpp"

#include <array>
#include <cmath>
#include <map>
#include <sstream>

#include <fmt/format.h>

#include "core/atomic_file.hpp"
#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/markup.hpp"
#include "core/rotation.hpp"
#include "core/time.hpp"
#include "core/yaml_io.hpp"
#include "report/gnuplot.hpp"

namespace driftlab::report {

namespace {

std::string yaml_num(double v) { return std::isfinite(v) ? yaml::format_double(v) : "NaN"; }

// Euler ZYX [deg] of the camera with FRD axes (x along the optical axis): the attitude a
// reader compares with the platform's (river paper Fig. 7).
Vec3 camera_euler_deg(const SE3& T_W_C) {
  const EulerZYX e = euler_zyx_from_matrix(T_W_C.rotation() * R_frd_optical().transpose());
  return Vec3(rad2deg(e.yaw_rad), rad2deg(e.pitch_rad), rad2deg(e.roll_rad));
}

std::string trajectory_dat(const Trajectory& tr, const Trajectory* gt) {
  std::string s = "# t_s north_m east_m down_m yaw_deg pitch_deg roll_deg err3d_m\n";
  for (std::size_t k = 0; k < tr.size(); ++k) {
    const Vec3 p = tr[k].T_W_C.translation();
    const Vec3 e = camera_euler_deg(tr[k].T_W_C);
    double err = NAN;
    if (gt != nullptr && k < gt->size() && (*gt)[k].t_ns == tr[k].t_ns)
      err = (p - (*gt)[k].T_W_C.translation()).norm();
    s += fmt::format("{} {} {} {} {} {} {} {}\n", yaml_num(ns_to_seconds(tr[k].t_ns)),
                     yaml_num(p.x()), yaml_num(p.y()), yaml_num(p.z()), yaml_num(e.x()),
                     yaml_num(e.y()), yaml_num(e.z()), yaml_num(err));
  }
  return s;
}

// gnuplot string literal (single quotes; a quote is doubled).
std::string q(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

// The cells of a Markdown table row's inside, split at '|'.
std::vector<std::string> split_pipes(const std::string& text) {
  std::vector<std::string> out;
  std::string cell;
  std::istringstream in(text);
  while (std::getline(in, cell, '|')) out.push_back(cell);
  if (!text.empty() && text.back() == '|') out.emplace_back();
  return out;
}

// sections.csv split per algorithm: one "p_m_per_m v h f d" row per section, in the order the
// algorithms first appear.
struct SectionRows {
  std::map<std::string, std::string> rows;  // by algorithm
  std::vector<std::string> order;
};

SectionRows split_sections(const std::string& sections_csv) {
  SectionRows out;
  // The rows of a track whose covariates the first track lacks are longer than the header:
  // left out of the plots, as before.
  const CsvTable t = read_csv_table(sections_csv, "sections.csv", {.ragged = true});
  const std::vector<std::string> cov_names = {"v", "h", "f", "d"};
  const auto c_alg = t.column("algorithm"), c_p = t.column("p_m_per_m");
  if (!c_alg || !c_p) return out;
  for (const CsvTable::Row& r : t.rows) {
    if (r.cells.size() != t.header.size()) continue;
    const std::string& alg = r.cells[*c_alg];
    if (!out.rows.count(alg)) out.order.push_back(alg);
    std::string row = r.cells[*c_p];
    for (const auto& c : cov_names) {
      const auto i = t.column(c);
      row += " " + (i && !r.cells[*i].empty() ? r.cells[*i] : std::string("NaN"));
    }
    out.rows[alg] += row + "\n";
  }
  return out;
}

// Part of plots.gp and the plots it makes.
struct PlotScript {
  std::string gp;
  std::vector<PlotFile> made;
};

// The plot command's curves: the truth (when `with_gt`) and every estimate.
std::string curves(const std::vector<NamedTrajectory>& estimates, const std::string& using_gt,
                   const std::string& using_est, bool with_gt) {
  std::string s;
  if (with_gt)
    s += "'data/groundtruth.dat' using " + using_gt +
         " with lines lw 2 lc 'black' title 'ground truth'";
  for (const auto& e : estimates) {
    if (!s.empty()) s += ", ";
    s += q("data/" + e.name + ".dat") + " using " + using_est + " with lines title " + q(e.name);
  }
  return s;
}

// Top view (Fig. 6), position error over time and Euler angles (Fig. 7).
PlotScript trajectory_plots(const std::vector<NamedTrajectory>& estimates) {
  PlotScript out;
  std::string& gp = out.gp;
  gp +=
      "set output 'top_view.png'\nset title 'Top view (river paper Fig. 6)'\n"
      "set xlabel 'east [m]'\nset ylabel 'north [m]'\nset size ratio -1\n"
      "plot " +
      curves(estimates, "3:2", "3:2", true) + "\nset size noratio\n";
  out.made.push_back(
      {"Top view of the ground truth and every estimate (Fig. 6)", "plots/top_view.png"});
  gp +=
      "set output 'position_error.png'\nset title '3D position error'\n"
      "set xlabel 'time [s]'\nset ylabel 'error [m]'\nplot " +
      curves(estimates, "1:8", "1:8", false) + "\n";
  out.made.push_back({"3D position error over time", "plots/position_error.png"});
  gp +=
      "set output 'euler.png'\nset multiplot layout 3,1 title 'Camera attitude, FRD axes (Fig. "
      "7)'\n"
      "set xlabel ''\n";
  const char* angles[] = {"yaw", "pitch", "roll"};
  for (int a = 0; a < 3; ++a) {
    const std::string col = std::to_string(5 + a);
    gp += fmt::format("set title ''\nset ylabel '{} [deg]'\n{}plot {}\n", angles[a],
                      a == 2 ? "set xlabel 'time [s]'\n" : "",
                      curves(estimates, "1:" + col, "1:" + col, true));
  }
  gp += "unset multiplot\n";
  out.made.push_back({"Euler angles of the estimates and the truth (Fig. 7)", "plots/euler.png"});
  return out;
}

// A covariate panel's least-squares line, a + b x, as a curve to append to its plot command;
// empty when the points (x, e'_p) do not determine one.
std::string least_squares_curve(const std::vector<std::array<double, 2>>& pts) {
  double mx = 0, my = 0;
  for (const auto& p : pts) {
    mx += p[0] / static_cast<double>(pts.size());
    my += p[1] / static_cast<double>(pts.size());
  }
  double sxx = 0, sxy = 0;
  for (const auto& p : pts) {
    sxx += (p[0] - mx) * (p[0] - mx);
    sxy += (p[0] - mx) * (p[1] - my);
  }
  if (pts.size() >= 3 && sxx > 1e-12 * (1 + mx * mx) * static_cast<double>(pts.size())) {
    const double b = sxy / sxx, a = my - b * mx;
    return fmt::format(", {} + {} * x with lines lw 2 title 'least squares'", yaml_num(a),
                       yaml_num(b));
  }
  return "";
}

// Section error against the covariates of one algorithm (Table 3): four panels, each with the
// least-squares line of e'_p on its covariate. `rows` are the algorithm's section rows.
std::string covariate_panels(const std::string& alg, const std::string& rows) {
  std::string gp = "set output 'covariates.png'\nset multiplot layout 2,2 title " +
                   q("Section error against the covariates, " + alg + " (Table 3)") + "\n";
  const char* labels[] = {"v: speed [m/s]", "h: yaw rate sd [deg/s]", "f: inlier features",
                          "d: mean feature depth [m]"};
  // The least-squares line of each panel (simple regression of e'_p on one covariate).
  std::vector<std::array<double, 2>> xy[4];
  {
    std::istringstream in(rows);
    std::string r;
    while (std::getline(in, r)) {
      std::istringstream v(r);
      double p = NAN, c[4] = {NAN, NAN, NAN, NAN};
      v >> p >> c[0] >> c[1] >> c[2] >> c[3];
      for (int k = 0; k < 4; ++k)
        if (std::isfinite(p) && std::isfinite(c[k])) xy[k].push_back({c[k], p});
    }
  }
  for (int c = 0; c < 4; ++c) {
    const std::string data = q("data/sections_" + alg + ".dat");
    gp += fmt::format("set title ''\nset xlabel '{}'\nset ylabel 'e''_p [m/m]'\n", labels[c]);
    gp += fmt::format("plot {} using {}:1 with points pt 7 ps 0.6 title 'sections'", data, c + 2);
    gp += least_squares_curve(xy[c]);
    gp += "\n";
  }
  gp += "unset multiplot\n";
  return gp;
}

// The section error histogram (Fig. 5) and the covariate panels of the first algorithm; none
// without sections.
PlotScript section_plots(const SectionRows& sections) {
  PlotScript out;
  if (sections.order.empty()) return out;
  std::string& gp = out.gp;
  gp +=
      "set output 'section_errors.png'\nset title 'Section position error e''_p (Fig. 5)'\n"
      "set xlabel 'e''_p [m/m]'\nset ylabel 'sections'\nset style fill transparent solid 0.4\n"
      "bin(x) = 0.02 * floor(x / 0.02) + 0.01\nplot ";
  for (std::size_t i = 0; i < sections.order.size(); ++i)
    gp += (i ? ", " : "") + q("data/sections_" + sections.order[i] + ".dat") +
          " using (bin($1)):(1) smooth frequency with boxes title " + q(sections.order[i]);
  gp += "\nset style fill empty\n";
  out.made.push_back({"Distribution of the section errors (Fig. 5)", "plots/section_errors.png"});
  const std::string first = sections.order.front();
  gp += covariate_panels(first, sections.rows.at(first));
  out.made.push_back(
      {"Section error against each covariate, with a least-squares line", "plots/covariates.png"});
  return out;
}

}  // namespace

PlotSet make_plots(const std::filesystem::path& dir, const Trajectory& gt,
                   const std::vector<NamedTrajectory>& estimates, const std::string& sections_csv) {
  const std::filesystem::path plots = dir / "plots";
  std::filesystem::create_directories(plots / "data");
  write_file_atomic(plots / "data" / "groundtruth.dat", trajectory_dat(gt, nullptr));
  for (const auto& e : estimates)
    write_file_atomic(plots / "data" / (e.name + ".dat"), trajectory_dat(e.trajectory, &gt));

  // sections.csv split per algorithm: p_m_per_m and the covariates.
  const SectionRows sections = split_sections(sections_csv);
  for (const auto& alg : sections.order)
    write_file_atomic(plots / "data" / ("sections_" + alg + ".dat"),
                      "# p_m_per_m v h f d\n" + sections.rows.at(alg));

  // Data files first: they are written whatever happens to gnuplot.
  const GnuplotLookup lookup = find_gnuplot();
  const std::string terminal = lookup.gnuplot ? lookup.gnuplot->terminal : "pngcairo";
  std::vector<PlotFile> made;
  std::string gp =
      "# Made by driftlab run; re-run with: cd plots && gnuplot plots.gp\n"
      "set terminal " +
      terminal +
      " size 900,640 font ',10' noenhanced\n"
      "set grid\nset key outside right top\n";
  for (const PlotScript& part : {trajectory_plots(estimates), section_plots(sections)}) {
    gp += part.gp;
    made.insert(made.end(), part.made.begin(), part.made.end());
  }
  write_file_atomic(plots / "plots.gp", gp);
  if (!lookup.gnuplot) return {{}, lookup.warning + ": no plots"};
  const GnuplotRun run = run_gnuplot(*lookup.gnuplot, plots, "plots.gp", "gnuplot.log");
  if (!run.ok) return {{}, fmt::format("gnuplot failed ({}): see plots/gnuplot.log", run.failure)};
  return {made, ""};
}

// HTML text and double-quoted attributes: apostrophes stay as they are ("e'_p").
static std::string html_escape(std::string_view s) {
  return markup_escape(s, MarkupQuotes::kDoubleOnly);
}

std::string report_html(const std::string& title, const std::string& markdown,
                        const std::vector<PlotFile>& plots) {
  std::string h = "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>" +
                  html_escape(title) +
                  "</title>\n<style>body{font-family:sans-serif;max-width:70em;margin:auto}"
                  "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #999;"
                  "padding:2px 8px;text-align:right}th{background:#eee}img{max-width:100%}"
                  "</style></head><body>\n";
  std::istringstream in(markdown);
  std::string line;
  bool in_table = false, header_row = false;
  auto cells = [](const std::string& l) {
    std::vector<std::string> out;
    std::string t = l.substr(1, l.size() > 1 && l.back() == '|' ? l.size() - 2 : l.size() - 1);
    for (auto& c : split_pipes(t)) {
      const auto b = c.find_first_not_of(' '), e = c.find_last_not_of(' ');
      out.push_back(b == std::string::npos ? "" : c.substr(b, e - b + 1));
    }
    return out;
  };
  while (std::getline(in, line)) {
    const bool table_line = !line.empty() && line[0] == '|';
    if (table_line && !in_table) {
      h += "<table>\n";
      in_table = header_row = true;
    } else if (!table_line && in_table) {
      h += "</table>\n";
      in_table = false;
    }
    if (table_line) {
      if (line.find("---") != std::string::npos &&
          line.find_first_not_of("|-: ") == std::string::npos)
        continue;  // the separator row
      const char* tag = header_row ? "th" : "td";
      h += "<tr>";
      for (const auto& c : cells(line)) h += fmt::format("<{0}>{1}</{0}>", tag, html_escape(c));
      h += "</tr>\n";
      header_row = false;
    } else if (line.rfind("### ", 0) == 0) {
      h += "<h3>" + html_escape(line.substr(4)) + "</h3>\n";
    } else if (line.rfind("## ", 0) == 0) {
      h += "<h2>" + html_escape(line.substr(3)) + "</h2>\n";
    } else if (line.rfind("# ", 0) == 0) {
      h += "<h1>" + html_escape(line.substr(2)) + "</h1>\n";
    } else if (!line.empty()) {
      h += "<p>" + html_escape(line) + "</p>\n";
    }
  }
  if (in_table) h += "</table>\n";
  if (!plots.empty()) h += "<h2>Plots</h2>\n";
  for (const auto& p : plots)
    h += fmt::format("<figure><img src=\"{0}\" alt=\"{1}\"><figcaption>{1}</figcaption></figure>\n",
                     html_escape(p.file), html_escape(p.title));
  return h + "</body></html>\n";
}

}  // namespace driftlab::report
