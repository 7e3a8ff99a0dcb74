// Tests of the basin paper's Kalman and particle filters (fusion/ned_filters, Kucic & Valcic
// 2020, Eqs. (2)-(10)) against expectations computed here independently: the steady-state
// covariance from the discrete Riccati equation (fixed-point iteration, and the closed form of the
// scalar heading filter), the batch weighted least-squares solution of the same data, and the
// Kalman filter's answer for the particle filter, within its Monte-Carlo error.
#include "fusion/ned_filters.hpp"

#include <array>
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
#include "tests/support/test_support.hpp"

namespace driftlab::fusion {
namespace {

namespace fs = std::filesystem;

using driftlab::test::kEps;
constexpr TimeNs kNedStepNs = 50'000'000;  // 20 Hz, the basin paper's frame rate
constexpr double kNedDt = 0.05;
// The filter's recursion (Joseph form) and the textbook recursion iterated here agree to
// rounding, amplified by the few hundred steps of the recursion's memory.
constexpr double kNedRiccatiRelTol = 1e-9;
// Dense normal equations of ~300 unknowns with condition ~1e6 against the recursion.
constexpr double kBatchRelTol = 1e-7;

using Mat = Eigen::MatrixXd;
using Vec = Eigen::VectorXd;

BodyVelocityMeasurement vo_at(int k, double u, double v, double r, bool valid = true) {
  BodyVelocityMeasurement m;
  m.t_ns = k * kNedStepNs;
  m.valid = valid;
  m.dt_s = kNedDt;
  m.surge_m_s = u;
  m.sway_m_s = v;
  m.yaw_rate_rad_s = r;
  return m;
}

HeadingMeasurement heading_at(int k, double psi) { return {k * kNedStepNs, psi}; }

bool finite(const NedEstimate& e) { return e.x.allFinite() && e.P.allFinite(); }

// The linear model of one step, written out here from the paper's description: position moves
// by (u, v) rotated by the heading at mid-step, the heading by the VO yaw input.
NedMatrix phi_at(double psi_mid, double dt) {
  NedMatrix F = NedMatrix::Identity();
  F(0, 2) = dt * std::cos(psi_mid);
  F(0, 3) = -dt * std::sin(psi_mid);
  F(1, 2) = dt * std::sin(psi_mid);
  F(1, 3) = dt * std::cos(psi_mid);
  return F;
}

NedVector q_diag(const NedFilterOptions& o, double dt, double psi_input_var) {
  NedVector q;
  const double qp = o.position_noise_m_sqrt_s * o.position_noise_m_sqrt_s * dt;
  const double qv = o.velocity_noise_m_s_sqrt_s * o.velocity_noise_m_s_sqrt_s * dt;
  q << qp, qp, qv, qv, o.heading_noise_rad_sqrt_s * o.heading_noise_rad_sqrt_s * dt + psi_input_var;
  return q;
}

double r_uv(const NedFilterOptions& o) {
  return (*o.vo_increment_noise_m / kNedDt) * (*o.vo_increment_noise_m / kNedDt);
}

void ned_expect_rel_near(double actual, double expected, double rel, const std::string& what) {
  EXPECT_NEAR(actual, expected, rel * std::abs(expected) + 1e-300) << what;
}

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
// Kalman filter: Riccati and batch least squares

struct NedSteadyState {
  NedMatrix P;  // posterior
};

// Discrete algebraic Riccati equation by fixed-point iteration of the textbook recursion
// (standard form, all measurements at once: a different computation from the filter's
// sequential Joseph-form updates).
NedMatrix solve_riccati(const NedMatrix& F, const NedVector& q,
                        const Eigen::Matrix<double, 3, 5>& H, const Eigen::Vector3d& r) {
  NedMatrix P = NedMatrix::Identity();
  const NedMatrix Q = q.asDiagonal();
  const Eigen::Matrix3d R = r.asDiagonal();
  for (int it = 0; it < 1'000'000; ++it) {
    const NedMatrix Pp = F * P * F.transpose() + Q;
    const Eigen::Matrix3d S = H * Pp * H.transpose() + R;
    const Eigen::Matrix<double, 5, 3> K = Pp * H.transpose() * S.inverse();
    const NedMatrix Pn = (NedMatrix::Identity() - K * H) * Pp;
    const bool done = (Pn - P).cwiseAbs().maxCoeff() <= 4 * kEps * Pn.cwiseAbs().maxCoeff();
    P = Pn;
    if (done) break;
  }
  return P;
}

TEST(NedKalmanFilterTest, CovarianceConvergesToTheDiscreteRiccatiSolution) {
  // Constant heading (measured exactly, so the estimate, and Phi with it, never moves): the
  // filter is then time-invariant and its covariance must reach the Riccati solution, whatever
  // the velocity data.
  NedFilterOptions o;
  o.position_noise_m_sqrt_s = 0.03;
  o.velocity_noise_m_s_sqrt_s = 0.2;
  o.heading_noise_rad_sqrt_s = 0.004;
  o.vo_increment_noise_m = 0.004;
  o.compass_noise_rad = 0.02;
  const double psi0 = 0.7;
  NedKalmanFilter kf(o, NedState{.heading_rad = psi0});
  Rng rng(11);
  NedEstimate e;
  for (int k = 0; k < 4000; ++k)
    e = kf.step(vo_at(k, 1.0 + rng.normal(0, 0.1), rng.normal(0, 0.1), 0.0), heading_at(k, psi0));
  ASSERT_EQ(e.heading_rad(), psi0);

  const double var_dpsi = *o.vo_yaw_increment_noise_rad * *o.vo_yaw_increment_noise_rad;
  Eigen::Matrix<double, 3, 5> H = Eigen::Matrix<double, 3, 5>::Zero();
  H(0, 2) = H(1, 3) = H(2, 4) = 1.0;
  const NedVector q = q_diag(o, kNedDt, var_dpsi);
  const Eigen::Vector3d r(r_uv(o), r_uv(o), *o.compass_noise_rad * *o.compass_noise_rad);
  const NedMatrix P = solve_riccati(phi_at(psi0, kNedDt), q, H, r);
  // North and east are never measured: their variance grows without bound; the rest converges.
  for (int i = 2; i < 5; ++i) {
    for (int j = 2; j < 5; ++j) {
      ned_expect_rel_near(e.P(i, j), P(i, j), kNedRiccatiRelTol,
                          "P(" + std::to_string(i) + "," + std::to_string(j) + ")");
    }
  }
  // The heading filter alone is a scalar random walk measured directly: its steady prior
  // variance solves Pp^2 - q Pp - q r = 0, and the posterior is Pp r / (Pp + r).
  const double qh = q(4), rh = r(2);
  const double Pp = 0.5 * (qh + std::sqrt(qh * qh + 4.0 * qh * rh));
  ned_expect_rel_near(e.P(4, 4), Pp * rh / (Pp + rh), kNedRiccatiRelTol,
                      "closed-form heading variance");
  EXPECT_LT(e.P(2, 2), r(0));  // the smoothing: better than one VO velocity
  // Position uncertainty grows by about q_p dt + u-coupling per step.
  const NedEstimate next = kf.step(vo_at(4000, 1.0, 0.0, 0.0), heading_at(4000, psi0));
  EXPECT_GT(next.P(0, 0), e.P(0, 0));
}

// Weighted least squares over the whole trajectory x_0..x_K: prior on x_0, one dynamics
// residual per step (Q_k), one residual per measured component. Its solution's last state and the
// matching block of the inverse information matrix are what the Kalman filter must give at K.
struct BatchProblem {
  std::vector<NedMatrix> F;  // F[k], k >= 1: step k-1 -> k
  std::vector<NedVector> b;  // input added at step k
  std::vector<NedVector> q;  // diagonal of Q_k
  std::vector<bool> vo_valid;
  std::vector<double> u, v, psi;  // measurements at step k
  NedVector x0;
  NedVector p0;  // prior variances
  double r_uv = 0, r_psi = 0;
};

void batch_solve(const BatchProblem& bp, int K, NedVector* x_last, NedMatrix* P_last) {
  const int n = 5 * (K + 1);
  Mat A = Mat::Zero(n, n);
  Vec g = Vec::Zero(n);
  auto add = [&](const Eigen::RowVectorXd& row, double y, double w) {
    // row: over all unknowns; residual y - row x, weight w = 1 / variance.
    A += w * row.transpose() * row;
    g += w * row.transpose() * y;
  };
  for (int j = 0; j < 5; ++j) {
    Eigen::RowVectorXd row = Eigen::RowVectorXd::Zero(n);
    row(j) = 1.0;
    add(row, bp.x0(j), 1.0 / bp.p0(j));
  }
  for (int k = 1; k <= K; ++k) {
    for (int j = 0; j < 5; ++j) {
      Eigen::RowVectorXd row = Eigen::RowVectorXd::Zero(n);
      row(5 * k + j) = 1.0;
      row.segment<5>(5 * (k - 1)) = -bp.F[static_cast<std::size_t>(k)].row(j);
      add(row, bp.b[static_cast<std::size_t>(k)](j), 1.0 / bp.q[static_cast<std::size_t>(k)](j));
    }
  }
  for (int k = 0; k <= K; ++k) {
    const auto kk = static_cast<std::size_t>(k);
    Eigen::RowVectorXd row = Eigen::RowVectorXd::Zero(n);
    if (bp.vo_valid[kk]) {
      row(5 * k + 2) = 1.0;
      add(row, bp.u[kk], 1.0 / bp.r_uv);
      row.setZero();
      row(5 * k + 3) = 1.0;
      add(row, bp.v[kk], 1.0 / bp.r_uv);
      row.setZero();
    }
    row(5 * k + 4) = 1.0;
    add(row, bp.psi[kk], 1.0 / bp.r_psi);
  }
  const Vec x = A.ldlt().solve(g);
  const Mat cov = A.inverse();
  *x_last = x.segment<5>(5 * K);
  *P_last = cov.block<5, 5>(5 * K, 5 * K);
}

TEST(NedKalmanFilterTest, EqualsTheBatchLeastSquaresSolutionOfTheSameData) {
  // A turning vessel (0.05 rad/s) with noisy VO velocities, a VO gap (the yaw rate is held and
  // its uncertainty inflated) and compass headings equal to the true heading: the heading
  // estimate then follows the truth exactly, so Phi_k is known in advance and the problem is
  // linear-Gaussian, with time-varying Phi_k.
  NedFilterOptions o;
  const double psi0 = -2.9, r = 0.05;  // crosses +-pi during the run
  NedKalmanFilter kf(
      o, NedState{.north_m = 3.0, .east_m = -1.0, .surge_m_s = 0.8, .heading_rad = psi0});
  constexpr int K = 60;
  BatchProblem bp;
  bp.x0 << 3.0, -1.0, 0.8, 0.0, psi0;
  const double sp = o.initial_position_sd_m, sv = o.initial_velocity_sd_m_s,
               sh = o.initial_heading_sd_rad;
  bp.p0 << sp * sp, sp * sp, sv * sv, sv * sv, sh * sh;
  bp.r_uv = r_uv(o);
  bp.r_psi = *o.compass_noise_rad * *o.compass_noise_rad;
  bp.F.resize(K + 1);
  bp.b.resize(K + 1);
  bp.q.resize(K + 1);
  Rng rng(5);
  std::vector<NedEstimate> kf_out;
  double psi_true = psi0;  // unwrapped
  for (int k = 0; k <= K; ++k) {
    const bool valid = !(k >= 20 && k < 24);
    if (k > 0) {
      const auto kk = static_cast<std::size_t>(k);
      bp.F[kk] = phi_at(psi_true + 0.5 * r * kNedDt, kNedDt);
      bp.b[kk] = NedVector::Zero();
      bp.b[kk](4) = r * kNedDt;
      const double var_dpsi = valid ? *o.vo_yaw_increment_noise_rad * *o.vo_yaw_increment_noise_rad
                                    : (o.unmeasured_yaw_rate_sd_rad_s * kNedDt) *
                                          (o.unmeasured_yaw_rate_sd_rad_s * kNedDt);
      bp.q[kk] = q_diag(o, kNedDt, var_dpsi);
      psi_true += r * kNedDt;
    }
    const double u = 0.8 + rng.normal(0.0, 0.1), v = 0.05 + rng.normal(0.0, 0.1);
    bp.vo_valid.push_back(valid);
    bp.u.push_back(u);
    bp.v.push_back(v);
    // The filter wraps its heading; the batch problem works with the unwrapped one, and the
    // compass reports it wrapped.
    bp.psi.push_back(psi_true);
    kf_out.push_back(kf.step(vo_at(k, valid ? u : std::nan(""), v, r, valid),
                             heading_at(k, wrap_angle_rad(psi_true))));
  }
  for (int k : {10, 22, K}) {
    NedVector x;
    NedMatrix P;
    batch_solve(bp, k, &x, &P);
    const NedEstimate& e = kf_out[static_cast<std::size_t>(k)];
    const std::string at = "step " + std::to_string(k);
    for (int i = 0; i < 4; ++i) {
      EXPECT_NEAR(e.x(i), x(i), kBatchRelTol * (1.0 + std::abs(x(i)))) << at << " state " << i;
    }
    EXPECT_NEAR(e.x(4), wrap_angle_rad(x(4)), kBatchRelTol) << at << " heading";
    for (int i = 0; i < 5; ++i)
      for (int j = 0; j < 5; ++j)
        EXPECT_NEAR(e.P(i, j), P(i, j), kBatchRelTol * std::sqrt(P(i, i) * P(j, j)))
            << at << " P(" << i << "," << j << ")";
  }
  // During the gap velocities are predicted only and their variance grows.
  EXPECT_FALSE(kf_out[21].vo_fused);
  EXPECT_GT(kf_out[23].P(2, 2), kf_out[19].P(2, 2));
  EXPECT_EQ(kf.nonfinite_guards(), 0);
}

TEST(NedKalmanFilterTest, PredictionIsEquationsTwoAndThreeWithOrWithoutTheHeadingColumn) {
  // One prediction-only step (no VO, no compass) from the prior, against Eqs. (2)-(3) written
  // out here: the paper's linear Phi, and the extended KF's Phi with d(N, E)/d psi.
  for (bool jacobian : {false, true}) {
    NedFilterOptions o;
    o.heading_jacobian = jacobian;
    const NedState init{
        .north_m = 1.0, .east_m = 2.0, .surge_m_s = 1.5, .sway_m_s = -0.3, .heading_rad = 0.4};
    NedKalmanFilter kf(o, init);
    const NedMatrix P0 = kf.covariance();
    kf.step(vo_at(0, 0.0, 0.0, 0.0, false));
    const NedEstimate e = kf.step(vo_at(1, 0.0, 0.0, 0.0, false));
    NedMatrix F = phi_at(0.4, kNedDt);  // no yaw rate yet: the held rate is 0
    if (jacobian) {
      F(0, 4) = -kNedDt * (1.5 * std::sin(0.4) + -0.3 * std::cos(0.4));
      F(1, 4) = kNedDt * (1.5 * std::cos(0.4) - -0.3 * std::sin(0.4));
    }
    const double s = o.unmeasured_yaw_rate_sd_rad_s * kNedDt;
    const NedMatrix P1 = F * P0 * F.transpose() + NedMatrix(q_diag(o, kNedDt, s * s).asDiagonal());
    NedVector x1 = init.vector();
    x1(0) += kNedDt * (1.5 * std::cos(0.4) + 0.3 * std::sin(0.4));
    x1(1) += kNedDt * (1.5 * std::sin(0.4) - 0.3 * std::cos(0.4));
    EXPECT_LT((e.x - x1).norm(), 1e-14) << jacobian;
    EXPECT_LT((e.P - P1).norm(), 1e-14 * P1.norm()) << jacobian;
    EXPECT_EQ(e.P(0, 4) != 0.0, jacobian);  // only the EKF couples position and heading
  }
}

// ---------------------------------------------------------------------------------------------
// Particle filter against the Kalman filter

struct LinearRun {
  std::vector<BodyVelocityMeasurement> vo;
  std::vector<HeadingMeasurement> heading;
};

// A straight run at constant heading with noisy VO velocities and a precise compass: heading
// uncertainty then barely reaches the positions, and the model the PF samples is, for practical
// purposes, the KF's linear-Gaussian one.
LinearRun linear_run(int steps, std::uint64_t seed, const NedFilterOptions& o, double psi0) {
  LinearRun run;
  Rng rng = RngStreams(seed).stream("test.ned.data");
  const double su = *o.vo_increment_noise_m / kNedDt;
  for (int k = 0; k < steps; ++k) {
    run.vo.push_back(vo_at(k, 1.0 + rng.normal(0, su), 0.1 + rng.normal(0, su),
                           rng.normal(0.0, *o.vo_yaw_increment_noise_rad / kNedDt), k % 17 != 9));
    run.heading.push_back(heading_at(k, psi0 + rng.normal(0.0, *o.compass_noise_rad)));
  }
  return run;
}

NedFilterOptions linear_options() {
  NedFilterOptions o;
  o.compass_noise_rad = 3e-4;
  o.heading_noise_rad_sqrt_s = 1e-4;
  return o;
}

// The particles' own position estimate (the paper's Eq. (10)) unless told otherwise: the
// Monte-Carlo tests below are about the particles.
NedParticleFilter make_pf(const NedFilterOptions& o, int particles, PfResampling resampling,
                          std::uint64_t seed, const NedState& init,
                          PfPosition position = PfPosition::kParticles) {
  NedParticleFilterOptions po;
  static_cast<NedFilterOptions&>(po) = o;
  po.particles = particles;
  po.resampling = resampling;
  po.position = position;
  return NedParticleFilter(po, RngStreams(seed).stream("test.pf"), init);
}

TEST(NedParticleFilterTest, MatchesTheKalmanFilterWithinMonteCarloError) {
  // Independent PF runs (different seeds) on the same data: their spread is the PF's
  // Monte-Carlo error, and the mean over runs must agree with the KF within it. Per step and
  // state, t = (mean - KF) / (sd / sqrt(R)); without a bias, t follows Student's t with R - 1
  // degrees of freedom, E[t^2] = (R - 1) / (R - 3) = 1.3 for R = 10; the bound 3.5 allows for the
  // steps' strong correlation (a slowly varying position is nearly one draw of t); it resolves
  // biases down to ~0.2 posterior standard deviations, and a wrong sign or frame in the PF's
  // model gives t of tens. Positions are never measured, so resampling keeps collapsing their
  // spread (path degeneracy): their Monte-Carlo error is far larger than sqrt(P / N) and the
  // particles' own spread underestimates P; both are printed, and only the observed states'
  // spread is held to the KF's covariance.
  constexpr int kRuns = 10, kSteps = 120, kParticles = 1000;
  const NedFilterOptions o = linear_options();
  const double psi0 = 0.3;
  const NedState init{.surge_m_s = 1.0, .heading_rad = psi0};
  for (PfResampling scheme : {PfResampling::kMultinomial, PfResampling::kSystematicEss}) {
    const std::string name(yaml::enum_name(scheme));
    for (std::uint64_t data_seed : {100u, 101u}) {
      const LinearRun run = linear_run(kSteps, data_seed, o, psi0);
      NedKalmanFilter kf(o, init);
      std::vector<NedEstimate> ref;
      for (int k = 0; k < kSteps; ++k) {
        const auto kk = static_cast<std::size_t>(k);
        ref.push_back(kf.step(run.vo[kk], run.heading[kk]));
      }
      std::vector<std::vector<NedEstimate>> pf_runs;
      for (int s = 0; s < kRuns; ++s) {
        NedParticleFilter pf =
            make_pf(o, kParticles, scheme, 7 + static_cast<std::uint64_t>(s), init);
        std::vector<NedEstimate> out;
        for (int k = 0; k < kSteps; ++k) {
          const auto kk = static_cast<std::size_t>(k);
          out.push_back(pf.step(run.vo[kk], run.heading[kk]));
        }
        pf_runs.push_back(std::move(out));
      }
      NedVector t2 = NedVector::Zero(), mc_over_ideal = NedVector::Zero(),
                var_ratio = NedVector::Zero();
      int samples = 0;
      for (int k = 5; k < kSteps; ++k) {
        const auto kk = static_cast<std::size_t>(k);
        for (int i = 0; i < 5; ++i) {
          double sum = 0.0, sum2 = 0.0, var = 0.0;
          for (const auto& r : pf_runs) {
            double d = r[kk].x(i) - ref[kk].x(i);
            if (i == ned::kHeading) d = wrap_angle_rad(d);
            sum += d;
            sum2 += d * d;
            var += r[kk].P(i, i);
          }
          const double mean = sum / kRuns;
          const double sd2 = (sum2 - kRuns * mean * mean) / (kRuns - 1);
          t2(i) += mean * mean / (sd2 / kRuns);
          mc_over_ideal(i) += std::sqrt(sd2 / (ref[kk].P(i, i) / kParticles));
          var_ratio(i) += var / kRuns / ref[kk].P(i, i);
        }
        ++samples;
      }
      for (int i = 0; i < 5; ++i) {
        const double rms_t = std::sqrt(t2(i) / samples);
        std::printf(
            "[  metrics ] %s data %llu state %d: RMS t %.2f, MC error / sqrt(P/N) %.1f, "
            "particle variance / P %.3f\n",
            name.c_str(), static_cast<unsigned long long>(data_seed), i, rms_t,
            mc_over_ideal(i) / samples, var_ratio(i) / samples);
        const std::string what = name + " state " + std::to_string(i);
        EXPECT_LT(rms_t, 3.5) << what;
        if (i >= ned::kSurge) {
          EXPECT_NEAR(var_ratio(i) / samples, 1.0, 0.1) << what;
        }
      }
    }
  }
}

TEST(NedParticleFilterTest, IntegratedPositionFollowsTheKalmanFilterFarCloserThanTheParticles) {
  // The default position estimate moves the previous one by the weighted mean velocity and
  // heading (Eq. (7)), as the KF's prediction does: no Monte-Carlo error of never-measured
  // particle positions. Against the KF (the optimal estimate of this linear model) what is left
  // is the Monte-Carlo error of the mean velocity and heading, integrated: measured within 0.26
  // of the KF's own position standard deviation (0.14 on the second data set), and 3.7 and 8.6
  // times closer (RMS) than the particles' mean (the paper's Eq. (10)) with the same seed.
  constexpr int kSteps = 120;
  const NedFilterOptions o = linear_options();
  const NedState init{.surge_m_s = 1.0, .heading_rad = 0.3};
  for (std::uint64_t data_seed : {100u, 101u}) {
    const LinearRun run = linear_run(kSteps, data_seed, o, 0.3);
    NedKalmanFilter kf(o, init);
    NedParticleFilter integrated =
        make_pf(o, 1000, PfResampling::kMultinomial, 7, init, PfPosition::kIntegrated);
    NedParticleFilter particles = make_pf(o, 1000, PfResampling::kMultinomial, 7, init);
    double worst_ratio = 0, err_integrated = 0, err_particles = 0;
    for (int k = 0; k < kSteps; ++k) {
      const auto kk = static_cast<std::size_t>(k);
      const NedEstimate r = kf.step(run.vo[kk], run.heading[kk]);
      const NedEstimate a = integrated.step(run.vo[kk], run.heading[kk]);
      const NedEstimate b = particles.step(run.vo[kk], run.heading[kk]);
      const double sd = std::sqrt(r.P(ned::kNorth, ned::kNorth) + r.P(ned::kEast, ned::kEast));
      const double da = (a.x.head<2>() - r.x.head<2>()).norm();
      worst_ratio = std::max(worst_ratio, da / sd);
      err_integrated += da * da;
      err_particles += (b.x.head<2>() - r.x.head<2>()).squaredNorm();
    }
    std::printf(
        "[  metrics ] data %llu: integrated |PF - KF| <= %.3f sd; RMS %.2g m against "
        "the particles' %.2g m\n",
        static_cast<unsigned long long>(data_seed), worst_ratio, std::sqrt(err_integrated / kSteps),
        std::sqrt(err_particles / kSteps));
    EXPECT_LT(worst_ratio, 0.35);
    EXPECT_LT(std::sqrt(err_integrated), 0.4 * std::sqrt(err_particles));
  }
}

TEST(NedParticleFilterTest, MonteCarloErrorOfTheMeasuredStatesShrinksAsOneOverSqrtN) {
  // For the measured states (u, v, heading) the PF's error against the KF is Monte-Carlo error
  // of order sqrt(P / N) times an inefficiency factor of a few; with 16 times the particles it
  // must shrink about 4 times (a bias would not shrink).
  constexpr int kSteps = 120, kSeeds = 4;
  const NedFilterOptions o = linear_options();
  const double psi0 = 0.3;
  const NedState init{.surge_m_s = 1.0, .heading_rad = psi0};
  auto normalised_rms = [&](int particles) {
    NedVector e2 = NedVector::Zero();
    int samples = 0;
    for (int s = 0; s < kSeeds; ++s) {
      const LinearRun run = linear_run(kSteps, 200 + static_cast<std::uint64_t>(s), o, psi0);
      NedKalmanFilter kf(o, init);
      NedParticleFilter pf = make_pf(o, particles, PfResampling::kSystematicEss,
                                     30 + static_cast<std::uint64_t>(s), init);
      for (int k = 0; k < kSteps; ++k) {
        const auto kk = static_cast<std::size_t>(k);
        const NedEstimate a = kf.step(run.vo[kk], run.heading[kk]);
        const NedEstimate b = pf.step(run.vo[kk], run.heading[kk]);
        if (k < 5) continue;
        for (int i = ned::kSurge; i < 5; ++i) {
          const double d = wrap_angle_rad(b.x(i) - a.x(i));
          e2(i) += d * d / (a.P(i, i) / particles);
        }
        ++samples;
      }
    }
    return NedVector((e2 / samples).cwiseSqrt());
  };
  const NedVector big = normalised_rms(16000), small = normalised_rms(1000);
  for (int i = ned::kSurge; i < 5; ++i) {
    std::printf("[  metrics ] state %d: RMS error / sqrt(P/N) %.2f (N=16000), %.2f (N=1000)\n", i,
                big(i), small(i));
    EXPECT_LT(big(i), 8.0) << i;
    EXPECT_LT(small(i), 8.0) << i;
    const double shrink = small(i) / big(i) * 4.0;  // ratio of the absolute errors
    EXPECT_GT(shrink, 2.0) << i;
    EXPECT_LT(shrink, 8.0) << i;
  }
}

TEST(NedParticleFilterTest, SystematicEssResamplesLessOftenThanTheMultinomialScheme) {
  const NedFilterOptions o = linear_options();
  const LinearRun run = linear_run(200, 3, o, 0.0);
  NedParticleFilterOptions po;
  static_cast<NedFilterOptions&>(po) = o;
  po.resampling = PfResampling::kMultinomial;
  NedParticleFilter paper(po, Rng(1));
  po.resampling = PfResampling::kSystematicEss;
  po.ess_threshold = 0.5;
  NedParticleFilter ess(po, Rng(1));
  for (std::size_t k = 0; k < run.vo.size(); ++k) {
    const NedEstimate a = paper.step(run.vo[k], run.heading[k]);
    const NedEstimate b = ess.step(run.vo[k], run.heading[k]);
    EXPECT_TRUE(a.resampled);
    // systematic_ess resamples exactly when the ESS falls below the threshold.
    EXPECT_EQ(b.resampled, b.effective_sample_size < 0.5 * po.particles) << k;
    EXPECT_GT(b.effective_sample_size, 0.0);
    EXPECT_LE(b.effective_sample_size, po.particles * (1 + 1e-12));
  }
  EXPECT_EQ(paper.resample_count(), 200);
  EXPECT_LT(ess.resample_count(), 200);
  EXPECT_GT(ess.resample_count(), 0);
}

TEST(NedParticleFilterTest, PaperAverageLikelihoodIsTheAverageOfTheComponentDensities) {
  // Two particles only, one VO step: the weights are the likelihoods normalised (Eq. (9)); for
  // Eq. (8)'s average they follow from the densities written out here.
  NedParticleFilterOptions po;
  po.particles = 2;
  po.likelihood = PfLikelihood::kPaperAverage;
  po.resampling = PfResampling::kSystematicEss;
  po.ess_threshold = 0.0;  // never resample: the weights stay visible
  NedParticleFilter pf(po, Rng(3));
  const auto particles = pf.particles();
  const std::vector<NedVector> before(particles.begin(), particles.end());
  const BodyVelocityMeasurement m = vo_at(0, 0.1, -0.2, 0.0);
  const HeadingMeasurement h = heading_at(0, 0.02);
  pf.step(m, h);  // first step: no prediction, the particles stay where they were drawn
  const double ruv = r_uv(po), rp = *po.compass_noise_rad * *po.compass_noise_rad;
  auto density = [](double res, double var) {
    return std::exp(-0.5 * res * res / var) / std::sqrt(2.0 * std::numbers::pi * var);
  };
  std::array<double, 2> l{};
  for (std::size_t i = 0; i < 2; ++i) {
    l[i] = (density(0.1 - before[i](2), ruv) + density(-0.2 - before[i](3), ruv) +
            density(0.02 - before[i](4), rp)) /
           3.0;
  }
  EXPECT_NEAR(pf.weights()[0], l[0] / (l[0] + l[1]), 1e-12);
  EXPECT_NEAR(pf.weights()[1], l[1] / (l[0] + l[1]), 1e-12);
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
