// Tests of the constant-acceleration smoother (river paper Eqs. (4)-(5)) against expectations
// computed here independently: exact reproduction of a noise-free constant-acceleration twist,
// the steady-state Kalman gain and covariance from the discrete Riccati equation, and the
// steady-state error variance from the discrete Lyapunov equation.
#include "fusion/ca_smoother.hpp"

#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "core/yaml_io.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab::fusion {
namespace {

using driftlab::test::kEps;
constexpr TimeNs kStepNs = 100'000'000;  // 10 Hz, the river paper's frame rate
constexpr double kDt = 0.1;
// Fixed-point iterations and the filter's own recursion agree to rounding, amplified by the
// few hundred steps of the recursion's memory.
constexpr double kRiccatiRelTol = 1e-9;
// After convergence the noise-free filter reproduces the model to rounding: twists of O(1)
// through exp/log and a few thousand steps.
constexpr double kReproduceTol = 1e-9;
// Sample variances of ~1e5 autocorrelated errors (correlation time ~10 steps): a relative
// standard error of ~1.5%; 6% is four of them.
constexpr double kVarianceRelTol = 0.06;

vo::VoResult valid_increment(const SE3& T) {
  vo::VoResult r;
  r.valid = true;
  r.T_prev_curr = T;
  r.matches = r.inliers = 100;
  r.mean_inlier_depth_m = 10.0;
  return r;
}

vo::VoResult invalid_result(const std::string& reason) {
  vo::VoResult r;
  r.valid = false;
  r.reason = reason;
  return r;
}

bool finite(const SmoothedStep& s) {
  return s.velocity.allFinite() && s.acceleration.allFinite() && s.velocity_sd.allFinite() &&
         s.T_prev_curr.translation().allFinite() && s.T_prev_curr.quaternion().coeffs().allFinite();
}

// Per-axis noise of the filter (same layout as the smoother's axes: 3 linear, 3 angular).
double axis_q2(const CaSmootherOptions& o, int i) {
  const double q = i < 3 ? o.jerk_noise_linear_m_s3_sqrt_hz[static_cast<std::size_t>(i)]
                         : o.jerk_noise_angular_rad_s3_sqrt_hz[static_cast<std::size_t>(i - 3)];
  return q * q;
}
double axis_r(const CaSmootherOptions& o, int i, double dt) {
  const double s = i < 3 ? o.increment_noise_linear_m[static_cast<std::size_t>(i)]
                         : o.increment_noise_angular_rad[static_cast<std::size_t>(i - 3)];
  return s * s / (dt * dt);
}

// The 1-D constant-acceleration model, written out here from Eqs. (4)-(5).
struct Model1d {
  Eigen::Matrix2d F, Q;
  Eigen::RowVector2d H;
  double r;
  Model1d(double dt, double q2, double r_in) : r(r_in) {
    F << 1.0, dt, 0.0, 1.0;
    Q << q2 * dt * dt * dt / 3.0, q2 * dt * dt / 2.0, q2 * dt * dt / 2.0, q2 * dt;
    H << 1.0, 0.0;
  }
};

struct SteadyState {
  Eigen::Matrix2d P;  // posterior (after the update)
  Eigen::Vector2d K;
};

// Discrete algebraic Riccati equation by fixed-point iteration of the textbook recursion
// (standard, not Joseph, form: a different computation from the smoother's).
SteadyState solve_riccati(const Model1d& m) {
  Eigen::Matrix2d P = Eigen::Matrix2d::Identity();
  Eigen::Vector2d K = Eigen::Vector2d::Zero();
  for (int it = 0; it < 1'000'000; ++it) {
    const Eigen::Matrix2d Pp = m.F * P * m.F.transpose() + m.Q;
    const double S = (m.H * Pp * m.H.transpose())(0, 0) + m.r;
    const Eigen::Vector2d Kn = Pp * m.H.transpose() / S;
    const Eigen::Matrix2d Pn = (Eigen::Matrix2d::Identity() - Kn * m.H) * Pp;
    const bool done = (Pn - P).cwiseAbs().maxCoeff() <= 4 * kEps * Pn.cwiseAbs().maxCoeff() &&
                      (Kn - K).cwiseAbs().maxCoeff() <= 4 * kEps * Kn.cwiseAbs().maxCoeff();
    P = Pn;
    K = Kn;
    if (done) break;
  }
  return {P, K};
}

// Steady-state covariance of the estimation error of a filter with fixed gain K when the truth
// follows the model without process noise (constant velocity): e <- (I - K H) F e + K nu, i.e.
// the discrete Lyapunov equation S = A S A^T + K r K^T.
Eigen::Matrix2d solve_lyapunov(const Model1d& m, const Eigen::Vector2d& K) {
  const Eigen::Matrix2d A = (Eigen::Matrix2d::Identity() - K * m.H) * m.F;
  const Eigen::Matrix2d B = K * m.r * K.transpose();
  Eigen::Matrix2d S = B;
  for (int it = 0; it < 1'000'000; ++it) {
    const Eigen::Matrix2d Sn = A * S * A.transpose() + B;
    const bool done = (Sn - S).cwiseAbs().maxCoeff() <= 4 * kEps * Sn.cwiseAbs().maxCoeff();
    S = Sn;
    if (done) break;
  }
  return S;
}

void expect_rel_near(double actual, double expected, double rel, const std::string& what) {
  EXPECT_NEAR(actual, expected, rel * std::abs(expected)) << what;
}

// ---------------------------------------------------------------------------------------------

TEST(CaSmootherTest, FirstUpdateOnlyStartsTheClock) {
  ConstantAccelerationSmoother s{CaSmootherOptions{}};
  const SmoothedStep first = s.update(5 * kStepNs, valid_increment(SE3::exp(Vec6::Constant(0.1))));
  EXPECT_FALSE(first.measured);
  EXPECT_EQ(first.dt_s, 0.0);
  EXPECT_EQ(first.T_prev_curr.translation(), Vec3::Zero());
  EXPECT_EQ(first.T_prev_curr.quaternion().coeffs(), Quat::Identity().coeffs());
  const SmoothedStep second = s.update(6 * kStepNs, valid_increment(SE3()));
  EXPECT_TRUE(second.measured);
  EXPECT_DOUBLE_EQ(second.dt_s, kDt);
}

TEST(CaSmootherTest, NoiseFreeConstantAccelerationTwistIsReproducedAfterConvergence) {
  // Each axis its own constant-acceleration twist: measurements lie exactly on Eq. (4)'s model.
  Vec6 v0, a0;
  v0 << 1.5, -0.2, 3.0, 0.05, -0.3, 0.1;
  a0 << 0.02, 0.01, -0.05, 0.002, 0.004, -0.003;
  ConstantAccelerationSmoother s{CaSmootherOptions{}};
  s.update(0, invalid_result("first frame"));
  constexpr int kSteps = 600;
  for (int k = 1; k <= kSteps; ++k) {
    const double t = k * kDt;
    const Vec6 v = v0 + a0 * t;
    const SE3 T = SE3::exp(v * kDt);
    const SmoothedStep step = s.update(k * kStepNs, valid_increment(T));
    ASSERT_TRUE(finite(step));
    if (k < 200) continue;  // convergence from the zero prior
    for (int i = 0; i < 6; ++i) {
      EXPECT_NEAR(step.velocity(i), v(i), kReproduceTol) << "axis " << i << " step " << k;
      EXPECT_NEAR(step.acceleration(i), a0(i), kReproduceTol * 10) << "axis " << i;
    }
    EXPECT_TRUE(step.T_prev_curr.is_approx(T, kReproduceTol, kReproduceTol)) << "step " << k;
  }
}

TEST(CaSmootherTest, GainAndCovarianceMatchDiscreteRiccatiSolution) {
  CaSmootherOptions o;
  // Different noise on every axis, so a mixed-up axis would show.
  o.jerk_noise_linear_m_s3_sqrt_hz = {0.5, 2.0, 8.0};
  o.jerk_noise_angular_rad_s3_sqrt_hz = {0.05, 0.3, 1.0};
  o.increment_noise_linear_m = {0.002, 0.01, 0.004};
  o.increment_noise_angular_rad = {1e-4, 5e-4, 2e-3};
  ConstantAccelerationSmoother s(o);
  s.update(0, invalid_result("first frame"));
  for (int k = 1; k <= 3000; ++k) s.update(k * kStepNs, valid_increment(SE3()));
  for (int i = 0; i < 6; ++i) {
    const Model1d m(kDt, axis_q2(o, i), axis_r(o, i, kDt));
    const SteadyState ss = solve_riccati(m);
    const Eigen::Vector2d K = s.axis_gain(i);
    const Eigen::Matrix2d P = s.axis_covariance(i);
    const std::string axis = "axis " + std::to_string(i);
    expect_rel_near(K(0), ss.K(0), kRiccatiRelTol, axis + " K_v");
    expect_rel_near(K(1), ss.K(1), kRiccatiRelTol, axis + " K_a");
    expect_rel_near(P(0, 0), ss.P(0, 0), kRiccatiRelTol, axis + " P_vv");
    expect_rel_near(P(0, 1), ss.P(0, 1), kRiccatiRelTol, axis + " P_va");
    expect_rel_near(P(1, 1), ss.P(1, 1), kRiccatiRelTol, axis + " P_aa");
    // A gain in (0, 1) that trusts the model more than one measurement: the smoothing.
    EXPECT_GT(K(0), 0.0);
    EXPECT_LT(K(0), 1.0);
    EXPECT_LT(P(0, 0), m.r);
  }
}

TEST(CaSmootherTest, NoisyConstantVelocityVarianceBelowMeasurementAndAsPredicted) {
  // Truth: constant twist. Measurements: truth + Gaussian noise of the filter's own R.
  const CaSmootherOptions o;
  Vec6 v_true;
  v_true << 0.3, -0.1, 2.0, 0.01, 0.08, -0.02;
  Rng rng = RngStreams(1234).stream("test.vo_noise");
  ConstantAccelerationSmoother s(o);
  s.update(0, invalid_result("first frame"));
  constexpr int kBurnIn = 500;
  constexpr int kSteps = 100'000;
  Vec6 sum_e = Vec6::Zero(), sum_e2 = Vec6::Zero(), sum_n2 = Vec6::Zero();
  for (int k = 1; k <= kBurnIn + kSteps; ++k) {
    Vec6 noise;
    for (int i = 0; i < 6; ++i) noise(i) = rng.normal(0.0, std::sqrt(axis_r(o, i, kDt)));
    const SmoothedStep step =
        s.update(k * kStepNs, valid_increment(SE3::exp((v_true + noise) * kDt)));
    ASSERT_TRUE(finite(step));
    if (k <= kBurnIn) continue;
    const Vec6 e = step.velocity - v_true;
    sum_e += e;
    sum_e2 += e.cwiseProduct(e);
    sum_n2 += noise.cwiseProduct(noise);
  }
  for (int i = 0; i < 6; ++i) {
    const Model1d m(kDt, axis_q2(o, i), axis_r(o, i, kDt));
    const SteadyState ss = solve_riccati(m);
    const double predicted = solve_lyapunov(m, ss.K)(0, 0);
    const double mean = sum_e(i) / kSteps;
    const double var = sum_e2(i) / kSteps - mean * mean;
    const double raw_var = sum_n2(i) / kSteps;
    const std::string axis = "axis " + std::to_string(i);
    std::printf(
        "[  metrics ] %s: raw measurement variance %.4g, smoothed %.4g (predicted %.4g, "
        "filter's own P_vv %.4g)\n",
        axis.c_str(), raw_var, var, predicted, ss.P(0, 0));
    EXPECT_LT(var, raw_var) << axis;
    expect_rel_near(var, predicted, kVarianceRelTol, axis + " error variance");
    // The filter assumes jerk the truth does not have, so its own P bounds the actual error.
    EXPECT_LE(predicted, ss.P(0, 0)) << axis;
  }
}

TEST(CaSmootherTest, ErrorVarianceMatchesOwnCovarianceWhenTheModelIsTrue) {
  // Truth driven by exactly the modelled white jerk (Eq. (4)'s epsilon with covariance Q):
  // then the filter's posterior P_vv is the actual error variance. Such a truth wanders off
  // (velocity ~ q t^1.5), so many short runs from rest replace one long one, and the angular
  // jerk is small enough that a step's rotation stays far below pi (SE3::log's range).
  CaSmootherOptions o;
  o.jerk_noise_linear_m_s3_sqrt_hz = {1.0, 0.5, 2.0};
  o.jerk_noise_angular_rad_s3_sqrt_hz = {0.01, 0.02, 0.005};
  Rng rng = RngStreams(99).stream("test.truth");
  ConstantAccelerationSmoother s(o);
  std::vector<Model1d> models;
  std::vector<Eigen::Matrix2d> chol;
  for (int i = 0; i < 6; ++i) {
    models.emplace_back(kDt, axis_q2(o, i), axis_r(o, i, kDt));
    chol.push_back(models.back().Q.llt().matrixL());
  }
  constexpr int kRuns = 500;
  constexpr int kBurnIn = 100;
  constexpr int kStepsPerRun = 300;
  Vec6 sum_e2 = Vec6::Zero();
  int samples = 0;
  for (int run = 0; run < kRuns; ++run) {
    s.reset();
    s.update(0, invalid_result("first frame"));
    std::array<Eigen::Vector2d, 6> x;
    x.fill(Eigen::Vector2d::Zero());
    for (int k = 1; k <= kStepsPerRun; ++k) {
      Vec6 z, v;
      for (std::size_t i = 0; i < 6; ++i) {
        const Eigen::Vector2d w(rng.normal(), rng.normal());
        x[i] = models[i].F * x[i] + chol[i] * w;
        v(static_cast<Eigen::Index>(i)) = x[i](0);
        z(static_cast<Eigen::Index>(i)) = x[i](0) + rng.normal(0.0, std::sqrt(models[i].r));
      }
      const SmoothedStep step = s.update(k * kStepNs, valid_increment(SE3::exp(z * kDt)));
      if (k <= kBurnIn) continue;
      const Vec6 e = step.velocity - v;
      sum_e2 += e.cwiseProduct(e);
      ++samples;
    }
  }
  for (int i = 0; i < 6; ++i) {
    const double var = sum_e2(i) / samples;
    const double P_vv = s.axis_covariance(i)(0, 0);
    std::printf("[  metrics ] axis %d: error variance %.4g, filter's P_vv %.4g\n", i, var, P_vv);
    expect_rel_near(var, P_vv, kVarianceRelTol,
                    "axis " + std::to_string(i) + " error variance vs P_vv");
  }
}

TEST(CaSmootherTest, InvalidFramesArePredictedOnlyWithoutNan) {
  ConstantAccelerationSmoother s{CaSmootherOptions{}};
  // Invalid from the very start: the prior predicts zero motion, and stays finite.
  for (int k = 0; k < 5; ++k) {
    const SmoothedStep step = s.update(k * kStepNs, invalid_result("too few features"));
    ASSERT_TRUE(finite(step));
    EXPECT_FALSE(step.measured);
    EXPECT_TRUE(step.T_prev_curr.is_approx(SE3(), 1e-12, 1e-12));
  }
  // Converge on a constant twist, then lose the VO for a while.
  Vec6 v;
  v << 0.2, 0.0, 1.5, 0.0, 0.05, 0.0;
  int k = 5;
  for (; k < 400; ++k) s.update(k * kStepNs, valid_increment(SE3::exp(v * kDt)));
  const Eigen::Vector2d before = s.axis_state(2);
  for (int gap = 0; gap < 20; ++gap, ++k) {
    vo::VoResult bad = invalid_result("too few inliers");
    // A failed VO must not be read at all, whatever its pose holds.
    bad.T_prev_curr = SE3::exp(Vec6::Constant(0.7));
    const SmoothedStep step = s.update(k * kStepNs, bad);
    ASSERT_TRUE(finite(step));
    EXPECT_FALSE(step.measured);
    // Prediction only, Eq. (4): v <- v + a dt, with a ~ 0 after a constant twist.
    EXPECT_TRUE(step.T_prev_curr.is_approx(SE3::exp(v * kDt), 1e-9, 1e-9));
  }
  const Eigen::Vector2d after = s.axis_state(2);
  EXPECT_NEAR(after(0), before(0) + 20 * kDt * before(1), 1e-12);
  // Uncertainty grows while predicting, and the next measurement is fused again.
  const double sd_gap = std::sqrt(s.axis_covariance(2)(0, 0));
  const SmoothedStep back = s.update(k * kStepNs, valid_increment(SE3::exp(v * kDt)));
  EXPECT_TRUE(back.measured);
  EXPECT_LT(back.velocity_sd(2), sd_gap);
  EXPECT_EQ(s.nonfinite_guards(), 0);
}

TEST(CaSmootherTest, NonFiniteMeasurementIsGuardedAndCounted) {
  ConstantAccelerationSmoother s{CaSmootherOptions{}};
  s.update(0, invalid_result("first frame"));
  s.update(kStepNs, valid_increment(SE3::exp(Vec6::Constant(0.01))));
  // VoResult promises finite fields; if one broke that promise the filter must not spread it.
  vo::VoResult broken = valid_increment(SE3());
  broken.T_prev_curr = SE3(Quat::Identity(), Vec3(std::nan(""), 0.0, 0.0));
  const SmoothedStep step = s.update(2 * kStepNs, broken);
  EXPECT_TRUE(finite(step));
  EXPECT_FALSE(step.measured);
  EXPECT_EQ(s.nonfinite_guards(), 1);
}

TEST(CaSmootherTest, TimeMustIncrease) {
  ConstantAccelerationSmoother s{CaSmootherOptions{}};
  s.update(kStepNs, invalid_result("first frame"));
  try {
    s.update(kStepNs, valid_increment(SE3()));
    FAIL() << "expected UserError";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("time stamps must increase"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(s.update(0, valid_increment(SE3())), UserError);
}

TEST(CaSmootherTest, ResetRepeatsTheSameBytes) {
  ConstantAccelerationSmoother s{CaSmootherOptions{}};
  Rng rng(7);
  std::vector<vo::VoResult> in;
  for (int k = 0; k < 50; ++k) {
    Vec6 xi;
    for (int i = 0; i < 6; ++i) xi(i) = rng.normal(0.0, 0.05);
    in.push_back(k % 7 == 3 ? invalid_result("x") : valid_increment(SE3::exp(xi)));
  }
  auto run = [&] {
    std::vector<SmoothedStep> out;
    for (std::size_t k = 0; k < in.size(); ++k)
      out.push_back(s.update(static_cast<TimeNs>(k) * kStepNs, in[k]));
    return out;
  };
  const auto a = run();
  s.reset();
  const auto b = run();
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(0, std::memcmp(a[k].velocity.data(), b[k].velocity.data(), sizeof(double) * 6));
    EXPECT_EQ(0, std::memcmp(a[k].T_prev_curr.translation().data(),
                             b[k].T_prev_curr.translation().data(), sizeof(double) * 3));
  }
}

TEST(CaSmootherOptionsTest, BadOptionsGiveClearErrors) {
  CaSmootherOptions o;
  o.jerk_noise_linear_m_s3_sqrt_hz[1] = -1.0;
  o.increment_noise_angular_rad[2] = 0.0;
  const std::string problems = o.validate();
  EXPECT_NE(problems.find("jerk_noise_linear_m_s3_sqrt_hz[1]: got -1"), std::string::npos)
      << problems;
  EXPECT_NE(problems.find("increment_noise_angular_rad[2]: got 0"), std::string::npos) << problems;
  try {
    ConstantAccelerationSmoother s(o);
    FAIL() << "expected UserError";
  } catch (const UserError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("ConstantAccelerationSmoother"), std::string::npos) << m;
    EXPECT_NE(m.find("jerk_noise_linear_m_s3_sqrt_hz[1]"), std::string::npos) << m;
  }
  CaSmootherOptions nan_prior;
  nan_prior.initial_velocity_sd_m_s = std::nan("");
  EXPECT_NE(nan_prior.validate().find("initial_velocity_sd_m_s"), std::string::npos);
  EXPECT_EQ(CaSmootherOptions{}.validate(), "");
}

TEST(CaSmootherOptionsTest, YamlRoundTripAndStrictKeys) {
  CaSmootherOptions o;
  o.jerk_noise_angular_rad_s3_sqrt_hz = {0.1, 0.2, 0.3};
  o.rts_backward_pass = true;
  const std::string text = yaml::to_yaml(o);
  CaSmootherOptions back;
  yaml::read_into(yaml::load_string(text, "round trip"), {"round trip", false}, &back);
  EXPECT_EQ(yaml::to_yaml(back), text);
  EXPECT_TRUE(back.rts_backward_pass);
  try {
    CaSmootherOptions strict;
    yaml::read_into(
        yaml::load_string("increment_noise_linear_m: [0.01, 0.01]\nrts_pass: true\n", "f.yaml"),
        {"f.yaml", true}, &strict);
    FAIL() << "expected UserError";
  } catch (const UserError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("f.yaml:1"), std::string::npos) << m;
    EXPECT_NE(m.find("increment_noise_linear_m"), std::string::npos) << m;
    EXPECT_NE(m.find("exactly 3"), std::string::npos) << m;
    EXPECT_NE(m.find("rts_pass"), std::string::npos) << m;
  }
}

