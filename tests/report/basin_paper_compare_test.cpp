// The basin paper's Tables 2-3 next to the twin's runs: the paper's printed cells, the runs'
// from metrics.json in the paper's units, both references, and which experiment is hardest.
#include "report/basin_paper_compare.hpp"

#include <gtest/gtest.h>

#include <string>

#include "core/error.hpp"

namespace driftlab::report {
namespace {

// A basin table in SI units, every quantity's RMSE `rmse` and SD `sd`.
nlohmann::json table(double rmse, double sd) {
  nlohmann::json t;
  for (const char* q : {"north_m", "east_m", "surge_m_s", "sway_m_s", "heading_deg"})
    t[q] = {{"rmse", rmse}, {"sd", sd}, {"n", 300}};
  return t;
}

nlohmann::json run(const std::string& scenario, double north_rmse_m) {
  nlohmann::json m;
  m["scenario"] = scenario;
  for (const char* a : {"pnp_ned_kf", "pnp_ned_pf"}) {
    m["algorithms"][a]["basin"] = table(0.01, 0.002);
    m["algorithms"][a]["basin"]["north_m"]["rmse"] = north_rmse_m;
    m["algorithms"][a]["basin_overhead"] = table(0.012, 0.003);
  }
  m["algorithms"]["pnp"]["basin"] = table(0.5, 0.5);  // the raw VO: not in the tables
  return m;
}

// The records the side-by-side reads, through the one reader of metrics.json.
std::vector<record::RunRecord> as_records(const std::vector<nlohmann::json>& runs) {
  std::vector<record::RunRecord> out;
  for (const nlohmann::json& m : runs) out.push_back(record::run_record_from_json(m, "m.json"));
  return out;
}

TEST(BasinPaperCompare, ThePapersCellsAndTheTwinsInThePapersUnits) {
  const std::string md =
      basin_paper_side_by_side(as_records({run("basin_exp1", 0.004), run("basin_exp4", 0.031)}));
  // Table 2, experiment 1, as printed: N 1.097 (1.213).
  EXPECT_NE(md.find("| 1 | calm | paper | 1.097 (1.213) | 1.608 (1.408) |"), std::string::npos)
      << md;
  // Table 3, experiment 4: N 6.265 (5.180).
  EXPECT_NE(md.find("| 4 | 40°, 11 mm, 59 mm | paper | 6.265 (5.180) |"), std::string::npos);
  // The twin's metres as centimetres; heading stays in degrees.
  EXPECT_NE(md.find("| 1 | calm | twin, exact truth | 0.400 (0.200) | 1.000 (0.200) | 1.000 "
                    "(0.200) | 1.000 (0.200) | 0.010 (0.002) |"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("| 4 | 40°, 11 mm, 59 mm | twin, overhead camera | 1.200 (0.300) |"),
            std::string::npos);
  EXPECT_NE(md.find("## Table 2. Kalman filter (pnp_ned_kf)"), std::string::npos);
  EXPECT_NE(md.find("## Table 3. Particle filter (pnp_ned_pf)"), std::string::npos);
  // Hardest by N: the paper's and the twin's exact rows both say experiment 4.
  EXPECT_NE(md.find("| paper | largest in 4, smallest in 1 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| twin, exact truth | largest in 4, smallest in 1 |"), std::string::npos);
}

TEST(BasinPaperCompare, ExperimentsByNameAndOtherRunsRefused) {
  EXPECT_EQ(basin_paper_experiment_of("basin_exp7"), 7);
  EXPECT_FALSE(basin_paper_experiment_of("basin_exp8").has_value());
  EXPECT_FALSE(basin_paper_experiment_of("river_crossing").has_value());
  EXPECT_THROW(basin_paper_side_by_side(as_records({run("river_crossing", 0.01)})), UserError);
  nlohmann::json no_filter = run("basin_exp2", 0.01);
  no_filter["algorithms"].erase("pnp_ned_kf");
  no_filter["algorithms"].erase("pnp_ned_pf");
  EXPECT_THROW(basin_paper_side_by_side(as_records({no_filter})), UserError);
}

}  // namespace
}  // namespace driftlab::report
