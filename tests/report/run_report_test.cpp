// Report pieces of a run: Markdown tables to HTML, gnuplot plots.
#include "report/run_report.hpp"
#include "report/gnuplot.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace driftlab::report {
namespace {

namespace fs = std::filesystem;

TEST(ReportHtml, TablesHeadingsParagraphsAndEscaping) {
  const std::string md =
      "# Run <a>\n\nSome text & more.\n\n| algo | e'_p |\n|---|---:|\n| sparse | 0.05 |\n"
      "| dense | 0.1 |\n\n## Next\n";
  const std::string h = report_html("t", md, {{"Top view", "plots/top_view.png"}});
  EXPECT_NE(h.find("<h1>Run &lt;a&gt;</h1>"), std::string::npos) << h;
  EXPECT_NE(h.find("<p>Some text &amp; more.</p>"), std::string::npos) << h;
  EXPECT_NE(h.find("<table>\n<tr><th>algo</th><th>e'_p</th></tr>\n<tr><td>sparse</td><td>0.05</td>"
                   "</tr>\n<tr><td>dense</td><td>0.1</td></tr>\n</table>"),
            std::string::npos)
      << h;
  EXPECT_NE(h.find("<h2>Next</h2>"), std::string::npos);
  EXPECT_NE(h.find("<img src=\"plots/top_view.png\" alt=\"Top view\">"), std::string::npos);
}

TEST(Plots, GnuplotDrawsEveryPlotOrSaysWhyNot) {
  const fs::path dir = fs::temp_directory_path() / ("driftlab_plots_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  Trajectory gt, est;
  for (int k = 0; k < 50; ++k) {
    gt.push_back({k * 100'000'000LL, SE3(Mat3::Identity(), Vec3(0.1 * k, 0, 0))});
    est.push_back({k * 100'000'000LL, SE3(Mat3::Identity(), Vec3(0.1 * k, 0.01 * k, 0))});
  }
  const std::string sections =
      "algorithm,index,p_m_per_m,v,h,f,d\nsparse,0,0.1,0.5,1,100,20\nsparse,1,0.2,0.6,2,90,25\n"
      "sparse,2,0.15,0.55,1.5,95,22\n";
  const PlotSet made = make_plots(dir, gt, {{"sparse", est}}, sections);
  const auto& plots = made.files;
  const std::string& warning = made.warning;
  // The data files are written whatever happens to gnuplot.
  std::ifstream data(dir / "plots/data/sparse.dat");
  std::string header, first;
  std::getline(data, header);
  std::getline(data, first);
  EXPECT_EQ(header, "# t_s north_m east_m down_m yaw_deg pitch_deg roll_deg err3d_m");
  std::getline(data, first);  // frame 1: 0.01 m off the truth
  EXPECT_NE(first.rfind(" 0.01"), std::string::npos) << first;
  if (!find_gnuplot().gnuplot) {
    EXPECT_TRUE(plots.empty());
    EXPECT_NE(warning.find("gnuplot"), std::string::npos);
    GTEST_SKIP() << "gnuplot not installed";
  }
  EXPECT_TRUE(warning.empty()) << warning;
  ASSERT_EQ(plots.size(), 5u);
  for (const auto& p : plots) {
    std::ifstream png(dir / p.file, std::ios::binary);
    char magic[4] = {};
    png.read(magic, 4);
    EXPECT_EQ(std::string(magic + 1, 3), "PNG") << p.file;
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace driftlab::report
