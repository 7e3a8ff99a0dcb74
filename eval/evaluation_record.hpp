// What one evaluation reports (metrics.json algorithms.NAME): typed records, each field listed
// once in its visit(), which writes it (core/record_json.hpp), reads it back and documents it
// (docs/metrics-reference.md). eval::evaluation_record() fills it from an Evaluation.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace driftlab::eval {

/// A statistic a record holds before it is measured (or where an older metrics.json lacks
/// it): null in metrics.json, never mistaken for an error of 0.
inline constexpr double kUnmeasured = std::numeric_limits<double>::quiet_NaN();

/// What every summary of values reports: count, extremes, mean, median and RMS.
struct CommonStats {
  std::size_t n = 0;
  double min = kUnmeasured, max = kUnmeasured, mean = kUnmeasured, median = kUnmeasured,
         rmse = kUnmeasured;
  template <class A>
  void visit(A& a) {
    a("n", n, "values");
    a("min", min, "smallest");
    a("max", max, "largest");
    a("mean", mean, "mean");
    a("median", median, "median");
    a("rmse", rmse, "root mean square");
  }
};

/// Statistics of errors over poses or pairs, with the population SD (as evo).
struct ErrorStats : CommonStats {
  double sd_population = kUnmeasured;
  template <class A>
  void visit(A& a) {
    CommonStats::visit(a);
    a("std", sd_population, "standard deviation of the population (divides by n)");
  }
};

/// Statistics over sections or runs, with the sample SD (as the papers' tables).
struct SampleStats : CommonStats {
  double sd = kUnmeasured;
  template <class A>
  void visit(A& a) {
    CommonStats::visit(a);
    a("sd", sd, "sample standard deviation (divides by n - 1; 0 when n < 2)");
  }
};

struct AssociationRecord {
  std::size_t pairs = 0, gt_poses = 0, est_poses = 0;
  double max_diff_s = 0;
  std::array<double, 3> reference_point_m{0, 0, 0};
  template <class A>
  void visit(A& a) {
    a("pairs", pairs, "estimate poses paired with a ground-truth pose");
    a("gt_poses", gt_poses, "ground-truth poses");
    a("est_poses", est_poses, "estimate poses");
    a("max_diff_s", max_diff_s,
      "largest stamp difference of a pair (eval.association_tolerance_s) [s]");
    a("reference_point_m", reference_point_m,
      "where on the vessel the truth was measured, in the camera frame (eval.reference_point_m, "
      "--reference-point; [0, 0, 0]: the camera) [m]");
  }
};

struct AlignmentRecord {
  std::string method;
  int first_n = 0;
  std::array<std::array<double, 3>, 3> rotation{};
  std::array<double, 3> translation_m{0, 0, 0};
  double scale = 1;
  template <class A>
  void visit(A& a) {
    a("method", method, "eval.align: horn, se3, sim3, pos_yaw or none");
    a("first_n", first_n, "aligned on the first N poses only (0: the whole track)");
    a("rotation", rotation, "R of the alignment, rows");
    a("translation_m", translation_m, "t of the alignment [m]");
    a("scale", scale, "s of the alignment (1 unless sim3)");
  }
};

/// A rotation and a translation error's statistics.
struct PoseErrorStats {
  ErrorStats trans_m, rot_deg;
  template <class A>
  void visit(A& a) {
    a("trans_m", trans_m, "translation error [m]");
    a("rot_deg", rot_deg, "rotation error [deg]");
  }
};

struct RpeRecord {
  double delta = 1;
  std::string unit;
  std::size_t pairs = 0;
  PoseErrorStats errors;
  template <class A>
  void visit(A& a) {
    a("delta", delta, "step between the poses of a pair, in `unit`");
    a("unit", unit, "frames or meters");
    a("pairs", pairs, "pose pairs");
    errors.visit(a);
  }
};

/// The track's absolute position errors after alignment, and its length.
struct TrackRecord {
  std::size_t n = 0;
  double rmse_3d_m = kUnmeasured, max_3d_m = kUnmeasured, rmse_2d_m = kUnmeasured,
         max_2d_m = kUnmeasured;
  double rmse_3d_pct = kUnmeasured, max_3d_pct = kUnmeasured, rmse_2d_pct = kUnmeasured,
         max_2d_pct = kUnmeasured;
  double length_gt_m = kUnmeasured, length_est_m = kUnmeasured, length_error_pct = kUnmeasured;
  template <class A>
  void visit(A& a) {
    a("n", n, "poses");
    a("rmse_3d_m", rmse_3d_m, "3D position error, RMS [m]");
    a("max_3d_m", max_3d_m, "3D position error, largest [m]");
    a("rmse_2d_m", rmse_2d_m, "horizontal position error, RMS [m]");
    a("max_2d_m", max_2d_m, "horizontal position error, largest [m]");
    a("rmse_3d_pct", rmse_3d_pct, "rmse_3d_m over the track's length [%]");
    a("max_3d_pct", max_3d_pct, "max_3d_m over the track's length [%]");
    a("rmse_2d_pct", rmse_2d_pct, "rmse_2d_m over the track's length [%]");
    a("max_2d_pct", max_2d_pct, "max_2d_m over the track's length [%]");
    a("length_gt_m", length_gt_m, "the true track's length [m]");
    a("length_est_m", length_est_m, "the estimate's length through the same poses [m]");
    a("length_error_pct", length_error_pct, "(estimate - truth) / truth [%]: > 0 over-estimates");
  }
};

