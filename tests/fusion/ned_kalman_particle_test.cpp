// Tests of the basin paper's Kalman and particle filters (fusion/ned_filters, Kucic & Valcic
// 2020, Eqs. (2)-(10)) against expectations computed here independently: the steady-state
// covariance from the discrete Riccati equation (fixed-point iteration, and the closed form of the
// scalar heading filter), the batch weighted least-squares solution of the same data, and the
// Kalman filter's answer for the particle filter, within its Monte-Carlo error.
#include "fusion/ned_filters.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "core/rng.hpp"
#include "core/rotation.hpp"
#include "core/yaml_io.hpp"
#include "tests/fusion/ned_fixtures.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab::fusion {
namespace {

using driftlab::test::kEps;
using fixtures::heading_at;
using fixtures::kNedDt;
using fixtures::linear_run;
using fixtures::LinearRun;
using fixtures::vo_at;

// The filter's recursion (Joseph form) and the textbook recursion iterated here agree to
// rounding, amplified by the few hundred steps of the recursion's memory.
constexpr double kNedRiccatiRelTol = 1e-9;
// Dense normal equations of ~300 unknowns with condition ~1e6 against the recursion.
constexpr double kBatchRelTol = 1e-7;

using Mat = Eigen::MatrixXd;
using Vec = Eigen::VectorXd;

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

}  // namespace
}  // namespace driftlab::fusion
