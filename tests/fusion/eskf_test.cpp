// Tests of the error-state Kalman filter (fusion/eskf) with expectations computed here: ground
// truth from the vessel simulator in waves, measurements from the synthetic IMU, compass and GPS
// (sim/sensors) and VO increments made here from the true camera poses. Checked: exact data are
// reproduced; with noise the filter is consistent (NEES within the chi-square band, averaged over
// seeds); a GPS outage lets the error grow and fixes bring it back; every analytic Jacobian
// matches finite differences per axis; bad input is refused clearly; invalid VO is skipped.
#include "fusion/eskf.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "core/rotation.hpp"
#include "core/yaml_io.hpp"
#include "sim/physics/vessel/simulator.hpp"
#include "sim/physics/waves/wave_field.hpp"
#include "sim/sensors/compass.hpp"
#include "sim/sensors/gps.hpp"
#include "sim/sensors/imu.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab::fusion {
namespace {

using driftlab::test::kDeg;
constexpr double kImuRateHz = 200.0;
constexpr double kCameraRateHz = 13.0;  // the default camera: frames fall between IMU samples
constexpr int kCompassEvery = 20;       // 10 Hz
constexpr int kGpsEvery = 200;          // 1 Hz
constexpr double kTruthSeconds = 130.0;

// ---------------------------------------------------------------------------------------------
// Ground truth: survey_boat in three regular waves (as the IMU strapdown test), surging, turning,
// heaving, rolling and pitching by several degrees.

struct Truth {
  std::vector<sim::BodySample> imu;  // at the IMU times
  std::vector<sim::BodySample> cam;  // at the camera times
};

Truth simulate_truth(double seconds) {
  const sim::VesselModel model(sim::VesselOptions{});
  sim::WaveOptions w;
  w.model = sim::WaveModel::kComponents;
  w.water_depth_m = 3.0;
  w.components = {
      {.amplitude_m = 0.065, .wavelength_m = 12.0, .direction_deg = 40},
      {.amplitude_m = 0.04, .wavelength_m = 8.0, .direction_deg = -70, .phase_deg = 30},
      {.amplitude_m = 0.025, .wavelength_m = 5.0, .direction_deg = 160, .phase_deg = 100}};
  const auto waves = sim::make_wave_field(w, RngStreams(7).stream("waves.phases"));
  sim::Environment env;
  env.waves = waves.get();
  sim::MotionOptions mo;
  mo.physics_rate_hz = 400;
  mo.max_duration_s = seconds;
  mo.fixed_inputs.thrust_command_n = {14.0, 9.0};
  const std::vector<TimeNs> ti = sim::sample_times(kImuRateHz, seconds);
  const std::vector<TimeNs> tc = sim::sample_times(kCameraRateHz, seconds);
  std::vector<TimeNs> all(ti);
  all.insert(all.end(), tc.begin(), tc.end());
  std::sort(all.begin(), all.end());
  all.erase(std::unique(all.begin(), all.end()), all.end());
  Truth t;
  std::size_t ii = 0, ic = 0;
  sim::simulate(model, env, nullptr, sim::initial_state(model, sim::Vec2(5, -3), 0.4), mo, all,
                nullptr, [&](const sim::BodySample& b) {
                  if (ii < ti.size() && ti[ii] == b.t_ns) {
                    t.imu.push_back(b);
                    ++ii;
                  }
                  if (ic < tc.size() && tc[ic] == b.t_ns) {
                    t.cam.push_back(b);
                    ++ic;
                  }
                });
  return t;
}

// The truth of at least `seconds`, simulated once per process for each of a few lengths, so that
// a test run alone (ctest runs each test in its own process) pays only for what it needs. The
// simulation is deterministic: a shorter run is the start of a longer one.
const Truth& wavy_truth(double seconds) {
  static const Truth short_run = simulate_truth(10.0);
  if (seconds <= 10.0) return short_run;
  static const Truth minute = simulate_truth(60.0);
  if (seconds <= 60.0) return minute;
  static const Truth long_run = simulate_truth(kTruthSeconds);
  return long_run;
}

// The IMU frame's true state from the body's and the IMU mount (r: lever arm in body).
EskfState truth_state(const sim::BodySample& b, const SE3& T_B_S, const Vec3& accel_bias,
                      const Vec3& gyro_bias) {
  EskfState s;
  s.t_ns = b.t_ns;
  const Vec3& r = T_B_S.translation();
  s.q_W_I = b.state.q_W_B * T_B_S.quaternion();
  s.p_W_m = b.state.p_W + b.state.q_W_B * r;
  s.v_W_m_s = b.state.q_W_B * (b.state.v_B + b.state.w_B.cross(r));
  s.accel_bias_m_s2 = accel_bias;
  s.gyro_bias_rad_s = gyro_bias;
  return s;
}

// The error truth [-] estimate in the filter's convention, written out here with Eigen's
// angle-axis (not the library's so3_log).
Vec15 error_of(const EskfState& est, const EskfState& truth) {
  Vec15 e;
  e.segment<3>(0) = truth.p_W_m - est.p_W_m;
  e.segment<3>(3) = truth.v_W_m_s - est.v_W_m_s;
  const Eigen::AngleAxisd aa(est.q_W_I.conjugate() * truth.q_W_I);
  e.segment<3>(6) = aa.angle() * aa.axis();
  e.segment<3>(9) = truth.accel_bias_m_s2 - est.accel_bias_m_s2;
  e.segment<3>(12) = truth.gyro_bias_rad_s - est.gyro_bias_rad_s;
  return e;
}

Quat exp_aa(const Vec3& w) {
  const double a = w.norm();
  return a == 0.0 ? Quat::Identity() : Quat(Eigen::AngleAxisd(a, w / a));
}

// ---------------------------------------------------------------------------------------------
// One filter run over the wavy truth.

struct RunConfig {
  double seconds = 60.0;
  bool noise = true;  // IMU mpu9250 with turn-on biases, noisy VO and compass; else all exact
  bool use_gps = true;
  bool use_compass = true;
  double gps_off_from_s = -1.0, gps_off_to_s = -1.0;  // the bridge: no fixes in [from, to)
  double gps_sigma_m = 1.5;
  sim::MountOptions imu_mount;
  int invalid_vo_every = 0;  // every n-th frame's VO fails (0: none)
  EskfOptions filter;
};

struct FrameRecord {
  double t_s = 0.0;
  Vec15 error = Vec15::Zero();  // truth [-] estimate
  Mat15 P = Mat15::Zero();
  bool gps_on = true;
};

struct RunResult {
  std::vector<FrameRecord> frames;
  EskfStats stats;
  EskfState final_state;
};

SE3 camera_in_body() {
  // Forward-looking, pitched 5 deg down, 1 m ahead of the CG, 0.2 m to starboard, 0.6 m up.
  const Mat3 R = R_frd_optical() * Eigen::AngleAxisd(-5 * kDeg, Vec3::UnitX()).toRotationMatrix();
  return SE3(R, Vec3(1.0, 0.2, -0.6));
}

RunResult run_eskf(const RunConfig& cfg, std::uint64_t seed) {
  const Truth& truth = wavy_truth(cfg.seconds);
  const RngStreams rng(seed);
  const EskfOptions& fo = cfg.filter;

  sim::ImuOptions io = sim::ImuOptions::preset_defaults(cfg.noise ? sim::ImuPreset::kMpu9250
                                                                  : sim::ImuPreset::kIdeal);
  io.rate_hz = kImuRateHz;
  io.mount = cfg.imu_mount;
  if (cfg.noise) {
    // The switch-on biases are drawn with the filter's prior, so the initial error is N(0, P0).
    io.gyro_turn_on_bias_rad_s = fo.initial_gyro_bias_sd_rad_s;
    io.accel_turn_on_bias_m_s2 = fo.initial_accel_bias_sd_m_s2;
  }
  sim::ImuSimulator imu(io, rng);
  sim::CompassOptions co;
  co.sigma_deg = cfg.noise ? *fo.compass_noise_rad / kDeg : 0.0;
  sim::CompassSimulator compass(co, rng);
  sim::GpsOptions go;
  go.sigma_horizontal_m = cfg.gps_sigma_m;
  sim::GpsSimulator gps(go, rng);
  Rng vo_rng = rng.stream("test.vo");
  Rng init_rng = rng.stream("test.init");

  const sim::SensorMount imu_mount = sim::SensorMount::from_options(io.mount);
  const SE3 T_B_S = imu_mount.T_B_S();
  const SE3 T_B_C = camera_in_body();
  EskfExtrinsics ex;
  ex.T_I_C = T_B_S.inverse() * T_B_C;
  ex.p_I_antenna_m =
      T_B_S.inverse() * Vec3(go.antenna_frd_m[0], go.antenna_frd_m[1], go.antenna_frd_m[2]);
  ex.R_I_M = T_B_S.rotation().transpose();  // the compass sits level in the body

  // Initial estimate: the truth moved by an error drawn from the prior (biases: the IMU's drawn
  // switch-on biases are the error, the estimate starts at zero).
  EskfState init = truth_state(truth.imu[0], T_B_S, Vec3::Zero(), Vec3::Zero());
  if (cfg.noise) {
    Vec3 ep, ev, et;
    for (int i = 0; i < 3; ++i) {
      ep(i) = init_rng.normal(0.0, fo.initial_position_sd_m);
      ev(i) = init_rng.normal(0.0, fo.initial_velocity_sd_m_s);
      et(i) = init_rng.normal(0.0, i < 2 ? fo.initial_roll_pitch_sd_rad : fo.initial_yaw_sd_rad);
    }
    init.p_W_m -= ep;
    init.v_W_m_s -= ev;
    init.q_W_I = init.q_W_I * exp_aa(-et);
  }
  Eskf filter(fo, ex, init);

  const double su_t[3] = {fo.vo_translation_noise_m[0], fo.vo_translation_noise_m[1],
                          fo.vo_translation_noise_m[2]};
  const double su_r[3] = {fo.vo_rotation_noise_rad[0], fo.vo_rotation_noise_rad[1],
                          fo.vo_rotation_noise_rad[2]};
  RunResult out;
  const TimeNs end_ns = seconds_to_ns(cfg.seconds);
  std::size_t c = 0;
  SE3 T_W_C_prev;
  for (std::size_t i = 0; i < truth.imu.size() && truth.imu[i].t_ns <= end_ns; ++i) {
    const sim::BodySample& b = truth.imu[i];
    const auto s = imu.measure(b);
    EXPECT_TRUE(s.has_value());
    filter.propagate(*s);
    const double t_s = ns_to_seconds(b.t_ns);
    if (i % kCompassEvery == 0) {
      const auto m = compass.measure(b);
      if (cfg.use_compass && m) filter.update_heading({m->t_ns, m->heading_rad});
    }
    if (i % kGpsEvery == 0) {
      const auto f = gps.measure(b);  // the error process advances even under the bridge
      const bool bridge = t_s >= cfg.gps_off_from_s && t_s < cfg.gps_off_to_s;
      if (cfg.use_gps && f && f->fix && !bridge) {
        const sim::Dop dop = sim::dilution_of_precision(gps.visible_satellites(f->p_true_W, t_s));
        GpsPositionMeasurement g;
        g.t_ns = f->t_valid_ns;
        g.p_W_m = f->p_W;
        g.covariance_m2 = go.sigma_horizontal_m * go.sigma_horizontal_m * dop.position_cov_ned;
        filter.update_gps(g);
      }
    }
    const TimeNs next_ns = i + 1 < truth.imu.size() ? truth.imu[i + 1].t_ns : end_ns + 1;
    for (; c < truth.cam.size() && truth.cam[c].t_ns < next_ns && truth.cam[c].t_ns <= end_ns;
         ++c) {
      const sim::BodySample& bc = truth.cam[c];
      const SE3 T_W_C = bc.state.T_W_B() * T_B_C;
      vo::VoResult r;
      if (c == 0) {
        r.reason = "first frame";
      } else if (cfg.invalid_vo_every > 0 &&
                 c % static_cast<std::size_t>(cfg.invalid_vo_every) == 0) {
        r.reason = "too few inliers";
        r.T_prev_curr = SE3::exp(Vec6::Constant(0.3));  // must not be read
      } else {
        const SE3 T = T_W_C_prev.inverse() * T_W_C;
        Vec3 nt, nr;
        for (int k = 0; k < 3; ++k) {
          nt(k) = cfg.noise ? vo_rng.normal(0.0, su_t[k]) : 0.0;
          nr(k) = cfg.noise ? vo_rng.normal(0.0, su_r[k]) : 0.0;
        }
        r.valid = true;
        r.T_prev_curr = SE3(T.quaternion() * exp_aa(nr), T.translation() + nt);
      }
      T_W_C_prev = T_W_C;
      filter.update_vo(bc.t_ns, r);
      FrameRecord rec;
      rec.t_s = ns_to_seconds(bc.t_ns);
      rec.error =
          error_of(filter.state(), truth_state(bc, T_B_S, imu.accel().bias, imu.gyro().bias));
      rec.P = filter.covariance();
      rec.gps_on = !(rec.t_s >= cfg.gps_off_from_s && rec.t_s < cfg.gps_off_to_s);
      out.frames.push_back(rec);
    }
  }
  out.stats = filter.stats();
  out.final_state = filter.state();
  return out;
}

double nees(const FrameRecord& f) { return f.error.dot(f.P.ldlt().solve(f.error)); }

// Chi-square quantile by Wilson and Hilferty (1931), accurate to ~0.1 % for the hundreds of
// degrees of freedom used here.
double chi2_quantile(double dof, double z) {
  const double a = 2.0 / (9.0 * dof);
  return dof * std::pow(1.0 - a + z * std::sqrt(a), 3);
}

// ---------------------------------------------------------------------------------------------
// Acceptance over the wavy run

TEST(EskfTest, TheWavyRunIsRichEnoughToMeanSomething) {
  const Truth& t = wavy_truth(60.0);
  ASSERT_GE(t.imu.size(), static_cast<std::size_t>(60.0 * kImuRateHz));
  ASSERT_GE(t.cam.size(), static_cast<std::size_t>(60.0 * kCameraRateHz));
  double path = 0, max_roll = 0, max_pitch = 0, max_rate = 0;
  for (std::size_t i = 1; i < t.imu.size() && t.imu[i].t_ns <= seconds_to_ns(60); ++i) {
    path += (t.imu[i].state.p_W - t.imu[i - 1].state.p_W).norm();
    const EulerZYX e = euler_zyx_from_quat(t.imu[i].state.q_W_B);
    max_roll = std::max(max_roll, std::abs(e.roll_rad));
    max_pitch = std::max(max_pitch, std::abs(e.pitch_rad));
    max_rate = std::max(max_rate, t.imu[i].state.w_B.norm());
  }
  std::printf(
      "[  metrics ] 60 s: %.1f m of track, max roll %.1f deg, pitch %.1f deg, rate %.2f "
      "rad/s\n",
      path, max_roll / kDeg, max_pitch / kDeg, max_rate);
  EXPECT_GT(path, 10.0);
  EXPECT_GT(max_roll, 2 * kDeg);
  EXPECT_GT(max_pitch, 2 * kDeg);
}

TEST(EskfTest, NoiseFreeImuAndVoReproduceTheGroundTruth) {
  // Exact IMU (mounted off the CG and turned, so the extrinsics matter) and exact VO, no GPS, no
  // compass, started at the truth: what is left is the second-order integration error between
  // 200 Hz samples, which the exact VO increments keep in check.
  RunConfig cfg;
  cfg.noise = false;
  cfg.use_gps = false;
  cfg.use_compass = false;
  cfg.imu_mount.position_frd_m = {0.45, -0.2, -0.35};
  cfg.imu_mount.rpy_deg = {3, -5, 95};
  const RunResult r = run_eskf(cfg, 1);
  ASSERT_GT(r.frames.size(), 700u);
  double max_p = 0, max_v = 0, max_th = 0;
  for (const FrameRecord& f : r.frames) {
    ASSERT_TRUE(f.error.allFinite());
    max_p = std::max(max_p, f.error.segment<3>(0).norm());
    max_v = std::max(max_v, f.error.segment<3>(3).norm());
    max_th = std::max(max_th, f.error.segment<3>(6).norm());
  }
  std::printf(
      "[  metrics ] noise-free 60 s: max error position %.3g m, velocity %.3g m/s, "
      "attitude %.3g rad; %s\n",
      max_p, max_v, max_th, r.stats.brief().c_str());
  // Measured: 2.7e-5 m, 7.7e-5 m/s, 6.3e-6 rad over 53 m of track.
  EXPECT_LT(max_p, 3e-4);
  EXPECT_LT(max_v, 5e-4);
  EXPECT_LT(max_th, 5e-5);
  EXPECT_EQ(r.stats.vo_fused + 1, static_cast<std::int64_t>(r.frames.size()));
  EXPECT_EQ(r.stats.nonfinite_guards, 0);
}

TEST(EskfTest, NeesIsWithinTheChiSquareBandAveragedOverSeeds) {
  // 60 s, every sensor with the noise the filter assumes. At each frame the NEES averaged over M
  // seeds, times M, is chi-square with 15 M degrees of freedom when the filter is consistent
  // (Bar-Shalom, Li & Kirubarajan 2001, Sec. 5.4.2): its 95 % band must hold the average at
  // most frames, and the time-average must be near 15. Frames are strongly correlated (a
  // position error lasts tens of seconds), so both scatter far more than for independent
  // frames: over eight sets of 24 seeds the fraction inside was 87-100 % and the mean
  // 14.1-15.3 (6 dof: 86-100 %, 5.4-6.3), hence the bounds 80 % and +-12 %. A filter that
  // assumes 1.5x too little, or 1.7x too much, VO noise fails both (13-15 % inside).
  constexpr int kSeeds = 24;
  RunConfig cfg;
  cfg.invalid_vo_every = 37;
  std::vector<double> sum;
  std::vector<double> sum_pose;  // position and attitude only (6 dof)
  std::vector<double> t;
  std::array<double, 5> block_sum{};  // per 3-dof block: position, velocity, attitude, biases
  int samples = 0;
  for (int s = 0; s < kSeeds; ++s) {
    const RunResult r = run_eskf(cfg, 1000 + static_cast<std::uint64_t>(s));
    if (s == 0) {
      sum.assign(r.frames.size(), 0.0);
      sum_pose.assign(r.frames.size(), 0.0);
      for (const auto& f : r.frames) t.push_back(f.t_s);
      std::printf("[  metrics ] seed %d: %s\n", s, r.stats.brief().c_str());
    }
    ASSERT_EQ(r.frames.size(), sum.size());
    EXPECT_EQ(r.stats.nonfinite_guards, 0);
    for (std::size_t k = 0; k < r.frames.size(); ++k) {
      const FrameRecord& f = r.frames[k];
      ASSERT_TRUE(f.error.allFinite() && f.P.allFinite());
      sum[k] += nees(f);
      Eigen::Matrix<double, 6, 1> e;
      e << f.error.segment<3>(0), f.error.segment<3>(6);
      Eigen::Matrix<double, 6, 6> P;
      P << f.P.block<3, 3>(0, 0), f.P.block<3, 3>(0, 6), f.P.block<3, 3>(6, 0),
          f.P.block<3, 3>(6, 6);
      sum_pose[k] += e.dot(P.ldlt().solve(e));
      for (std::size_t b = 0; b < 5; ++b) {
        const Vec3 eb = f.error.segment<3>(3 * static_cast<int>(b));
        const Mat3 Pb = f.P.block<3, 3>(3 * static_cast<int>(b), 3 * static_cast<int>(b));
        block_sum[b] += eb.dot(Pb.ldlt().solve(eb));
      }
      ++samples;
    }
  }
  std::printf(
      "[  metrics ] mean NEES per 3-dof block: position %.2f, velocity %.2f, attitude "
      "%.2f, accel bias %.2f, gyro bias %.2f\n",
      block_sum[0] / samples, block_sum[1] / samples, block_sum[2] / samples,
      block_sum[3] / samples, block_sum[4] / samples);
  const double z = 1.959963984540054;
  for (int dim : {15, 6}) {
    const std::vector<double>& v = dim == 15 ? sum : sum_pose;
    const double lo = chi2_quantile(dim * kSeeds, -z) / kSeeds;
    const double hi = chi2_quantile(dim * kSeeds, z) / kSeeds;
    int inside = 0;
    double mean = 0;
    for (double x : v) {
      const double avg = x / kSeeds;
      inside += avg >= lo && avg <= hi;
      mean += avg;
    }
    mean /= static_cast<double>(v.size());
    const double fraction = static_cast<double>(inside) / static_cast<double>(v.size());
    std::printf(
        "[  metrics ] NEES (%d dof) averaged over %d seeds: mean %.2f, band [%.2f, %.2f], "
        "%.1f %% of %zu frames inside\n",
        dim, kSeeds, mean, lo, hi, 100 * fraction, v.size());
    EXPECT_GE(fraction, 0.80) << dim << " dof";
    EXPECT_NEAR(mean, dim, 0.12 * dim) << dim << " dof";
  }
}

TEST(EskfTest, PositionErrorGrowsUnderTheBridgeAndRecoversWhenFixesReturn) {
  // 130 s: fixes for 30 s, none for 60 s (a long bridge), fixes again. VO, IMU and compass carry
  // the filter through; the position error and the filter's own uncertainty grow, and both come
  // back once fixes return. RMS over seeds and frames in each window.
  constexpr int kSeeds = 6;
  RunConfig cfg;
  cfg.seconds = kTruthSeconds;
  cfg.gps_off_from_s = 30.0;
  cfg.gps_off_to_s = 90.0;
  cfg.gps_sigma_m = 0.3;
  cfg.filter.vo_translation_noise_m = {0.01, 0.01, 0.01};
  cfg.filter.vo_rotation_noise_rad = {1e-3, 1e-3, 1e-3};
  struct Window {
    double from, to;
    double e2 = 0, p2 = 0;
    int n = 0;
  };
  std::array<Window, 4> w{{{20, 30}, {80, 90}, {90, 95}, {110, 130}}};
  for (int s = 0; s < kSeeds; ++s) {
    const RunResult r = run_eskf(cfg, 77 + static_cast<std::uint64_t>(s));
    EXPECT_EQ(r.stats.nonfinite_guards, 0);
    for (const FrameRecord& f : r.frames) {
      for (Window& x : w) {
        if (f.t_s < x.from || f.t_s >= x.to) continue;
        x.e2 += f.error.head<2>().squaredNorm();
        x.p2 += f.P(0, 0) + f.P(1, 1);
        ++x.n;
      }
    }
  }
  for (const Window& x : w) {
    std::printf("[  metrics ] [%3.0f, %3.0f) s: horizontal error RMS %.3f m, filter sd %.3f m\n",
                x.from, x.to, std::sqrt(x.e2 / x.n), std::sqrt(x.p2 / x.n));
  }
  auto rms = [](const Window& x) { return std::sqrt(x.e2 / x.n); };
  auto sd = [](const Window& x) { return std::sqrt(x.p2 / x.n); };
  const Window &before = w[0], &bridge_end = w[1], &after = w[3];
  EXPECT_GT(rms(bridge_end), 2.0 * rms(before));
  EXPECT_GT(sd(bridge_end), 2.0 * sd(before));
  EXPECT_LT(rms(after), 1.5 * rms(before));
  EXPECT_LT(sd(after), 1.5 * sd(before));
  // The error stays within what the filter believes: a few sigma, in and after the outage.
  EXPECT_LT(rms(bridge_end), 3.0 * sd(bridge_end));
}

// ---------------------------------------------------------------------------------------------
// Jacobians by finite differences, one error-state axis at a time

EskfState some_state() {
  EskfState s;
  s.q_W_I = quat_from_euler_zyx({0.2, -0.35, 2.4});
  s.p_W_m = Vec3(12.0, -4.0, 0.7);
  s.v_W_m_s = Vec3(1.5, -0.8, 0.3);
  s.accel_bias_m_s2 = Vec3(0.05, -0.08, 0.12);
  s.gyro_bias_rad_s = Vec3(0.01, -0.02, 0.015);
  return s;
}

// state [+] eps e_j, written out here (Eigen's angle-axis for the attitude).
EskfState perturb(const EskfState& s, int j, double eps) {
  EskfState o = s;
  Vec3 d = Vec3::Zero();
  d(j % 3) = eps;
  switch (j / 3) {
    case 0:
      o.p_W_m += d;
      break;
    case 1:
      o.v_W_m_s += d;
      break;
    case 2:
      o.q_W_I = s.q_W_I * exp_aa(d);
      break;
    case 3:
      o.accel_bias_m_s2 += d;
      break;
    default:
      o.gyro_bias_rad_s += d;
      break;
  }
  return o;
}

TEST(EskfJacobianTest, PropagationMatchesFiniteDifferencesPerAxis) {
  const EskfState s = some_state();
  detail::ImuInput a{Vec3(0.3, -0.5, 0.8), Vec3(1.2, -0.7, -9.0)};
  detail::ImuInput b{Vec3(0.35, -0.45, 0.7), Vec3(1.0, -0.4, -10.1)};
  // A long step makes the h^2 terms (position from attitude and biases) count.
  for (double h : {0.005, 0.1}) {
    Mat15 F;
    const EskfState f0 = detail::propagate_nominal(s, a, b, h, 9.80665, &F);
    constexpr double eps = 1e-6;
    for (int j = 0; j < 15; ++j) {
      const EskfState fp = detail::propagate_nominal(perturb(s, j, eps), a, b, h, 9.80665, nullptr);
      const EskfState fm =
          detail::propagate_nominal(perturb(s, j, -eps), a, b, h, 9.80665, nullptr);
      const Vec15 col = (error_of(f0, fp) - error_of(f0, fm)) / (2 * eps);
      // Central differences: truncation ~eps^2, rounding ~1e-16 * |x| / eps.
      const double tol = 1e-7 * std::max(1.0, col.norm());
      EXPECT_LT((F.col(j) - col).norm(), tol)
          << "h " << h << ", axis " << j << ":\nanalytic " << F.col(j).transpose() << "\nnumeric  "
          << col.transpose();
    }
  }
}

TEST(EskfJacobianTest, VoGpsAndHeadingMeasurementsMatchFiniteDifferencesPerAxis) {
  const EskfState cur = some_state();
  EskfState clone = cur;
  clone.q_W_I = quat_from_euler_zyx({0.17, -0.31, 2.3});
  clone.p_W_m = cur.p_W_m - Vec3(0.12, -0.05, 0.01);
  const SE3 T_I_C(R_frd_optical() * quat_from_euler_zyx({0.02, -0.1, 0.05}).toRotationMatrix(),
                  Vec3(0.9, 0.25, -0.5));
  Eigen::Matrix<double, 6, 21> H;
  const SE3 z0 = detail::predict_vo(clone.q_W_I, clone.p_W_m, cur.q_W_I, cur.p_W_m, T_I_C, &H);
  // Independent check of the prediction itself.
  const SE3 expect = (clone.T_W_I() * T_I_C).inverse() * (cur.T_W_I() * T_I_C);
  EXPECT_TRUE(z0.is_approx(expect, 1e-12, 1e-12));
  constexpr double eps = 1e-6;
  for (int j = 0; j < 21; ++j) {
    auto predict = [&](double e) {
      EskfState c = cur, k = clone;
      if (j < 15) {
        c = perturb(cur, j, e);
      } else {
        // clone position (15-17) and attitude (18-20): perturb()'s axes 0-2 and 6-8
        k = perturb(clone, j < 18 ? j - 15 : j - 12, e);
      }
      return detail::predict_vo(k.q_W_I, k.p_W_m, c.q_W_I, c.p_W_m, T_I_C, nullptr);
    };
    auto residual_change = [&](const SE3& z) {
      Eigen::Matrix<double, 6, 1> d;
      d.head<3>() = z.translation() - z0.translation();
      const Eigen::AngleAxisd aa(z0.quaternion().conjugate() * z.quaternion());
      d.tail<3>() = aa.angle() * aa.axis();
      return d;
    };
    const Eigen::Matrix<double, 6, 1> col =
        (residual_change(predict(eps)) - residual_change(predict(-eps))) / (2 * eps);
    EXPECT_LT((H.col(j) - col).norm(), 1e-8 * std::max(1.0, col.norm()))
        << "VO axis " << j << ":\nanalytic " << H.col(j).transpose() << "\nnumeric  "
        << col.transpose();
  }

  const Vec3 antenna(0.3, -0.1, -1.2);
  const Mat3 R_I_M = quat_from_euler_zyx({0.05, 0.1, -1.4}).toRotationMatrix();
  Eigen::Matrix<double, 3, 15> Hg;
  Eigen::Matrix<double, 1, 15> Hh;
  const Vec3 g0 = detail::predict_gps(cur.q_W_I, cur.p_W_m, antenna, &Hg);
  const double h0 = detail::predict_heading(cur.q_W_I, R_I_M, &Hh);
  EXPECT_TRUE(g0.isApprox(cur.p_W_m + cur.q_W_I * antenna, 1e-14));
  EXPECT_NEAR(h0, euler_zyx_from_matrix(cur.q_W_I.toRotationMatrix() * R_I_M).yaw_rad, 1e-12);
  for (int j = 0; j < 15; ++j) {
    const EskfState p = perturb(cur, j, eps), m = perturb(cur, j, -eps);
    const Vec3 cg = (detail::predict_gps(p.q_W_I, p.p_W_m, antenna, nullptr) -
                     detail::predict_gps(m.q_W_I, m.p_W_m, antenna, nullptr)) /
                    (2 * eps);
    EXPECT_LT((Hg.col(j) - cg).norm(), 1e-8 * std::max(1.0, cg.norm())) << "GPS axis " << j;
    const double ch = wrap_angle_rad(detail::predict_heading(p.q_W_I, R_I_M, nullptr) -
                                     detail::predict_heading(m.q_W_I, R_I_M, nullptr)) /
                      (2 * eps);
    EXPECT_NEAR(Hh(j), ch, 1e-8 * std::max(1.0, std::abs(ch))) << "heading axis " << j;
  }
}

TEST(EskfJacobianTest, ErrorHelperMatchesTheConvention) {
  const EskfState s = some_state();
  Vec15 dx;
  for (int i = 0; i < 15; ++i) dx(i) = 0.01 * (i + 1) * (i % 2 ? -1 : 1);
  const EskfState t = detail::boxplus(s, dx);
  EXPECT_LT((eskf_error(s, t) - dx).norm(), 1e-12);
  EXPECT_LT((error_of(s, t) - dx).norm(), 1e-12);
}

// ---------------------------------------------------------------------------------------------
// Behaviour and input handling

TEST(EskfTest, AttitudeFromGravityAndHeading) {
  const Quat q_true = quat_from_euler_zyx({0.1, -0.2, 2.0});
  const Mat3 R_I_M = quat_from_euler_zyx({0.0, 0.05, 0.3}).toRotationMatrix();
  const Vec3 f_I = q_true.conjugate() * Vec3(0, 0, -9.81);  // at rest: minus gravity
  const double heading = euler_zyx_from_matrix(q_true.toRotationMatrix() * R_I_M).yaw_rad;
  const Quat q = attitude_from_gravity_and_heading(f_I, heading, R_I_M);
  EXPECT_LT(angle_between(q, q_true), 1e-12);
}

struct Rest {
  // The IMU at rest and level; the filter started at the truth.
  static ImuSample sample(TimeNs t) {
    ImuSample s;
    s.t_ns = t;
    s.accel_m_s2 = Vec3(0, 0, -9.80665);
    return s;
  }
};

TEST(EskfTest, InvalidVoFrameIsSkippedWithoutNan) {
  Eskf f(EskfOptions{}, EskfExtrinsics{.T_I_C = SE3(R_frd_optical(), Vec3::Zero())}, EskfState{});
  constexpr TimeNs kImu = 5'000'000, kFrame = 50'000'000;
  vo::VoResult first;
  first.reason = "first frame";
  vo::VoResult still;
  still.valid = true;  // at rest: identity motion
  for (TimeNs t = 0; t <= 2'000'000'000; t += kImu) {
    f.propagate(Rest::sample(t));
    if (t % kFrame != 0) continue;
    const int frame = static_cast<int>(t / kFrame);
    if (frame == 0) {
      EXPECT_FALSE(f.update_vo(t, first));
    } else if (frame % 5 == 0) {
      vo::VoResult bad;
      bad.reason = "too few inliers";
      bad.T_prev_curr = SE3(Quat::Identity(), Vec3(std::nan(""), 0.0, 0.0));
      EXPECT_FALSE(f.update_vo(t, bad));
    } else {
      EXPECT_TRUE(f.update_vo(t, still));
    }
    ASSERT_TRUE(f.augmented_covariance().allFinite());
    ASSERT_TRUE(f.state().p_W_m.allFinite() && f.state().q_W_I.coeffs().allFinite());
  }
  EXPECT_EQ(f.stats().vo_skipped, 1 + 8);
  EXPECT_EQ(f.stats().vo_fused, 40 - 8);
  EXPECT_EQ(f.stats().nonfinite_guards, 0);
  // At rest nothing moved.
  EXPECT_LT(f.state().p_W_m.norm(), 1e-9);
  // A "valid" result that breaks the promise of finite values is caught and counted.
  vo::VoResult broken = still;
  broken.T_prev_curr = SE3(Quat::Identity(), Vec3(std::nan(""), 0.0, 0.0));
  f.propagate(Rest::sample(2'005'000'000));
  EXPECT_FALSE(f.update_vo(2'005'000'000, broken));
  EXPECT_EQ(f.stats().nonfinite_guards, 1);
  EXPECT_TRUE(f.augmented_covariance().allFinite());
}

TEST(EskfTest, BadInputGivesClearErrors) {
  EskfOptions o;
  o.vo_translation_noise_m[1] = 0.0;
  o.gyro_noise_density_rad_s_sqrt_hz = -1.0;
  try {
    Eskf f(o, EskfExtrinsics{}, EskfState{});
    FAIL() << "expected UserError";
  } catch (const UserError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("Eskf: invalid options"), std::string::npos) << m;
    EXPECT_NE(m.find("vo_translation_noise_m[1]: got 0, expected a value > 0"), std::string::npos)
        << m;
    EXPECT_NE(m.find("gyro_noise_density_rad_s_sqrt_hz: got -1"), std::string::npos) << m;
  }
  EskfState nan_state;
  nan_state.v_W_m_s.x() = std::nan("");
  EXPECT_THROW(Eskf(EskfOptions{}, EskfExtrinsics{}, nan_state), UserError);
  EskfExtrinsics mirror;
  mirror.R_I_M = Vec3(1, 1, -1).asDiagonal();
  EXPECT_THROW(Eskf(EskfOptions{}, mirror, EskfState{}), UserError);

  Eskf f(EskfOptions{}, EskfExtrinsics{}, EskfState{});
  // A measurement before any IMU sample cannot be propagated to.
  try {
    f.update_heading({1'000'000, 0.0});
    FAIL() << "expected UserError";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("no IMU sample"), std::string::npos) << e.what();
  }
  f.propagate(Rest::sample(0));
  f.propagate(Rest::sample(5'000'000));
  // Non-positive GPS covariance.
  GpsPositionMeasurement g = GpsPositionMeasurement::with_sd(5'000'000, Vec3::Zero(), 1.0, 2.0);
  g.covariance_m2(2, 2) = -4.0;
  try {
    f.update_gps(g);
    FAIL() << "expected UserError";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("symmetric positive definite"), std::string::npos)
        << e.what();
  }
  g.covariance_m2.setZero();
  EXPECT_THROW(f.update_gps(g), UserError);
  g = GpsPositionMeasurement::with_sd(5'000'000, Vec3::Zero(), 1.0, 2.0);
  g.covariance_m2(0, 1) = 0.5;  // not symmetric
  EXPECT_THROW(f.update_gps(g), UserError);
  EXPECT_TRUE(f.update_gps(GpsPositionMeasurement::with_sd(5'000'000, Vec3::Zero(), 1.0, 2.0)));
  // Time order.
  try {
    f.update_heading({1'000'000, 0.0});
    FAIL() << "expected UserError";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("time order"), std::string::npos) << e.what();
  }
  EXPECT_THROW(f.propagate(Rest::sample(4'000'000)), UserError);
  EXPECT_EQ(EskfOptions{}.validate(), "");
}

TEST(EskfTest, GatesRejectOutliersWhenSet) {
  EskfOptions o;
  o.gps_gate_chi2 = 16.3;
  Eskf f(o, EskfExtrinsics{}, EskfState{});
  f.propagate(Rest::sample(0));
  EXPECT_FALSE(f.update_gps(GpsPositionMeasurement::with_sd(0, Vec3(50, 0, 0), 1.0, 1.0)));
  EXPECT_EQ(f.stats().gps_gated, 1);
  EXPECT_TRUE(f.update_gps(GpsPositionMeasurement::with_sd(0, Vec3(0.5, 0, 0), 1.0, 1.0)));
}

TEST(EskfTest, SameInputsGiveTheSameBytes) {
  RunConfig cfg;
  cfg.seconds = 5.0;
  const RunResult a = run_eskf(cfg, 5), b = run_eskf(cfg, 5), c = run_eskf(cfg, 6);
  ASSERT_EQ(a.frames.size(), b.frames.size());
  for (std::size_t k = 0; k < a.frames.size(); ++k) {
    EXPECT_EQ(0, std::memcmp(a.frames[k].error.data(), b.frames[k].error.data(), sizeof(Vec15)));
    EXPECT_EQ(0, std::memcmp(a.frames[k].P.data(), b.frames[k].P.data(), sizeof(Mat15)));
  }
  EXPECT_NE(0,
            std::memcmp(a.frames.back().error.data(), c.frames.back().error.data(), sizeof(Vec15)));
}

TEST(EskfOptionsTest, YamlRoundTrip) {
  EskfOptions o;
  o.vo_rotation_noise_rad = {1e-3, 2e-3, 3e-3};
  o.vo_gate_chi2 = 22.5;
  const std::string text = yaml::to_yaml(o);
  EskfOptions back;
  yaml::read_into(yaml::load_string(text, "round trip"), {"round trip", false}, &back);
  EXPECT_EQ(yaml::to_yaml(back), text);
}

}  // namespace
}  // namespace driftlab::fusion