/// River paper Table 1's rows: errors over displacement, over sections.
struct Table1Rows {
  SampleStats p_m_per_m, x_m_per_m, y_m_per_m, z_m_per_m;
  SampleStats roll_deg_per_m, pitch_deg_per_m, yaw_deg_per_m;
  template <class A>
  void visit(A& a) {
    a("p_m_per_m", p_m_per_m, "position error over displacement, Eq. (12) [m/m]");
    a("x_m_per_m", x_m_per_m, "along the optical axis [m/m]");
    a("y_m_per_m", y_m_per_m, "to the right [m/m]");
    a("z_m_per_m", z_m_per_m, "down [m/m]");
    a("roll_deg_per_m", roll_deg_per_m, "roll error over displacement, exact [deg/m]");
    a("pitch_deg_per_m", pitch_deg_per_m, "pitch error over displacement, exact [deg/m]");
    a("yaw_deg_per_m", yaw_deg_per_m, "yaw error over displacement, exact [deg/m]");
  }
};

/// Table 1 over the sections without a frame where the VO lost track.
struct TrackedSections {
  std::size_t count = 0;
  Table1Rows rows;
  template <class A>
  void visit(A& a) {
    a("count", count, "sections");
    rows.visit(a);
  }
};

struct SectionsRecord {
  double section_length_m = 0;
  std::size_t count = 0;
  Table1Rows rows;
  std::optional<std::vector<std::size_t>> with_lost_track;
  std::optional<TrackedSections> tracked;
  template <class A>
  void visit(A& a) {
    a("section_length_m", section_length_m, "length of a section (river paper Section 2.4) [m]");
    a("count", count, "sections");
    rows.visit(a);
    a("with_lost_track", with_lost_track,
      "with a `lost` column in the frame table (every run has one): the index of each section "
      "holding a frame where the VO lost track");
    a("tracked", tracked,
      "Table 1 without those sections (the report adds that row, and a warning says how much "
      "the lost stretches move the mean)");
  }
};

struct EulerDeg {
  double roll = 0, pitch = 0, yaw = 0;
  template <class A>
  void visit(A& a) {
    a("roll", roll, "[deg]");
    a("pitch", pitch, "[deg]");
    a("yaw", yaw, "[deg]");
  }
};

/// Table 1's angle rows as the river paper computed them, against its AHRS (Eq. (11)).
struct PaperAttitudeRecord {
  std::string reference = "ahrs";
  std::size_t pairs = 0;
  SampleStats roll_deg_per_m, pitch_deg_per_m, yaw_deg_per_m;
  EulerDeg max_abs_deg;
  template <class A>
  void visit(A& a) {
    a("reference", reference, "the attitude reference (the simulated x-IMU's AHRS)");
    a("pairs", pairs, "estimate poses with a reference sample within the tolerance");
    a("roll_deg_per_m", roll_deg_per_m, "AHRS - VO roll over displacement [deg/m]");
    a("pitch_deg_per_m", pitch_deg_per_m, "AHRS - VO pitch over displacement [deg/m]");
    a("yaw_deg_per_m", yaw_deg_per_m, "AHRS - VO yaw over displacement [deg/m]");
    a("max_abs_deg", max_abs_deg, "largest angle error along the track (Section 3.2's maxima)");
  }
};

struct CoefficientRecord {
  double estimate = kUnmeasured, std_error = kUnmeasured, t = kUnmeasured, p = kUnmeasured,
         vif = kUnmeasured;
  bool significant = false;
  template <class A>
  void visit(A& a) {
    a("estimate", estimate, "beta");
    a("std_error", std_error, "its standard error");
    a("t", t, "estimate / std_error");
    a("p", p, "two-sided p of the t test");
    a("vif", vif, "variance inflation factor (0 for the intercept)");
    a("significant", significant, "p < alpha");
  }
};

struct DiagnosticsRecord {
  double jarque_bera = kUnmeasured, jarque_bera_p = kUnmeasured, shapiro_wilk_w = kUnmeasured,
         shapiro_wilk_p = kUnmeasured;
  double breusch_pagan_lm = kUnmeasured, breusch_pagan_p = kUnmeasured, durbin_watson = kUnmeasured,
         max_vif = kUnmeasured;
  template <class A>
  void visit(A& a) {
    a("jarque_bera", jarque_bera, "Jarque-Bera statistic of the residuals");
    a("jarque_bera_p", jarque_bera_p, "its p");
    a("shapiro_wilk_w", shapiro_wilk_w, "Shapiro-Wilk W of the residuals");
    a("shapiro_wilk_p", shapiro_wilk_p, "its p");
    a("breusch_pagan_lm", breusch_pagan_lm, "Koenker's Breusch-Pagan LM (heteroscedasticity)");
    a("breusch_pagan_p", breusch_pagan_p, "its p");
    a("durbin_watson", durbin_watson, "Durbin-Watson of the residuals in section order");
    a("max_vif", max_vif, "largest variance inflation factor");
  }
};

