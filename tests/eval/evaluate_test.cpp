#include "eval/evaluate.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/error.hpp"
#include "core/rotation.hpp"
#include "eval/sections.hpp"

namespace driftlab::eval {
namespace {

// A serpentine survey: camera level, heading changing smoothly, 0.5 m steps
// every 0.5 s, 400 poses (~200 m).
Trajectory serpentine() {
  Trajectory t;
  Vec3 p(0, 0, 0);
  double heading = 0;
  for (int i = 0; i < 400; ++i) {
    heading = 0.8 * std::sin(i * 0.02);
    const Mat3 R_W_F = Eigen::AngleAxisd(heading, Vec3::UnitZ()).toRotationMatrix();
    t.push_back(
        {static_cast<TimeNs>(i) * 500'000'000, SE3(Mat3(R_W_F * R_optical_frd().transpose()), p)});
    p += R_W_F * Vec3(0.5, 0, 0);
    p.z() = 0.05 * std::sin(i * 0.3);  // a little heave
  }
  return t;
}

EvaluationInput input_with(const Trajectory& gt, const Trajectory& est) {
  EvaluationInput in;
  in.gt = gt;
  in.est = est;
  in.algorithm = "test";
  return in;
}

TEST(Evaluate, RigidlyMovedEstimateHasZeroErrorAfterHornAlignment) {
  const Trajectory gt = serpentine();
  const SE3 T(quat_from_euler_zyx({0.1, -0.2, 1.0}), Vec3(5, -3, 2));
  Trajectory est = gt;
  for (auto& p : est) p.T_W_C = T * p.T_W_C;
  const Evaluation e = evaluate(input_with(gt, est));
  EXPECT_EQ(e.association.size(), 400u);
  EXPECT_LT(e.ape.trans_m.rmse, 1e-9);
  EXPECT_LT(e.ape.rot_deg.max, 1e-7);
  EXPECT_LT(e.track.max_3d_m, 1e-9);
  EXPECT_NEAR(e.track.length_error_pct, 0.0, 1e-9);
  ASSERT_GT(e.sections.size(), 25u);
  EXPECT_LT(e.section_summary.p_m_per_m.max, 1e-9);
  EXPECT_LT(std::abs(e.section_summary.yaw_deg_per_m.max), 1e-7);
  // The alignment recovered the inverse of T.
  EXPECT_LT((e.alignment.R - T.rotation().transpose()).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(Evaluate, ScaledEstimateGivesItsScaleErrorPerMetreAndSim3UndoesIt) {
  const Trajectory gt = serpentine();
  Trajectory est = gt;
  for (auto& p : est) p.T_W_C = SE3(p.T_W_C.quaternion(), 1.05 * p.T_W_C.translation());
  EvaluationInput in = input_with(gt, est);
  in.options.align = Alignment::kSim3;
  const Evaluation e = evaluate(in);
  EXPECT_NEAR(e.alignment.scale, 1 / 1.05, 1e-9);
  EXPECT_LT(e.ape.trans_m.rmse, 1e-9);
  // Every section's relative translation is 5% long: the error is 5% of the
  // straight-line displacement over the section (the chord), divided by the
  // section's path length (the arc).
  ASSERT_GT(e.sections.size(), 25u);
  for (const auto& sec : e.sections) {
    const double chord =
        (gt[sec.last].T_W_C.translation() - gt[sec.first].T_W_C.translation()).norm();
    EXPECT_NEAR(sec.err_p_m, 0.05 * chord, 1e-9);
  }
  EXPECT_LE(e.section_summary.p_m_per_m.max, 0.05);
  EXPECT_NEAR(e.track.length_error_pct, 0.0, 1e-9);  // measured after alignment
}

TEST(Evaluate, JsonHasTheDocumentedKeysAndNoNonFiniteNumbers) {
  const Trajectory gt = serpentine();
  Trajectory est = gt;
  for (std::size_t i = 0; i < est.size(); ++i)
    est[i].T_W_C =
        SE3(est[i].T_W_C.quaternion(), est[i].T_W_C.translation() + Vec3(0.001 * i, 0, 0));
  EvaluationInput in = input_with(gt, est);
  in.options.subtracks.push_back({"first_minute", 0, 60});
  const Evaluation e = evaluate(in);
  const nlohmann::json j = to_json(e, in.options);
  for (const char* key : {"rmse", "mean", "median", "std", "min", "max"})
    EXPECT_TRUE(j["ape"]["trans_m"][key].is_number()) << key;
  for (const char* key : {"min", "mean", "median", "sd", "max", "n"})
    EXPECT_TRUE(j["sections"]["p_m_per_m"][key].is_number()) << key;
  for (const char* key : {"x_m_per_m", "y_m_per_m", "z_m_per_m", "roll_deg_per_m",
                          "pitch_deg_per_m", "yaw_deg_per_m"})
    EXPECT_TRUE(j["sections"].contains(key)) << key;
  for (const char* key : {"rmse_3d_m", "rmse_2d_m", "max_3d_m", "max_2d_m", "rmse_3d_pct"})
    EXPECT_TRUE(j["track"][key].is_number()) << key;
  EXPECT_TRUE(j["subtracks"].contains("first_minute"));
  // Without per-frame covariates f and d are missing: the regression says so.
  EXPECT_NE(j["regression"]["skipped"].get<std::string>().find("f, d not available"),
            std::string::npos)
      << j["regression"].dump();
  EXPECT_EQ(j.dump().find("NaN"), std::string::npos);
  EXPECT_FALSE(tables_markdown(e, in.options).empty());
  EXPECT_NE(sections_csv(e).find("algorithm,index,t_start_s"), std::string::npos);
}

TEST(Evaluate, RegressionRecoversAKnownDependence) {
  // A straight track of 0.5 m steps: sections are exactly 13 steps (6.5 m).
  // Section j runs at speed v_j and the estimate over-measures each of its
  // steps by the fraction c * v_j, so e'_p = c * v exactly: OLS must find
  // slope c, intercept 0 and R^2 = 1.
  const double c = 0.04;
  const double speeds[] = {0.25, 0.5, 1.0, 0.125, 0.2};  // exact step times in ns
  Trajectory gt, est;
  TimeNs t = 0;
  Vec3 p_gt(0, 0, 0), p_est(0, 0, 0);
  const SE3 level(Mat3(R_optical_frd().transpose()), Vec3::Zero());
  for (int i = 0; i <= 13 * 20; ++i) {
    gt.push_back({t, SE3(level.quaternion(), p_gt)});
    est.push_back({t, SE3(level.quaternion(), p_est)});
    const double v = speeds[(i / 13) % 5];
    t += seconds_to_ns(0.5 / v);
    p_gt.x() += 0.5;
    p_est.x() += 0.5 * (1 + c * v);
  }
  EvaluationInput in = input_with(gt, est);
  in.options.regression_covariates = {"v"};
  in.options.align = Alignment::kNone;
  const Evaluation e = evaluate(in);
  ASSERT_EQ(e.sections.size(), 20u);
  ASSERT_TRUE(e.regression.has_value()) << e.regression_skipped;
  const OlsResult& r = *e.regression;
  ASSERT_EQ(r.coefficients.size(), 2u);
  EXPECT_NEAR(r.coefficients[0].estimate, 0.0, 1e-12);
  EXPECT_NEAR(r.coefficients[1].estimate, c, 1e-12);
  EXPECT_NEAR(r.r2, 1.0, 1e-12);
  EXPECT_EQ(to_json(e, in.options).dump().find("NaN"), std::string::npos);
}

TEST(Evaluate, ShortTrackHasNoSectionsButValidOutput) {
  Trajectory gt = serpentine();
  gt.resize(5);  // 2 m: shorter than one 6.5 m section
  const Evaluation e = evaluate(input_with(gt, gt));
  EXPECT_TRUE(e.sections.empty());
  EXPECT_FALSE(e.regression.has_value());
  EXPECT_FALSE(e.warnings.empty());
  EXPECT_EQ(to_json(e, {}).dump().find("NaN"), std::string::npos);
}

TEST(Evaluate, NonFiniteValuesBecomeNullWithAWarning) {
  Evaluation e;
  e.ape.trans_m.rmse = std::numeric_limits<double>::quiet_NaN();
  const nlohmann::json j = to_json(e, {});
  EXPECT_TRUE(j["ape"]["trans_m"]["rmse"].is_null());
  bool warned = false;
  for (const auto& w : j["warnings"])
    warned = warned || w.get<std::string>().find("ape.trans_m.rmse") != std::string::npos;
  EXPECT_TRUE(warned);
}

TEST(Evaluate, BadInputIsAClearError) {
  const Trajectory gt = serpentine();
  Trajectory later = gt;
  for (auto& p : later) p.t_ns += 1'000'000'000'000;
  EXPECT_THROW(evaluate(input_with(gt, later)), UserError);  // no overlap
  Trajectory unsorted = gt;
  std::swap(unsorted[3], unsorted[4]);
  EXPECT_THROW(evaluate(input_with(unsorted, gt)), UserError);
  EvaluationInput bad = input_with(gt, gt);
  bad.options.section_length_m = -1;
  EXPECT_THROW(evaluate(bad), UserError);
}

}  // namespace
}  // namespace driftlab::eval
