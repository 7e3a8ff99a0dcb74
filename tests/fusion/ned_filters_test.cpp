// Tests of the basin paper's Kalman and particle filters (fusion/ned_filters, Kucic & Valcic
// 2020) as a whole: body velocities from the VO, a turning vessel tracked better than the raw
// measurements, the VO's noise estimated from the VO, invalid frames, errors, determinism and
// the CSV output. (Each filter against expectations computed independently:
// ned_kalman_particle_test.cpp.)
#include "fusion/ned_filters.hpp"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Dense>
#include <boost/math/distributions/normal.hpp>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "core/rotation.hpp"
#include "core/yaml_io.hpp"
#include "tests/fusion/ned_fixtures.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab::fusion {
namespace {

namespace fs = std::filesystem;

using fixtures::heading_at;
using fixtures::kNedDt;
using fixtures::kNedStepNs;
using fixtures::linear_run;
using fixtures::LinearRun;
using fixtures::vo_at;

bool finite(const NedEstimate& e) { return e.x.allFinite() && e.P.allFinite(); }

// ---------------------------------------------------------------------------------------------
// Measurements from VO

TEST(BodyVelocityFromVo, RecoversBodyVelocitiesAndYawRateThroughTheMount) {
  // The body moves 0.1 m forward and 0.02 m to starboard while yawing 0.01 rad in 0.1 s; the
  // camera looks forward, 1.2 m ahead of the CG, 0.5 m up and 0.1 m to starboard, so its own
  // motion includes the lever arm's swing (which must not show up as sway).
  const SE3 T_B_C(R_frd_optical(), Vec3(1.2, 0.1, -0.5));
  const SE3 T_Bprev_Bcurr(quat_from_euler_zyx({0.0, 0.0, 0.01}), Vec3(0.1, 0.02, 0.0));
  vo::VoResult r;
  r.valid = true;
  r.T_prev_curr = T_B_C.inverse() * T_Bprev_Bcurr * T_B_C;
  const BodyVelocityMeasurement m = body_velocity_from_vo(7, 0.1, r, T_B_C);
  ASSERT_TRUE(m.valid);
  EXPECT_EQ(m.t_ns, 7);
  EXPECT_NEAR(m.surge_m_s, 1.0, 1e-12);
  EXPECT_NEAR(m.sway_m_s, 0.2, 1e-12);
  EXPECT_NEAR(m.yaw_rate_rad_s, 0.1, 1e-12);
  // The camera's own translation differs from the body's by the lever arm's swing.
  const Vec3 cam_in_body = R_frd_optical() * r.T_prev_curr.translation();
  EXPECT_GT(std::abs(cam_in_body.y() - 0.02), 5e-3);

  vo::VoResult bad = r;
  bad.valid = false;
  EXPECT_FALSE(body_velocity_from_vo(7, 0.1, bad, T_B_C).valid);
  EXPECT_FALSE(body_velocity_from_vo(7, 0.0, r, T_B_C).valid);
  EXPECT_FALSE(body_velocity_from_vo(7, std::nan(""), r, T_B_C).valid);
}

// ---------------------------------------------------------------------------------------------
// A turning vessel with realistic noise

// One step of a vessel turning at a constant rate r with body velocities (u, v): the true
// state x = [N, E, u, v, psi] moves by kNedDt (heading at the step's midpoint).
void advance_turning_truth(NedVector* x, double u, double v, double r) {
  NedVector& s = *x;
  const double psi_m = s(4) + 0.5 * r * kNedDt;
  s(0) += kNedDt * (u * std::cos(psi_m) - v * std::sin(psi_m));
  s(1) += kNedDt * (u * std::sin(psi_m) + v * std::cos(psi_m));
  s(4) = wrap_angle_rad(s(4) + r * kNedDt);
}

// Adds the squared error of each state of `e` against the truth (heading wrapped) to `se`.
void add_squared_error(NedVector* se, const NedVector& e, const NedVector& truth) {
  for (int i = 0; i < 5; ++i) {
    const double d = i == 4 ? wrap_angle_rad(e(i) - truth(i)) : e(i) - truth(i);
    (*se)(i) += d * d;
  }
}

TEST(NedFiltersTest, TrackATurningVesselBetterThanTheRawMeasurements) {
  const NedFilterOptions o;
  Rng rng = RngStreams(21).stream("test.ned.turn");
  const double u = 1.2, v = -0.1, r = 0.08;
  NedVector x;
  x << 0.0, 0.0, u, v, 1.0;
  NedKalmanFilter kf(o, NedState{.surge_m_s = u, .sway_m_s = v, .heading_rad = 1.0});
  NedParticleFilterOptions po;
  po.resampling = PfResampling::kSystematicEss;
  NedParticleFilter pf(po, rng, NedState{.surge_m_s = u, .sway_m_s = v, .heading_rad = 1.0});
  const double su = *o.vo_increment_noise_m / kNedDt;
  NedVector se_kf = NedVector::Zero(), se_pf = NedVector::Zero();
  double se_raw_u = 0, se_raw_psi = 0;
  constexpr int kSteps = 1200;  // a minute at 20 Hz, 275 deg of turn
  for (int k = 0; k < kSteps; ++k) {
    if (k > 0) advance_turning_truth(&x, u, v, r);
    const double um = u + rng.normal(0, su), vm = v + rng.normal(0, su);
    const double rm = r + rng.normal(0, *o.vo_yaw_increment_noise_rad / kNedDt);
    std::optional<HeadingMeasurement> h;
    if (k % 2 == 0) h = heading_at(k, wrap_angle_rad(x(4) + rng.normal(0, *o.compass_noise_rad)));
    const bool valid = k % 40 != 39;
    const NedEstimate a = kf.step(vo_at(k, um, vm, rm, valid), h);
    const NedEstimate b = pf.step(vo_at(k, um, vm, rm, valid), h);
    ASSERT_TRUE(finite(a) && finite(b)) << k;
    add_squared_error(&se_kf, a.x, x);
    add_squared_error(&se_pf, b.x, x);
    se_raw_u += (um - u) * (um - u);
    if (h) se_raw_psi += std::pow(wrap_angle_rad(h->heading_rad - x(4)), 2);
  }
  const NedVector rms_kf = (se_kf / kSteps).cwiseSqrt(), rms_pf = (se_pf / kSteps).cwiseSqrt();
  const double raw_u = std::sqrt(se_raw_u / kSteps), raw_psi = std::sqrt(se_raw_psi / (kSteps / 2));
  std::printf(
      "[  metrics ] KF RMS N %.3f E %.3f u %.4f v %.4f psi %.4f; PF %.3f %.3f %.4f %.4f "
      "%.4f; raw u %.4f psi %.4f\n",
      rms_kf(0), rms_kf(1), rms_kf(2), rms_kf(3), rms_kf(4), rms_pf(0), rms_pf(1), rms_pf(2),
      rms_pf(3), rms_pf(4), raw_u, raw_psi);
  for (const NedVector* rms : {&rms_kf, &rms_pf}) {
    EXPECT_LT((*rms)(2), 0.5 * raw_u);
    EXPECT_LT((*rms)(3), 0.5 * raw_u);
    EXPECT_LT((*rms)(4), 0.5 * raw_psi);
    // 72 m of track: a heading error of ~0.2 deg and 0.03 m/s velocity errors stay decimetric.
    EXPECT_LT((*rms)(0), 0.5);
    EXPECT_LT((*rms)(1), 0.5);
  }
}

TEST(NedFiltersTest, NullVoNoiseIsEstimatedFromTheVoAndTracksAsWellAsTheTrueNoise) {
  // The turning vessel above, with VO noise three times the options' built-in values. A filter
  // with null VO noise estimates it from the VO's own velocities and yaw rates; it must find the
  // true standard deviations and track as well as a filter told them (the optimal one).
  NedFilterOptions truth;
  truth.vo_increment_noise_m = 0.015;
  truth.vo_yaw_increment_noise_rad = 1e-3;
  NedFilterOptions estimated;
  estimated.vo_increment_noise_m.reset();
  estimated.vo_yaw_increment_noise_rad.reset();
  Rng rng = RngStreams(33).stream("test.ned.noise");
  const double u = 1.2, v = -0.1, r = 0.08;
  const NedState init{.surge_m_s = u, .sway_m_s = v, .heading_rad = 1.0};
  NedKalmanFilter told(truth, init), guessing(estimated, init);
  const double su = *truth.vo_increment_noise_m / kNedDt;
  const double sr = *truth.vo_yaw_increment_noise_rad / kNedDt;
  NedVector x;
  x << 0.0, 0.0, u, v, 1.0;
  NedVector se_told = NedVector::Zero(), se_guess = NedVector::Zero();
  double su_sum = 0.0, sr_sum = 0.0;
  int n_estimates = 0;
  constexpr int kSteps = 1200;
  for (int k = 0; k < kSteps; ++k) {
    if (k > 0) advance_turning_truth(&x, u, v, r);
    const BodyVelocityMeasurement m =
        vo_at(k, u + rng.normal(0, su), v + rng.normal(0, su), r + rng.normal(0, sr), k % 40 != 39);
    std::optional<HeadingMeasurement> h;
    if (k % 2 == 0) h = heading_at(k, wrap_angle_rad(x(4) + rng.normal(0, 0.0175)));
    const NedEstimate a = told.step(m, h);
    const NedEstimate b = guessing.step(m, h);
    if (k >= 200 && m.valid) {  // once the windows are full (200 differences each)
      EXPECT_NEAR(b.vo_velocity_sd_m_s, su, 0.2 * su) << k;
      EXPECT_NEAR(b.vo_yaw_rate_sd_rad_s, sr, 0.3 * sr) << k;
      su_sum += b.vo_velocity_sd_m_s;
      sr_sum += b.vo_yaw_rate_sd_rad_s;
      ++n_estimates;
    }
    if (m.valid) {
      EXPECT_EQ(a.vo_velocity_sd_m_s, su) << k;
      EXPECT_NEAR(a.vo_yaw_rate_sd_rad_s, sr, 1e-15) << k;
    }
    add_squared_error(&se_told, a.x, x);
    add_squared_error(&se_guess, b.x, x);
  }
  const NedVector rms_told = (se_told / kSteps).cwiseSqrt();
  const NedVector rms_guess = (se_guess / kSteps).cwiseSqrt();
  const double su_mean = su_sum / n_estimates, sr_mean = sr_sum / n_estimates;
  std::printf(
      "[  metrics ] KF told the VO noise: RMS N %.3f E %.3f u %.4f psi %.4f; "
      "estimating it: %.3f %.3f %.4f %.4f; mean estimate %.4f m/s (true %.4f), %.5f "
      "rad/s (true %.5f)\n",
      rms_told(0), rms_told(1), rms_told(2), rms_told(4), rms_guess(0), rms_guess(1), rms_guess(2),
      rms_guess(4), su_mean, su, sr_mean, sr);
  // The median's own error averages out over the run's overlapping windows.
  EXPECT_NEAR(su_mean, su, 0.05 * su);
  EXPECT_NEAR(sr_mean, sr, 0.05 * sr);
  for (int i = 0; i < 5; ++i) EXPECT_LT(rms_guess(i), 1.1 * rms_told(i)) << i;
}

TEST(SecondDifferenceNoise, FindsWhiteNoiseOnASmoothSignalDespiteOutliersAndGaps) {
  // Two channels: 0.8 s oscillations of 0.05 m/s sampled at 20 Hz (surge and sway in waves),
  // white noise of 0.02, and one sample in 50 made wild.
  Rng rng = RngStreams(5).stream("test.noise");
  const double sigma = 0.02;
  // Each wild sample spoils three differences: a fraction p = 3/50 of them, all above the
  // median, which moves the median to the (1/2) / (1 - p) quantile of the clean |d|. The 0.8 s
  // oscillation's second difference (0.008) adds under 1 % to the noise's (0.049).
  const double p = 3.0 / 50.0;
  const boost::math::normal_distribution<double> n01;
  const double expected =
      sigma * boost::math::quantile(n01, 0.5 + 0.25 / (1.0 - p)) / 0.6744897501960817;
  SecondDifferenceNoise all(2, 4000), windowed(2);
  EXPECT_FALSE(windowed.sigma().has_value());
  for (int k = 0; k < 2000; ++k) {
    const double t = k * kNedDt;
    for (std::size_t c = 0; c < 2; ++c) {
      double x = 0.05 * std::sin(2.0 * std::numbers::pi * t / 0.8 + static_cast<double>(c)) +
                 rng.normal(0.0, sigma);
      if (k % 50 == 7) x += 5.0;
      x += static_cast<double>((k + 49) / 100);  // a level shift after each gap
      all.add(c, x);
      windowed.add(c, x);
    }
    if (k % 100 == 50) {  // a level shift across a gap adds no difference
      all.gap();
      windowed.gap();
    }
    // A chain's first difference needs its third sample; two differences give an estimate.
    if (k == 1) {
      EXPECT_FALSE(windowed.sigma().has_value());
    }
    if (k == 2) {
      EXPECT_TRUE(windowed.sigma().has_value());
    }
    if (k >= 100 && k % 25 == 0) {
      ASSERT_TRUE(windowed.sigma().has_value());
      EXPECT_NEAR(*windowed.sigma(), expected, 0.3 * expected) << k;  // 200 differences
    }
  }
  std::printf("[  metrics ] second differences: sigma %.5f, expected %.5f (true %.3f)\n",
              *all.sigma(), expected, sigma);
  EXPECT_NEAR(*all.sigma(), expected, 0.04 * expected);
  all.reset();
  EXPECT_FALSE(all.sigma().has_value());
}

// ---------------------------------------------------------------------------------------------
// Robustness, errors, determinism, output

TEST(NedFiltersTest, InvalidVoFramesAreSkippedWithoutNan) {
  NedKalmanFilter kf{NedFilterOptions{}};
  NedParticleFilter pf(NedParticleFilterOptions{}, Rng(9));
  double p_uu_before_gap = 0.0;
  for (int k = 0; k < 60; ++k) {
    BodyVelocityMeasurement m = vo_at(k, 1.0, 0.0, 0.01, k < 20 || k >= 40);
    if (!m.valid) {
      // A failed VO must not be read at all, whatever it holds.
      m.surge_m_s = std::nan("");
      m.yaw_rate_rad_s = std::numeric_limits<double>::infinity();
    }
    const NedEstimate a = kf.step(m);
    const NedEstimate b = pf.step(m);
    ASSERT_TRUE(finite(a)) << k;
    ASSERT_TRUE(finite(b)) << k;
    EXPECT_EQ(a.vo_fused, m.valid);
    EXPECT_EQ(b.vo_fused, m.valid);
    if (k == 19) p_uu_before_gap = a.P(2, 2);
    if (k == 39) {
      // 20 steps without VO: the velocity is predicted only (held) and its uncertainty grew.
      EXPECT_GT(a.P(2, 2), 2.0 * p_uu_before_gap);
      EXPECT_NEAR(a.surge_m_s(), 1.0, 0.05);
    }
  }
  EXPECT_EQ(kf.nonfinite_guards(), 0);
  EXPECT_EQ(pf.nonfinite_guards(), 0);
  // A "valid" measurement that breaks the promise of finite values is caught and counted.
  BodyVelocityMeasurement broken = vo_at(60, std::nan(""), 0.0, 0.0);
  EXPECT_TRUE(finite(kf.step(broken, HeadingMeasurement{60 * kNedStepNs, std::nan("")})));
  EXPECT_TRUE(finite(pf.step(broken)));
  EXPECT_EQ(kf.nonfinite_guards(), 2);
  EXPECT_EQ(pf.nonfinite_guards(), 1);
}

TEST(NedFiltersTest, TimeMustIncrease) {
  NedKalmanFilter kf{NedFilterOptions{}};
  kf.step(vo_at(3, 1, 0, 0));
  try {
    kf.step(vo_at(3, 1, 0, 0));
    FAIL() << "expected UserError";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("NedKalmanFilter::step: time stamps must increase"),
              std::string::npos)
        << e.what();
  }
  NedParticleFilter pf(NedParticleFilterOptions{}, Rng(1));
  pf.step(vo_at(3, 1, 0, 0));
  EXPECT_THROW(pf.step(vo_at(2, 1, 0, 0)), UserError);
}