/// River paper Table 3: e'_p regressed on the covariates; `skipped` alone when not run.
struct RegressionRecord {
  std::optional<std::size_t> n;
  std::optional<double> r2, adj_r2, f, f_p, sigma;
  std::optional<std::map<std::string, CoefficientRecord>> coefficients;
  std::optional<DiagnosticsRecord> diagnostics;
  std::optional<std::vector<std::string>> warnings;
  std::optional<std::string> skipped;
  template <class A>
  void visit(A& a) {
    a("n", n, "sections regressed");
    a("r2", r2, "R^2");
    a("adj_r2", adj_r2, "adjusted R^2");
    a("f", f, "F statistic");
    a("f_p", f_p, "its p");
    a("sigma", sigma, "residual standard deviation [m/m]");
    a("coefficients", coefficients, "each covariate's coefficient (and the intercept)");
    a("diagnostics", diagnostics, "tests of the model's assumptions");
    a("warnings", warnings, "what the diagnostics flag");
    a("skipped", skipped, "why the regression was not run");
  }
};

struct BasinRow {
  double rmse = kUnmeasured, sd = kUnmeasured;
  std::size_t n = 0;
  template <class A>
  void visit(A& a) {
    a("rmse", rmse, "RMS error");
    a("sd", sd, "sample standard deviation of the error");
    a("n", n, "samples");
  }
};

/// Basin paper Table 2's rows.
struct BasinRows {
  BasinRow north_m, east_m, surge_m_s, sway_m_s, heading_deg;
  template <class A>
  void visit(A& a) {
    a("north_m", north_m, "north position [m]");
    a("east_m", east_m, "east position [m]");
    a("surge_m_s", surge_m_s, "surge speed [m/s]");
    a("sway_m_s", sway_m_s, "sway speed [m/s]");
    a("heading_deg", heading_deg, "heading [deg]");
  }
};

/// Basin paper Table 2 against a second reference (the basin's overhead camera).
struct BasinReferenceRecord {
  BasinRows rows;
  std::string reference;
  std::size_t pairs = 0;
  template <class A>
  void visit(A& a) {
    rows.visit(a);
    a("reference", reference, "the reference's name");
    a("pairs", pairs, "estimate poses with a reference sample within the tolerance");
  }
};

struct KittiRecord {
  double length_m = kUnmeasured;
  std::size_t count = 0;
  double trans_err_pct = kUnmeasured, rot_err_deg_per_100m = kUnmeasured;
  template <class A>
  void visit(A& a) {
    a("length_m", length_m, "segment length (0: the average over all lengths) [m]");
    a("count", count, "segments");
    a("trans_err_pct", trans_err_pct, "mean translation error over length [%]");
    a("rot_err_deg_per_100m", rot_err_deg_per_100m, "mean rotation error over length [deg/100 m]");
  }
};

/// One estimate against ground truth.
struct EvaluationRecord {
  std::string algorithm;
  AssociationRecord association;
  AlignmentRecord alignment;
  PoseErrorStats ape;
  RpeRecord rpe;
  TrackRecord track;
  std::map<std::string, TrackRecord> subtracks;
  SectionsRecord sections;
  std::optional<PaperAttitudeRecord> paper_attitude;
  std::map<std::string, SampleStats> covariates;
  RegressionRecord regression;
  BasinRows basin;
  std::optional<BasinReferenceRecord> basin_overhead;
  std::vector<KittiRecord> kitti;
  std::vector<std::string> warnings;
  template <class A>
  void visit(A& a) {
    a("algorithm", algorithm, "the track's name");
    a("association", association, "estimate poses paired with ground truth by stamp");
    a("alignment", alignment, "the transform applied before the absolute errors");
    a("ape", ape, "absolute pose error after alignment");
    a("rpe", rpe, "relative pose error (no alignment)");
    a("track", track, "absolute position errors and length");
    a("subtracks", subtracks, "`track` over each eval.subtracks span, aligned on its own");
    a("sections", sections, "river paper Table 1 over sections of the true track");
    a("paper_attitude", paper_attitude, "Table 1's angle rows as the paper computed them");
    a("covariates", covariates, "river paper Table 4: each covariate over the sections");
    a("regression", regression, "river paper Table 3");
    a("basin", basin, "basin paper Table 2 against the simulated truth");
    a("basin_overhead", basin_overhead, "basin paper Table 2 against the overhead camera");
    a("kitti", kitti, "KITTI segment errors");
    a("warnings", warnings, "what made a number doubtful or absent");
  }
};

}  // namespace driftlab::eval
