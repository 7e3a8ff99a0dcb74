// Vessel physics cost: one RK4 step (four pressure integrations over the hull)
// in calm water and in a JONSWAP sea, and a whole 663 m river survey.
#include <benchmark/benchmark.h>

#include "core/rng.hpp"
#include "sim/physics/vessel/guidance.hpp"
#include "sim/physics/vessel/simulator.hpp"
#include "sim/physics/waves/ripple_spectrum.hpp"
#include "sim/physics/waves/wave_field.hpp"

namespace {

using namespace driftlab;
using namespace driftlab::sim;

void step_bench(benchmark::State& state, const WaveOptions& waves_options) {
  const VesselModel model(VesselOptions{});
  const auto waves = make_wave_field(waves_options, RngStreams(1).stream("waves.phases"));
  Environment env;
  env.waves = waves.get();
  VesselState s = initial_state(model, Vec2(0, 0), 0);
  VesselInputs in;
  in.thrust_command_n = {10, 10};
  double t = 0;
  for (auto _ : state) {
    s = rk4_step(model, s, in, env, t, 0.0025);
    t += 0.0025;
    benchmark::DoNotOptimize(s);
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_PhysicsStepCalm(benchmark::State& state) { step_bench(state, WaveOptions{}); }
BENCHMARK(BM_PhysicsStepCalm);

void BM_PhysicsStepAiry(benchmark::State& state) {
  WaveOptions w;  // basin experiment 2: 5 mm, 210 mm
  w.model = WaveModel::kAiry;
  w.water_depth_m = 0.6;
  w.airy.amplitude_m = 0.005;
  w.airy.wavelength_m = 0.21;
  step_bench(state, w);
}
BENCHMARK(BM_PhysicsStepAiry);

void BM_PhysicsStepJonswap(benchmark::State& state) {
  WaveOptions w;
  w.model = WaveModel::kJonswap;
  w.significant_height_m = 0.1;
  w.peak_period_s = 2.0;
  step_bench(state, w);
}
BENCHMARK(BM_PhysicsStepJonswap);

// The wind ripples' slope maps of one time step (both tiles, 256x256, FFT and
// mip levels): the river paper's breeze at the water (4.4 m/s, shelter 0.25).
void BM_RippleMapsBake(benchmark::State& state) {
  WindOptions w;
  w.speed_mps = 4.4;
  w.shelter = 0.25;
  RippleMaps maps(w, CurrentOptions{}, driftlab::RngStreams(1).stream("water.ripples"));
  double t = 0.0;
  for (auto _ : state) {
    maps.bake(t);
    t += 1.0 / 8.2;
    benchmark::DoNotOptimize(maps.level(1, 0).data());
  }
}
BENCHMARK(BM_RippleMapsBake)->Unit(benchmark::kMillisecond);

void BM_Survey663m(benchmark::State& state) {
  const VesselModel model(VesselOptions{});
  MissionOptions m;
  m.type = MissionType::kSurvey;
  m.survey_length_m = 663;
  m.speed_mps = 0.57;
  const auto waves = make_wave_field(WaveOptions{}, RngStreams(1).stream("waves.phases"));
  Environment env;
  env.waves = waves.get();
  for (auto _ : state) {
    Guidance g(model, plan_mission(m, Vec2(0, 0), 0, {}), m);
    const auto summary =
        simulate(model, env, &g, initial_state(model, Vec2(0, 0), 0), {}, {}, nullptr, nullptr);
    state.counters["sim_s"] = summary.duration_s;
    state.counters["steps"] = static_cast<double>(summary.steps);
  }
}
BENCHMARK(BM_Survey663m)->Unit(benchmark::kSecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