// ---------------------------------------------------------------------------------------------
// Batch smoothing

struct NoisySequence {
  std::vector<TimeNs> t;
  std::vector<vo::VoResult> vo;
  std::vector<Vec6> truth;  // true twist per step ([0] unused)
};

NoisySequence noisy_constant_velocity(int n, std::uint64_t seed, const CaSmootherOptions& o) {
  NoisySequence s;
  Vec6 v;
  v << 0.1, 0.02, 1.0, 0.0, 0.03, 0.0;
  Rng rng = RngStreams(seed).stream("test.vo_noise");
  for (int k = 0; k < n; ++k) {
    s.t.push_back(k * kStepNs);
    s.truth.push_back(v);
    if (k == 0) {
      s.vo.push_back(invalid_result("first frame"));
      continue;
    }
    Vec6 noise;
    for (int i = 0; i < 6; ++i) noise(i) = rng.normal(0.0, std::sqrt(axis_r(o, i, kDt)));
    s.vo.push_back(k % 50 == 25 ? invalid_result("gap")
                                : valid_increment(SE3::exp((v + noise) * kDt)));
  }
  return s;
}

TEST(SmoothTrajectoryTest, ForwardPassEqualsTheStreamingFilter) {
  const CaSmootherOptions o;
  const NoisySequence seq = noisy_constant_velocity(300, 5, o);
  const SmoothedTrajectory traj = smooth_trajectory(seq.t, seq.vo, o);
  ConstantAccelerationSmoother s(o);
  SE3 T;
  ASSERT_EQ(traj.T_first_cam.size(), seq.t.size());
  for (std::size_t k = 0; k < seq.t.size(); ++k) {
    T = T * s.update(seq.t[k], seq.vo[k]).T_prev_curr;
    EXPECT_EQ(0, std::memcmp(T.translation().data(), traj.T_first_cam[k].translation().data(),
                             3 * sizeof(double)));
  }
  EXPECT_EQ(traj.predicted_only, 6);  // the "gap" frames
}