TEST(NedFiltersTest, BadOptionsGiveClearErrors) {
  NedParticleFilterOptions po;
  po.particles = 0;
  po.compass_noise_rad = -1.0;
  po.velocity_noise_m_s_sqrt_s = 0.0;
  const std::string problems = po.validate();
  EXPECT_NE(problems.find("particles: got 0"), std::string::npos) << problems;
  EXPECT_NE(problems.find("compass_noise_rad: got -1"), std::string::npos) << problems;
  EXPECT_NE(problems.find("velocity_noise_m_s_sqrt_s: got 0"), std::string::npos) << problems;
  try {
    NedParticleFilter pf(po, Rng(1));
    FAIL() << "expected UserError";
  } catch (const UserError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("NedParticleFilter"), std::string::npos) << m;
    EXPECT_NE(m.find("particles: got 0, expected"), std::string::npos) << m;
  }
  NedFilterOptions ko;
  ko.initial_heading_sd_rad = 0.0;
  try {
    NedKalmanFilter kf(ko);
    FAIL() << "expected UserError";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("initial_heading_sd_rad: got 0"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(NedKalmanFilter(NedFilterOptions{}, NedState{.north_m = std::nan("")}), UserError);
  EXPECT_EQ(NedParticleFilterOptions{}.validate(), "");
}

TEST(NedFiltersTest, OptionsYamlRoundTripAndStrictKeys) {
  NedParticleFilterOptions o;
  o.particles = 500;
  o.resampling = PfResampling::kSystematicEss;
  o.likelihood = PfLikelihood::kPaperAverage;
  o.heading_jacobian = true;
  const std::string text = yaml::to_yaml(o);
  EXPECT_NE(text.find("resampling: systematic_ess"), std::string::npos) << text;
  NedParticleFilterOptions back;
  yaml::read_into(yaml::load_string(text, "round trip"), {"round trip", false}, &back);
  EXPECT_EQ(yaml::to_yaml(back), text);
  NedParticleFilterOptions strict;
  try {
    yaml::read_into(yaml::load_string("particles: 10\nresampling: stratified\n", "f.yaml"),
                    {"f.yaml", true}, &strict);
    FAIL() << "expected UserError";
  } catch (const UserError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("f.yaml:2"), std::string::npos) << m;
    EXPECT_NE(m.find("multinomial, systematic_ess"), std::string::npos) << m;
  }
}

