// Filter stack (fusion/ned_filters, fusion/eskf): update rates of the basin paper's Kalman and
// particle filters (one step per VO frame) and of the error-state filter's IMU propagation and
// VO, GPS and compass updates. The counter x_realtime is how many times faster than real time a
// filter runs its sensor stream: for the NED filters one step per frame at the basin paper's
// 20 Hz (the PF with 1000 particles must exceed 1); for the ESKF, one second of data (200 IMU
// samples, 20 VO frames, 10 compass headings, 1 GPS fix) per item.
#include <benchmark/benchmark.h>

#include <cmath>
#include <optional>
#include <vector>

#include "core/rng.hpp"
#include "core/rotation.hpp"
#include "fusion/eskf.hpp"
#include "fusion/ned_filters.hpp"

namespace {

using namespace driftlab;
using namespace driftlab::fusion;

constexpr TimeNs kFrameNs = 50'000'000;  // 20 Hz
constexpr double kFrameS = 0.05;
constexpr std::size_t kInputs = 4096;

struct NedInputs {
  std::vector<BodyVelocityMeasurement> vo;
  std::vector<std::optional<HeadingMeasurement>> heading;
};

// A turning vessel with noisy VO (every 50th frame failed) and a compass at 10 Hz. Time stamps
// are rewritten per iteration, so only the values repeat.
NedInputs ned_inputs() {
  Rng rng = RngStreams(1).stream("bench.ned");
  NedInputs in;
  double psi = 0.0;
  for (std::size_t k = 0; k < kInputs; ++k) {
    BodyVelocityMeasurement m;
    m.valid = k % 50 != 0;
    m.dt_s = kFrameS;
    m.surge_m_s = 1.0 + rng.normal(0.0, 0.1);
    m.sway_m_s = 0.05 + rng.normal(0.0, 0.1);
    m.yaw_rate_rad_s = 0.05 + rng.normal(0.0, 0.007);
    in.vo.push_back(m);
    psi = wrap_angle_rad(psi + 0.05 * kFrameS);
    if (k % 2 == 0) {
      in.heading.push_back(HeadingMeasurement{0, psi + rng.normal(0.0, 0.017)});
    } else {
      in.heading.push_back(std::nullopt);
    }
  }
  return in;
}

template <class Filter>
void run_ned(benchmark::State& state, Filter& f) {
  static const NedInputs in = ned_inputs();
  TimeNs t = 0;
  std::size_t i = 0;
  for (auto _ : state) {
    BodyVelocityMeasurement m = in.vo[i & (kInputs - 1)];
    m.t_ns = t;
    std::optional<HeadingMeasurement> h = in.heading[i & (kInputs - 1)];
    if (h) h->t_ns = t;
    benchmark::DoNotOptimize(f.step(m, h));
    t += kFrameNs;
    ++i;
  }
  state.SetItemsProcessed(state.iterations());
  // Frames per second of wall time / 20 frames per second of data.
  state.counters["x_realtime"] = benchmark::Counter(static_cast<double>(state.iterations()) / 20.0,
                                                    benchmark::Counter::kIsRate);
}

void BM_NedKalmanFilterStep(benchmark::State& state) {
  NedKalmanFilter kf{NedFilterOptions{}};
  run_ned(state, kf);
}
BENCHMARK(BM_NedKalmanFilterStep);

// Args: particles, resampling (0: the paper's multinomial at every step, 1: systematic with the
// ESS trigger).
void BM_NedParticleFilterStep(benchmark::State& state) {
  NedParticleFilterOptions o;
  o.particles = static_cast<int>(state.range(0));
  o.resampling = state.range(1) == 0 ? PfResampling::kMultinomial : PfResampling::kSystematicEss;
  NedParticleFilter pf(o, RngStreams(2).stream("bench.pf"));
  run_ned(state, pf);
}
BENCHMARK(BM_NedParticleFilterStep)
    ->Args({1000, 0})
    ->Args({1000, 1})
    ->Args({10000, 0})
    ->Args({10000, 1})
    ->Unit(benchmark::kMicrosecond);

// --- ESKF

constexpr TimeNs kImuNs = 5'000'000;  // 200 Hz

ImuSample imu_at(TimeNs t) {
  // A gentle turn with some rolling: enough to make every Jacobian block non-trivial.
  const double s = ns_to_seconds(t);
  ImuSample m;
  m.t_ns = t;
  m.gyro_rad_s = Vec3(0.1 * std::sin(2.0 * s), 0.05 * std::cos(1.5 * s), 0.05);
  m.accel_m_s2 = Vec3(0.2 * std::sin(s), 0.1, -9.80665 + 0.3 * std::sin(3.0 * s));
  return m;
}

EskfExtrinsics bench_extrinsics() {
  EskfExtrinsics ex;
  ex.T_I_C = SE3(R_frd_optical(), Vec3(1.0, 0.2, -0.6));
  ex.p_I_antenna_m = Vec3(0.0, 0.0, -1.0);
  return ex;
}

void BM_EskfPropagate(benchmark::State& state) {
  Eskf f(EskfOptions{}, bench_extrinsics(), EskfState{});
  TimeNs t = 0;
  for (auto _ : state) {
    f.propagate(imu_at(t));
    t += kImuNs;
  }
  benchmark::DoNotOptimize(f.state());
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_EskfPropagate);

void BM_EskfVoUpdate(benchmark::State& state) {
  // The update alone: repeated at one time stamp (the clone then sits at the same pose and the
  // increment is the identity; the algebra is the same as for any increment).
  Eskf f(EskfOptions{}, bench_extrinsics(), EskfState{});
  f.propagate(imu_at(0));
  vo::VoResult first;
  f.update_vo(0, first);
  vo::VoResult r;
  r.valid = true;
  r.T_prev_curr = SE3::exp(Vec6::Constant(1e-4));
  for (auto _ : state) benchmark::DoNotOptimize(f.update_vo(0, r));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_EskfVoUpdate);

void BM_EskfGpsUpdate(benchmark::State& state) {
  Eskf f(EskfOptions{}, bench_extrinsics(), EskfState{});
  f.propagate(imu_at(0));
  const GpsPositionMeasurement g =
      GpsPositionMeasurement::with_sd(0, Vec3(0.1, 0.0, 0.0), 1.5, 3.0);
  for (auto _ : state) benchmark::DoNotOptimize(f.update_gps(g));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_EskfGpsUpdate);

void BM_EskfHeadingUpdate(benchmark::State& state) {
  Eskf f(EskfOptions{}, bench_extrinsics(), EskfState{});
  f.propagate(imu_at(0));
  for (auto _ : state) benchmark::DoNotOptimize(f.update_heading({0, 0.01}));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_EskfHeadingUpdate);

void BM_EskfOneSecondOfData(benchmark::State& state) {
  // 200 IMU samples, 20 VO frames (between IMU samples: propagation to the frame time included),
  // 10 compass headings and 1 GPS fix per item.
  Eskf f(EskfOptions{}, bench_extrinsics(), EskfState{});
  vo::VoResult r;
  r.valid = true;
  r.T_prev_curr = SE3(Quat::Identity(), Vec3(0.0, 0.0, 0.05));
  TimeNs t = 0;
  std::int64_t frame = 0;
  for (auto _ : state) {
    for (int i = 0; i < 200; ++i, t += kImuNs) {
      f.propagate(imu_at(t));
      if (i % 20 == 0) f.update_heading({t, 0.0});
      if (i == 0) f.update_gps(GpsPositionMeasurement::with_sd(t, f.state().p_W_m, 1.5, 3.0));
      if (i % 10 == 0) f.update_vo(t + kImuNs / 3, frame++ == 0 ? vo::VoResult{} : r);
    }
  }
  benchmark::DoNotOptimize(f.state());
  state.SetItemsProcessed(state.iterations());
  state.counters["x_realtime"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_EskfOneSecondOfData)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
