// The report of a run: plots drawn by gnuplot (river paper Figs. 3, 5, 6 and 7 and the
// covariate scatter of Table 3) and report.html, the Markdown report with the plots inline.
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "core/trajectory_io.hpp"

namespace driftlab::report {

struct PlotFile {
  std::string title;
  std::string file;  ///< relative to the run folder, e.g. "plots/top_view.png"
};

struct NamedTrajectory {
  std::string name;
  Trajectory trajectory;
};

struct PlotSet {
  std::vector<PlotFile> files;  ///< none when gnuplot is missing or failed
  std::string warning;          ///< why there are none
};

/// Writes the plot data (DIR/plots/data/*.dat), a gnuplot script (DIR/plots/plots.gp) and runs
/// gnuplot on it. `sections_csv` is the content of sections.csv.
PlotSet make_plots(const std::filesystem::path& dir, const Trajectory& gt,
                   const std::vector<NamedTrajectory>& estimates, const std::string& sections_csv);

/// report.html: `markdown` (headings, paragraphs, pipe tables, as eval writes them) as HTML,
/// followed by the plots.
std::string report_html(const std::string& title, const std::string& markdown,
                        const std::vector<PlotFile>& plots);

}  // namespace driftlab::report