TEST(SmoothTrajectoryTest, BackwardPassReducesErrorAndKeepsExactModels) {
  CaSmootherOptions o;
  const NoisySequence seq = noisy_constant_velocity(2000, 11, o);
  const SmoothedTrajectory fwd = smooth_trajectory(seq.t, seq.vo, o);
  o.rts_backward_pass = true;
  const SmoothedTrajectory rts = smooth_trajectory(seq.t, seq.vo, o);
  double e_fwd = 0.0, e_rts = 0.0;
  for (std::size_t k = 100; k < seq.t.size(); ++k) {
    e_fwd += (fwd.velocity[k] - seq.truth[k]).head<3>().squaredNorm();
    e_rts += (rts.velocity[k] - seq.truth[k]).head<3>().squaredNorm();
  }
  std::printf("[  metrics ] linear twist MSE forward %.4g, forward + RTS %.4g\n",
              e_fwd / (seq.t.size() - 100), e_rts / (seq.t.size() - 100));
  EXPECT_LT(e_rts, 0.5 * e_fwd);

  // On noise-free constant-acceleration data both passes give back the model.
  Vec6 v0, a0;
  v0 << 1.0, 0.1, 2.0, 0.02, -0.1, 0.05;
  a0 << 0.01, -0.02, 0.03, 0.001, 0.002, -0.001;
  std::vector<TimeNs> t;
  std::vector<vo::VoResult> vo;
  for (int k = 0; k < 600; ++k) {
    t.push_back(k * kStepNs);
    vo.push_back(k == 0 ? invalid_result("first frame")
                        : valid_increment(SE3::exp((v0 + a0 * (k * kDt)) * kDt)));
  }
  const SmoothedTrajectory exact = smooth_trajectory(t, vo, o);
  for (std::size_t k = 300; k < t.size(); ++k) {
    const Vec6 v = v0 + a0 * (static_cast<double>(k) * kDt);
    EXPECT_LT((exact.velocity[k] - v).cwiseAbs().maxCoeff(), kReproduceTol) << "step " << k;
  }
}

TEST(SmoothTrajectoryTest, MismatchedInputsThrow) {
  const std::vector<TimeNs> t{0, kStepNs};
  const std::vector<vo::VoResult> vo{invalid_result("first frame")};
  EXPECT_THROW(smooth_trajectory(t, vo, CaSmootherOptions{}), UserError);
  const std::vector<TimeNs> backwards{kStepNs, 0};
  const std::vector<vo::VoResult> two{invalid_result("first frame"), valid_increment(SE3())};
  EXPECT_THROW(smooth_trajectory(backwards, two, CaSmootherOptions{}), UserError);
  EXPECT_TRUE(smooth_trajectory({}, {}, CaSmootherOptions{}).T_first_cam.empty());
}

}  // namespace
}  // namespace driftlab::fusion
