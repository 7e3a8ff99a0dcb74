// The river paper's attitude comparison (Eq. (11)) against closed forms: a camera pitched down
// by alpha on a hull that turns about the vertical shows, in its first frame's Euler angles, a
// pitch of asin(sin(alpha) cos(alpha) (1 - cos(psi))) and a roll of
// atan2(sin(alpha) sin(psi), sin^2(alpha) cos(psi) + cos^2(alpha)) after a turn by psi (the
// ZYX angles of Ry(alpha) Rz(psi) Ry(-alpha), written out by hand), though the VO is exact
// and the hull never pitches or rolls; a level camera shows none.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/rotation.hpp"
#include "eval/evaluate.hpp"
#include "eval/paper_attitude.hpp"
#include "eval/sections.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab::eval::paper_attitude_test {
namespace {

using driftlab::test::kDeg;

struct Turn {
  std::vector<TimeNs> t_ns;
  std::vector<SE3> T_W_C;  // optical frame, exact
  AttitudeReference hull;  // the hull's exact ZYX angles
  std::vector<double> psi;
};

// The hull turns in place from heading 0 to `total` while creeping north at 0.1 m per step;
// the camera looks along the bow, pitched down by `alpha` (FRD pitch -alpha).
Turn turn(double alpha, double total, int steps) {
  Turn t;
  for (int k = 0; k <= steps; ++k) {
    const double psi = total * k / steps;
    const Mat3 R_W_B = Eigen::AngleAxisd(psi, Vec3::UnitZ()).toRotationMatrix();
    const Mat3 R_B_Cfrd = Eigen::AngleAxisd(-alpha, Vec3::UnitY()).toRotationMatrix();
    t.t_ns.push_back(static_cast<TimeNs>(k) * 100'000'000);
    t.T_W_C.push_back(SE3(Quat(R_W_B * R_B_Cfrd * R_frd_optical()), Vec3(0.1 * k, 0, 0)));
    t.hull.t_ns.push_back(t.t_ns.back());
    t.hull.euler.push_back({0.0, 0.0, wrap_angle_rad(psi)});
    t.psi.push_back(psi);
  }
  return t;
}

TEST(PaperAttitude, ATiltedCameraTurnsYawIntoPitchAndRollAsInClosedForm) {
  const double alpha = 9 * kDeg;
  const Turn t = turn(alpha, 180 * kDeg, 180);
  const PaperAttitude a = paper_attitude(t.t_ns, t.T_W_C, {}, t.hull, 1'000'000);
  EXPECT_EQ(a.pairs, t.t_ns.size());
  const double s = std::sin(alpha), c = std::cos(alpha);
  double max_pitch = 0, max_roll = 0;
  for (double psi : t.psi) {
    max_pitch = std::max(max_pitch, std::abs(std::asin(s * c * (1 - std::cos(psi)))));
    max_roll =
        std::max(max_roll, std::abs(std::atan2(s * std::sin(psi), s * s * std::cos(psi) + c * c)));
  }
  EXPECT_NEAR(max_pitch, 2 * alpha, 1e-12);  // after the half turn: asin(sin 2 alpha)
  EXPECT_NEAR(a.max_abs_rad.pitch_rad, max_pitch, 1e-9);
  EXPECT_NEAR(a.max_abs_rad.roll_rad, max_roll, 1e-9);
  EXPECT_GT(a.max_abs_rad.roll_rad, 0.9 * alpha);
}

TEST(PaperAttitude, SectionsTakeTheChangeOfTheErrorPerMetre) {
  const double alpha = 9 * kDeg;
  const Turn t = turn(alpha, 180 * kDeg, 180);
  // Two sections: poses 0-90 (a quarter turn, 9 m) and 90-180.
  std::vector<Section> sections(2);
  sections[0].first = 0;
  sections[0].last = 90;
  sections[0].length_m = 9.0;
  sections[1].first = 90;
  sections[1].last = 180;
  sections[1].length_m = 9.0;
  const PaperAttitude a = paper_attitude(t.t_ns, t.T_W_C, sections, t.hull, 1'000'000);
  ASSERT_EQ(a.pitch_deg_per_m.n, 2u);
  const double s = std::sin(alpha), c = std::cos(alpha);
  auto pitch_err = [&](double psi) { return std::asin(s * c * (1 - std::cos(psi))); };
  const double first = (pitch_err(90 * kDeg) - pitch_err(0)) / kDeg / 9.0;
  const double second = (pitch_err(180 * kDeg) - pitch_err(90 * kDeg)) / kDeg / 9.0;
  EXPECT_NEAR(a.pitch_deg_per_m.mean, 0.5 * (first + second), 1e-9);
  EXPECT_NEAR(a.pitch_deg_per_m.max, std::max(first, second), 1e-9);
  // The half turn as a whole: the tilted frame's yaw is back at psi (Ry(alpha) Rz(pi)
  // Ry(-alpha) = Rz(pi) Ry(-2 alpha)), so the two sections' yaw errors cancel.
  EXPECT_NEAR(a.yaw_deg_per_m.mean, 0.0, 1e-9);
}

TEST(PaperAttitude, ALevelCameraOnAnExactVoShowsNoError) {
  const Turn t = turn(0.0, 270 * kDeg, 90);
  const PaperAttitude a = paper_attitude(t.t_ns, t.T_W_C, {}, t.hull, 1'000'000);
  EXPECT_LT(a.max_abs_rad.pitch_rad, 1e-12);
  EXPECT_LT(a.max_abs_rad.roll_rad, 1e-12);
  EXPECT_LT(a.max_abs_rad.yaw_rad, 1e-12);
}

TEST(PaperAttitude, FramesWithoutAReferenceSampleNearAreLeftOut) {
  Turn t = turn(0.0, 90 * kDeg, 10);
  t.hull.t_ns.resize(5);
  t.hull.euler.resize(5);
  const PaperAttitude a = paper_attitude(t.t_ns, t.T_W_C, {}, t.hull, 1'000'000);
  EXPECT_EQ(a.pairs, 5u);
}

TEST(PaperAttitude, ReadsAnAhrsCsvAndNamesWhatIsWrong) {
  const auto dir = std::filesystem::temp_directory_path();
  const auto good = dir / "driftlab_ahrs_good.csv";
  write_file_atomic(good, "t_ns,roll_deg,pitch_deg,yaw_deg\n0,1.5,-2,90\n7812500,0,0,-180\n");
  const AttitudeReference r = read_attitude_reference(good.string());
  ASSERT_EQ(r.t_ns.size(), 2u);
  EXPECT_EQ(r.t_ns[1], 7812500);
  EXPECT_NEAR(r.euler[0].roll_rad, 1.5 * kDeg, 1e-15);
  EXPECT_NEAR(r.euler[0].pitch_rad, -2 * kDeg, 1e-15);
  EXPECT_NEAR(r.euler[0].yaw_rad, 90 * kDeg, 1e-15);
  auto error_of = [&](const std::string& text) {
    const auto bad = dir / "driftlab_ahrs_bad.csv";
    write_file_atomic(bad, text);
    try {
      read_attitude_reference(bad.string());
    } catch (const UserError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error_of("t_ns,roll_deg,yaw_deg\n0,1,2\n").find("no column 'pitch_deg'"),
            std::string::npos);
  EXPECT_NE(error_of("t_ns,roll_deg,pitch_deg,yaw_deg\n0,1,2,3\n5,1,nan,3\n")
                .find("data row 2 (t_ns 5): pitch_deg is missing"),
            std::string::npos);
  EXPECT_NE(error_of("t_ns,roll_deg,pitch_deg,yaw_deg\n0,1,2,x\n").find("yaw_deg: got 'x'"),
            std::string::npos);
  std::filesystem::remove(good);
}

TEST(PaperAttitude, TheEvaluationCarriesItIntoMetricsWhenGivenAReference) {
  const Turn t = turn(9 * kDeg, 180 * kDeg, 180);
  EvaluationInput in;
  for (std::size_t k = 0; k < t.t_ns.size(); ++k) {
    in.gt.push_back({t.t_ns[k], t.T_W_C[k]});
    in.est.push_back({t.t_ns[k], t.T_W_C[k]});
  }
  in.options.align = Alignment::kNone;
  EXPECT_FALSE(evaluate(in).paper_attitude.has_value());
  in.attitude_reference = t.hull;
  const Evaluation e = evaluate(in);
  ASSERT_TRUE(e.paper_attitude.has_value());
  const nlohmann::json j = to_json(e, in.options);
  EXPECT_NEAR(j["paper_attitude"]["max_abs_deg"]["pitch"].get<double>(), 18.0, 1e-6);
  EXPECT_EQ(j["paper_attitude"]["pairs"].get<std::size_t>(), t.t_ns.size());
  EXPECT_NE(tables_markdown(e, in.options).find("AHRS − VO"), std::string::npos);
}

}  // namespace
}  // namespace driftlab::eval::paper_attitude_test
