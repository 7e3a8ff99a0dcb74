// The river paper's tables next to a run's: the paper's printed numbers, the
// run's from metrics.json, the right Table 2 row, and the findings.
#include "report/paper_compare.hpp"

#include <gtest/gtest.h>

#include <string>

#include "core/error.hpp"

namespace driftlab::report {
namespace {

nlohmann::json stats(double min, double mean, double median, double sd, double max, int n) {
  return {{"min", min}, {"mean", mean}, {"median", median}, {"sd", sd}, {"max", max}, {"n", n}};
}

// The record the side-by-side reads, through the one reader of metrics.json.
record::RunRecord as_record(const nlohmann::json& m) {
  return record::run_record_from_json(m, "metrics.json");
}

// A run's metrics.json with the keys the side-by-side reads.
nlohmann::json algorithm(double ep_mean, double h_p) {
  nlohmann::json a;
  a["sections"]["count"] = 12;
  a["sections"]["section_length_m"] = 6.5;
  a["sections"]["p_m_per_m"] = stats(0.011, ep_mean, 0.031, 0.021, 0.091, 12);
  for (const char* k : {"x_m_per_m", "y_m_per_m", "z_m_per_m", "roll_deg_per_m", "pitch_deg_per_m",
                        "yaw_deg_per_m"})
    a["sections"][k] = stats(-0.1, 0.004, 0.0, 0.05, 0.1, 12);
  a["track"] = {{"rmse_3d_m", 1.234},       {"rmse_3d_pct", 2.345}, {"max_3d_m", 3.0},
                {"max_3d_pct", 4.0},        {"rmse_2d_m", 1.111},   {"rmse_2d_pct", 1.9},
                {"max_2d_m", 2.5},          {"max_2d_pct", 3.5},    {"n", 777},
                {"length_error_pct", -2.44}};
  a["regression"]["coefficients"]["Intercept"] = {{"estimate", 0.01}, {"t", 0.5}, {"p", 0.6}};
  a["regression"]["coefficients"]["h"] = {{"estimate", 0.00456}, {"t", 4.2}, {"p", h_p}};
  a["regression"]["coefficients"]["d"] = {{"estimate", 0.00123}, {"t", 1.1}, {"p", 0.3}};
  a["regression"]["f"] = 9.87;
  a["regression"]["f_p"] = 0.001;
  a["regression"]["r2"] = 0.42;
  a["covariates"]["v"] = stats(0.1, 0.57, 0.5, 0.1, 1.2, 12);
  a["covariates"]["h"] = stats(0.5, 15.25, 9.5, 8.0, 60.0, 12);
  a["covariates"]["f"] = stats(50, 210, 200, 40, 400, 12);
  a["covariates"]["d"] = stats(5.0, 22.5, 21.0, 6.0, 38.0, 12);
  return a;
}

TEST(PaperCompare, PaperAndTwinColumnsSideBySideWithTheRightTrack) {
  nlohmann::json m;
  m["scenario"] = "river_survey";
  m["algorithms"]["sparse"] = algorithm(0.0456, 0.001);
  m["algorithms"]["dense"] = algorithm(0.0321, 0.5);
  const std::string total = river_paper_side_by_side(as_record(m), RiverPaperTrack::kTotal);
  // The paper's printed values (Kriechbaumer et al. 2015, Tables 1-4).
  for (const char* paper :
       {"| Mean | 0.067 |", "0.177", "13.36 (2.01)", "31.49 (4.75)", "2.33e-03 (t 9.53, p 0.00) *",
        "28.70 (0.00)", "| 0.56 |", "17.42 (10.45; 0.33-75.08)", "233 (238; 40-422)"})
    EXPECT_NE(total.find(paper), std::string::npos) << paper;
  // The run's, in its own columns, with significance and the length error.
  for (const char* twin : {"| paper sparse | twin sparse | paper dense | twin dense |",
                           "| Mean | 0.067 | 0.046 | 0.177 | 0.032 |", "1.23 (2.35)", "777", "-2.4",
                           "4.56e-03 (t 4.20, p 0.00) *", "9.87 (0.00)", "15.25 (9.50; 0.50-60.00)",
                           "0.57 (0.50; 0.10-1.20)"})
    EXPECT_NE(total.find(twin), std::string::npos) << twin;
  EXPECT_EQ(total.find("1.08 (1.99)"), std::string::npos);  // the discharge row is not shown
  // v is not in this run's regression: an empty cell, not a made-up number.
  EXPECT_NE(total.find("| v | 5.22e-04 (t 0.04, p 0.97) | — |"), std::string::npos) << total;
  // Findings: the twin's dense beats its sparse here, unlike the paper.
  EXPECT_NE(total.find("paper yes (0.067 against 0.177 m/m); twin no (0.046 against 0.032"),
            std::string::npos)
      << total;
  EXPECT_NE(total.find("twin: h significant, d not significant"), std::string::npos) << total;

  const std::string discharge = river_paper_side_by_side(as_record(m), RiverPaperTrack::kDischarge);
  EXPECT_NE(discharge.find("1.08 (1.99)"), std::string::npos);
  EXPECT_EQ(discharge.find("13.36 (2.01)"), std::string::npos);
}

// A run with the AHRS: Table 1's angle rows as the paper computed them beside the exact ones,
// and on the discharge track the largest pitch and roll errors, with the paper's; a (prism)
// column, whose truth differs only in position, gets none. A run without it shows neither.
TEST(PaperCompare, TheAttitudeAsThePaperComparedItWhenTheRunHasAnAhrs) {
  nlohmann::json m;
  m["scenario"] = "river_crossing";
  m["algorithms"]["sparse"] = algorithm(0.0456, 0.001);
  m["algorithms"]["sparse (prism)"] = algorithm(0.0789, 0.001);
  const std::string without = river_paper_side_by_side(as_record(m), RiverPaperTrack::kDischarge);
  EXPECT_EQ(without.find("AHRS"), std::string::npos);
  nlohmann::json& a = m["algorithms"]["sparse"]["paper_attitude"];
  a["roll_deg_per_m"] = stats(-2, 0.012, 0.0, 1.234, 2, 12);
  a["pitch_deg_per_m"] = stats(-2, -0.021, 0.0, 0.987, 2, 12);
  a["yaw_deg_per_m"] = stats(-1, 0.003, 0.0, 0.321, 1, 12);
  a["max_abs_deg"] = {{"roll", 12.345}, {"pitch", 23.456}, {"yaw", 3.0}};
  const std::string with = river_paper_side_by_side(as_record(m), RiverPaperTrack::kDischarge);
  EXPECT_NE(with.find("| e'_roll, AHRS − VO (deg/m), mean (SD) | 0.000 (1.250) | 0.012 (1.234) |"),
            std::string::npos)
      << with;
  EXPECT_NE(
      with.find("| e'_pitch, AHRS − VO (deg/m), mean (SD) | -0.010 (1.390) | -0.021 (0.987) |"),
      std::string::npos);
  EXPECT_NE(with.find("| pitch | 17.78 | 23.46 | 45.48 |"), std::string::npos) << with;
  EXPECT_NE(with.find("| roll | 13.88 | 12.35 | 40.56 |"), std::string::npos) << with;
  // The exact rows stay as they were.
  EXPECT_NE(with.find("| e'_roll (deg/m), mean (SD) | 0.000 (1.250) | 0.004 (0.050) |"),
            std::string::npos);
  // The total trajectory has no maxima in the paper.
  EXPECT_EQ(river_paper_side_by_side(as_record(m), RiverPaperTrack::kTotal).find("| pitch | 17.78"),
            std::string::npos);
}

// A run whose truth is a point away from the camera (eval.reference_point_m) says so; one
// measured at the camera, or from before the key existed, says nothing.
TEST(PaperCompare, SaysWhereTheTruthWasMeasuredWhenNotAtTheCamera) {
  nlohmann::json m;
  m["scenario"] = "river_survey";
  m["algorithms"]["sparse"] = algorithm(0.0456, 0.001);
  const std::string old_run = river_paper_side_by_side(as_record(m), RiverPaperTrack::kTotal);
  m["algorithms"]["sparse"]["association"]["reference_point_m"] = {0.0, 0.0, 0.0};
  const std::string at_camera = river_paper_side_by_side(as_record(m), RiverPaperTrack::kTotal);
  EXPECT_EQ(old_run, at_camera);
  EXPECT_EQ(at_camera.find("truth is measured"), std::string::npos);
  m["algorithms"]["sparse"]["association"]["reference_point_m"] = {-0.3, -0.4, 1.2};
  const std::string prism = river_paper_side_by_side(as_record(m), RiverPaperTrack::kTotal);
  EXPECT_NE(
      prism.find("The twin's truth is measured 1.30 m from its camera, at [-0.3, -0.4, 1.2] m"),
      std::string::npos)
      << prism;
}

// With each VO also measured at the prism (`driftlab paper` adds "NAME (prism)"), its column
// stands beside the camera's, in the VO's own group, and the findings name both.
TEST(PaperCompare, TheTwinAtTheCameraAndAtThePrismSideBySide) {
  nlohmann::json m;
  m["scenario"] = "river_survey";
  m["algorithms"]["sparse"] = algorithm(0.0041, 0.6);
  m["algorithms"]["sparse (prism)"] = algorithm(0.0780, 0.001);
  m["algorithms"]["sparse (prism)"]["association"]["reference_point_m"] = {-0.35, -0.55, 0.606};
  m["algorithms"]["dense"] = algorithm(0.0082, 0.5);
  m["algorithms"]["dense (prism)"] = algorithm(0.0800, 0.002);
  const std::string md = river_paper_side_by_side(as_record(m), RiverPaperTrack::kTotal);
  EXPECT_NE(md.find("| paper sparse | twin sparse | twin sparse (prism) | paper dense | twin dense "
                    "| twin dense (prism) |"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("| Mean | 0.067 | 0.004 | 0.078 | 0.177 | 0.008 | 0.080 |"), std::string::npos)
      << md;
  EXPECT_NE(md.find("In the (prism) columns the truth is measured 0.89 m from its camera, at "
                    "[-0.35, -0.55, 0.606] m"),
            std::string::npos)
      << md;
  EXPECT_EQ(md.find("The twin's truth is measured"), std::string::npos);
  EXPECT_NE(md.find("- sparse (prism) (Table 3): paper finds h and d significant; twin: h "
                    "significant"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("- sparse (Table 3): paper finds h and d significant; twin: h not significant"),
            std::string::npos)
      << md;
}

TEST(PaperCompare, TracksOfTheTwinScenariosAndARunWithoutTheAlgorithms) {
  EXPECT_EQ(river_paper_track_of("river_crossing"), RiverPaperTrack::kDischarge);
  EXPECT_EQ(river_paper_track_of("river_survey"), RiverPaperTrack::kTotal);
  EXPECT_FALSE(river_paper_track_of("basin_exp1").has_value());
  nlohmann::json m;
  m["algorithms"]["pnp"] = algorithm(0.1, 0.1);
  try {
    river_paper_side_by_side(as_record(m), RiverPaperTrack::kTotal);
    FAIL();
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("none of the algorithms sparse, sparse_kf and dense"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace driftlab::report
