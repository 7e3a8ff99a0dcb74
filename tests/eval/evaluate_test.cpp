#include "eval/evaluate.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

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
  EvaluationInput in = input_with(gt, est);
  in.options.align = Alignment::kHorn;  // a run's default is none: its estimates are anchored
  const Evaluation e = evaluate(in);
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

// The river paper's truth came from a prism the total station tracked, the estimate from the
// camera. With the truth moved 0.8 m ahead of a level camera (eval.reference_point_m) and a
// perfect estimate, a section's error is the lever arm's turn, (R_end - R_start) l: of length
// 2 |l| sin(dpsi / 2) for a heading change dpsi; with the default (the camera) it is zero.
TEST(Evaluate, ReferencePointAwayFromTheCameraTurnsHeadingChangesIntoSectionErrors) {
  const Trajectory gt = serpentine();
  EvaluationInput in = input_with(gt, gt);
  const Evaluation exact = evaluate(in);
  ASSERT_GT(exact.sections.size(), 25u);
  EXPECT_LT(exact.section_summary.p_m_per_m.max, 1e-9);
  in.options.reference_point_m = {0.0, 0.0, 0.8};
  const Evaluation e = evaluate(in);
  ASSERT_GT(e.sections.size(), 25u);
  double largest = 0;
  for (const auto& sec : e.sections) {
    const double dpsi =
        angle_between(gt[sec.first].T_W_C.quaternion(), gt[sec.last].T_W_C.quaternion());
    EXPECT_NEAR(sec.err_p_m, 2 * 0.8 * std::sin(dpsi / 2), 1e-9) << "section " << sec.index;
    EXPECT_NEAR(sec.err_rad.yaw_rad, 0.0, 1e-9);
    largest = std::max(largest, sec.err_p_m);
  }
  EXPECT_GT(largest, 0.1);  // the serpentine turns enough for the lever arm to show
  // The truth's positions moved, its orientations did not: the track is the prism's.
  EXPECT_NEAR(e.ape.rot_deg.max, 0.0, 1e-7);
  EXPECT_GT(e.ape.trans_m.max, 0.1);
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
  EXPECT_EQ(j["association"]["reference_point_m"], nlohmann::json::array({0.0, 0.0, 0.0}));
  // Without per-frame covariates f and d are missing: the regression says so.
  EXPECT_NE(j["regression"]["skipped"].get<std::string>().find("f, d not available"),
            std::string::npos)
      << j["regression"].dump();
  EXPECT_EQ(j.dump().find("NaN"), std::string::npos);
  EXPECT_FALSE(tables_markdown(e, in.options).empty());
  EXPECT_NE(sections_csv(e).find("algorithm,index,t_start_s"), std::string::npos);
}