std::vector<NedEstimate> run_pf(NedParticleFilter* pf, const LinearRun& run) {
  std::vector<NedEstimate> out;
  for (std::size_t k = 0; k < run.vo.size(); ++k)
    out.push_back(pf->step(run.vo[k], run.heading[k]));
  return out;
}

bool same_bytes(const std::vector<NedEstimate>& a, const std::vector<NedEstimate>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t k = 0; k < a.size(); ++k) {
    if (std::memcmp(a[k].x.data(), b[k].x.data(), sizeof(double) * 5) != 0) return false;
    if (std::memcmp(a[k].P.data(), b[k].P.data(), sizeof(double) * 25) != 0) return false;
  }
  return true;
}

TEST(NedFiltersTest, ParticleFilterIsDeterministicInItsRng) {
  const LinearRun run = linear_run(80, 4, NedFilterOptions{}, 0.5);
  NedParticleFilterOptions po;
  NedParticleFilter a(po, RngStreams(42).stream("fusion.ned_pf"));
  NedParticleFilter b(po, RngStreams(42).stream("fusion.ned_pf"));
  NedParticleFilter c(po, RngStreams(43).stream("fusion.ned_pf"));
  const auto ra = run_pf(&a, run);
  EXPECT_TRUE(same_bytes(ra, run_pf(&b, run)));
  EXPECT_FALSE(same_bytes(ra, run_pf(&c, run)));
  a.reset();
  EXPECT_TRUE(same_bytes(ra, run_pf(&a, run)));
}

class NedCsvTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ =
        fs::temp_directory_path() /
        ("driftlab_ned_csv_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
         "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  static std::string read(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }
  fs::path dir_;
};

TEST_F(NedCsvTest, WritesTheColumnsExactlyAndReproducibly) {
  const LinearRun run = linear_run(30, 8, NedFilterOptions{}, 3.1);
  NedKalmanFilter kf(NedFilterOptions{}, NedState{.heading_rad = 3.1});
  std::vector<NedEstimate> steps;
  for (std::size_t k = 0; k < run.vo.size(); ++k)
    steps.push_back(kf.step(run.vo[k], run.heading[k]));
  write_ned_csv(dir_ / "a.csv", steps);
  write_ned_csv(dir_ / "b.csv", steps);
  const std::string a = read(dir_ / "a.csv");
  EXPECT_EQ(a, read(dir_ / "b.csv"));
  std::istringstream in(a);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "t_s,north_m,east_m,surge_m_s,sway_m_s,heading_rad");
  std::size_t k = 0;
  while (std::getline(in, line)) {
    ASSERT_LT(k, steps.size());
    std::vector<std::string> cols;
    std::stringstream ls(line);
    for (std::string c; std::getline(ls, c, ',');) cols.push_back(c);
    ASSERT_EQ(cols.size(), 6u) << line;
    TimeNs t = 0;
    ASSERT_TRUE(parse_seconds(cols[0], &t)) << cols[0];
    EXPECT_EQ(t, steps[k].t_ns);
    for (int j = 0; j < 5; ++j)
      EXPECT_EQ(std::stod(cols[static_cast<std::size_t>(j) + 1]), steps[k].x(j));
    EXPECT_GT(steps[k].heading_rad(), -std::numbers::pi);
    EXPECT_LE(steps[k].heading_rad(), std::numbers::pi);
    ++k;
  }
  EXPECT_EQ(k, steps.size());
  // Nothing half-written: an uncommitted writer leaves no file.
  {
    NedCsvWriter w(dir_ / "c.csv");
    w.write(steps[0]);
  }
  EXPECT_FALSE(fs::exists(dir_ / "c.csv"));
}

TEST(NedEstimateTest, PlanarPose) {
  NedEstimate e;
  e.x << 2.0, -3.0, 1.0, 0.0, 0.5;
  const SE3 T = e.T_W_B();
  EXPECT_TRUE(T.translation().isApprox(Vec3(2.0, -3.0, 0.0)));
  EXPECT_NEAR(euler_zyx_from_quat(T.quaternion()).yaw_rad, 0.5, 1e-15);
  // The bow points along (cos psi, sin psi) in north-east.
  EXPECT_TRUE((T.quaternion() * Vec3::UnitX()).isApprox(Vec3(std::cos(0.5), std::sin(0.5), 0.0)));
}

}  // namespace
}  // namespace driftlab::fusion