// A VO that lost track for frames 101..110 gave no motion there: its estimate stands still
// at frame 100's pose and then goes on exactly, displaced. The sections whose frames include
// a lost one are marked; every other section is exact, so Table 1 without them is zero.
TEST(Evaluate, SectionsWhereTheVoLostTrackAreMarkedNotAveragedThroughUnseen) {
  const Trajectory gt = serpentine();
  Trajectory est = gt;
  const SE3 shift = gt[100].T_W_C * gt[110].T_W_C.inverse();
  for (std::size_t i = 101; i < est.size(); ++i)
    est[i].T_W_C = i <= 110 ? gt[100].T_W_C : shift * gt[i].T_W_C;
  EvaluationInput in = input_with(gt, est);
  FrameTable frames;
  frames.names = {"lost"};
  frames.columns.resize(1);
  for (std::size_t i = 0; i < gt.size(); ++i) {
    frames.t_ns.push_back(gt[i].t_ns);
    frames.columns[0].push_back(i >= 101 && i <= 110 ? 1.0 : 0.0);
  }
  in.frames = frames;
  const Evaluation e = evaluate(in);
  ASSERT_GT(e.sections.size(), 25u);
  std::vector<std::size_t> expected;  // sections whose first..last frames include 101..110
  double sum_all = 0;
  for (const auto& sec : e.sections) {
    sum_all += sec.per_m(sec.err_p_m);
    if (sec.last >= 101 && sec.first <= 110) {
      expected.push_back(sec.index);
    } else {
      EXPECT_LT(sec.err_p_m, 1e-9) << "section " << sec.index;
    }
  }
  EXPECT_EQ(e.lost_track_sections, expected);
  ASSERT_GE(expected.size(), 1u);
  ASSERT_TRUE(e.tracked_summary);
  EXPECT_EQ(e.tracked_summary->p_m_per_m.n, e.sections.size() - expected.size());
  EXPECT_LT(e.tracked_summary->p_m_per_m.max, 1e-9);
  EXPECT_NEAR(e.section_summary.p_m_per_m.mean, sum_all / e.sections.size(), 1e-12);
  EXPECT_GT(e.section_summary.p_m_per_m.mean, 0.01);  // averaged through the lost stretch

  const nlohmann::json j = to_json(e, in.options);
  EXPECT_EQ(j["sections"]["with_lost_track"].get<std::vector<std::size_t>>(), expected);
  EXPECT_EQ(j["sections"]["tracked"]["count"], e.sections.size() - expected.size());
  EXPECT_LT(j["sections"]["tracked"]["p_m_per_m"]["max"].get<double>(), 1e-9);
  EXPECT_NE(
      tables_markdown(e, in.options)
          .find(fmt::format("without the {} sections where the VO lost track", expected.size())),
      std::string::npos);
  bool warned = false;
  for (const auto& w : e.warnings)
    warned = warned || w.find("sections hold frames where the VO lost track") != std::string::npos;
  EXPECT_TRUE(warned);

  // Without a lost frame nothing is marked and nothing is said.
  for (double& v : in.frames->columns[0]) v = 0.0;
  in.est = gt;
  const Evaluation clean = evaluate(in);
  EXPECT_TRUE(clean.lost_track_sections.empty());
  EXPECT_EQ(clean.tracked_summary->p_m_per_m.n, clean.sections.size());
  EXPECT_EQ(tables_markdown(clean, in.options).find("lost track"), std::string::npos);
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

namespace driftlab::eval {
namespace {

// A track with a known, constant orientation error: the estimate's positions are the truth's
// plus small zero-mean noise, its orientations the truth's turned by `R_err` (in the camera
// frame). The true APE rotation is then the angle of R_err at every pose.
struct KnownRotationError {
  Trajectory gt, est;
  double angle_deg;
};

KnownRotationError with_rotation_error(const std::vector<Vec3>& path, double noise_m) {
  KnownRotationError k;
  const Quat R_err(
      Eigen::AngleAxisd(4.0 * std::numbers::pi / 180.0, Vec3(0.3, 0.1, 1.0).normalized()));
  k.angle_deg = 4.0;
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, noise_m);
  for (std::size_t i = 0; i < path.size(); ++i) {
    const TimeNs t = static_cast<TimeNs>(i) * 100'000'000;
    const SE3 T_W_C(Quat::Identity(), path[i]);
    k.gt.push_back({t, T_W_C});
    const Vec3 p = path[i] + Vec3(noise(rng), noise(rng), noise(rng));
    k.est.push_back({t, SE3(T_W_C.quaternion() * R_err, p)});
  }
  return k;
}

std::vector<Vec3> straight_path() {  // 30 m along north, 1 mm of sideways wobble
  std::vector<Vec3> p;
  for (int i = 0; i < 300; ++i) p.emplace_back(0.1 * i, 0.001 * std::sin(0.3 * i), 0.0);
  return p;
}

std::vector<Vec3> back_and_forth_path() {  // four 20 m crossings on one line
  std::vector<Vec3> p;
  for (int i = 0; i < 800; ++i) {
    const double s = std::fmod(0.1 * i, 40.0);
    p.emplace_back(0.0, s <= 20.0 ? s : 40.0 - s, 0.002 * std::cos(0.2 * i));
  }
  return p;
}

std::vector<Vec3> planar_path() {  // a 20 m x 12 m lawnmower on flat water
  std::vector<Vec3> p;
  for (int leg = 0; leg < 4; ++leg)
    for (int i = 0; i < 100; ++i)
      p.emplace_back(leg % 2 == 0 ? 0.2 * i : 20.0 - 0.2 * i, 4.0 * leg, 0.0);
  return p;
}

std::vector<Vec3> positions_of(const Trajectory& tr) {
  std::vector<Vec3> p;
  for (const auto& s : tr) p.push_back(s.T_W_C.translation());
  return p;
}

double ape_rot_mean_deg(const KnownRotationError& k, Alignment method) {
  EvaluationInput in;
  in.gt = k.gt;
  in.est = k.est;
  in.algorithm = "test";
  in.options.align = method;
  return evaluate(in).ape.rot_deg.mean;
}

TEST(HonestAlignment, StraightTrackKeepsTheKnownRotationErrorAndWarns) {
  const KnownRotationError k = with_rotation_error(straight_path(), 0.01);
  for (Alignment m : {Alignment::kHorn, Alignment::kSe3, Alignment::kSim3, Alignment::kNone})
    EXPECT_NEAR(ape_rot_mean_deg(k, m), k.angle_deg, 0.05) << yaml::enum_name(m);
  // The plain fit turns the estimate about the track's axis to absorb the noise: the check
  // above would fail without the fallback.
  const SimilarityTransform raw =
      compute_alignment(Alignment::kHorn, positions_of(k.est), positions_of(k.gt));
  EXPECT_GT(Eigen::AngleAxisd(raw.R).angle() * 180.0 / std::numbers::pi, 1.0);
  EvaluationInput in;
  in.gt = k.gt;
  in.est = k.est;
  in.options.align = Alignment::kHorn;
  const Evaluation e = evaluate(in);
  ASSERT_FALSE(e.warnings.empty());
  EXPECT_NE(e.warnings.front().find("rotation about the track's axis is unobservable"),
            std::string::npos)
      << e.warnings.front();
}

TEST(HonestAlignment, BackAndForthTrackKeepsTheKnownRotationError) {
  const KnownRotationError k = with_rotation_error(back_and_forth_path(), 0.02);
  for (Alignment m : {Alignment::kHorn, Alignment::kSe3, Alignment::kSim3, Alignment::kNone})
    EXPECT_NEAR(ape_rot_mean_deg(k, m), k.angle_deg, 0.05) << yaml::enum_name(m);
}

TEST(HonestAlignment, PlanarTrackIsFullyObservableAndNeedsNoWarning) {
  const KnownRotationError k = with_rotation_error(planar_path(), 0.02);
  for (Alignment m : {Alignment::kHorn, Alignment::kSe3, Alignment::kSim3, Alignment::kNone})
    EXPECT_NEAR(ape_rot_mean_deg(k, m), k.angle_deg, 0.05) << yaml::enum_name(m);
  EvaluationInput in;
  in.gt = k.gt;
  in.est = k.est;
  in.options.align = Alignment::kHorn;
  EXPECT_TRUE(evaluate(in).warnings.empty());
}

TEST(HonestAlignment, BasinHeadingIsTheEstimatesOwnWhateverTheAlignment) {
  // A straight tow whose estimate heads 2 deg off the truth all along, and so runs 2 deg off
  // course: the heading RMSE of the basin table is 2 deg with any alignment, although the
  // alignments turn the positions back onto the truth (and the heading with them, before).
  std::vector<Vec3> path = straight_path();
  KnownRotationError k;
  const Mat3 off_course =
      Eigen::AngleAxisd(2.0 * std::numbers::pi / 180.0, Vec3::UnitZ()).toRotationMatrix();
  const Quat yaw_err(Eigen::AngleAxisd(2.0 * std::numbers::pi / 180.0, Vec3::UnitY()));
  for (std::size_t i = 0; i < path.size(); ++i) {
    const TimeNs t = static_cast<TimeNs>(i) * 100'000'000;
    // Camera optical frame looking north: z (optical axis) north, x east, y down.
    const Quat q_W_C(R_frd_optical());
    k.gt.push_back({t, SE3(q_W_C, path[i])});
    k.est.push_back({t, SE3(q_W_C * yaw_err, off_course * path[i])});
  }
  for (Alignment m : {Alignment::kHorn, Alignment::kPosYaw, Alignment::kNone}) {
    EvaluationInput in;
    in.gt = k.gt;
    in.est = k.est;
    in.options.align = m;
    EXPECT_NEAR(evaluate(in).basin.heading_deg.rmse, 2.0, 1e-6) << yaml::enum_name(m);
  }
}

}  // namespace
}  // namespace driftlab::eval
