// Rendering cost: stereo pairs per second of the two scenes at 640x480 and
// 1024x768 with the default effects (water reflections, their pass at the camera's
// resolution; MSAA is off by default), on the scenario's default backend (OSMesa: Mesa llvmpipe on
// the CPU). The speed issue's targets on the 2-core CI machine: 60 pairs/s at 640x480 and 30 at
// 1024x768 (river_reach).
#include <benchmark/benchmark.h>

#include <cstdint>
#include <filesystem>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "core/rotation.hpp"
#include "pipeline/render_stage.hpp"
#include "pipeline/scenario.hpp"
#include "scenes/build_scene.hpp"
#include "sim/render/renderer.hpp"

namespace {

using namespace driftlab;

void render_bench(benchmark::State& state, const char* scenario_file, bool basin,
                  void (*adjust)(sim::RenderOptions*, std::int64_t) = nullptr,
                  void (*adjust_scenario)(pipeline::Scenario*) = nullptr) {
  pipeline::Scenario sc = pipeline::load_scenario(std::filesystem::path(DRIFTLAB_SOURCE_DIR) /
                                                  "scenarios" / scenario_file);
  if (adjust) adjust(&sc.render, state.range(2));
  if (adjust_scenario) adjust_scenario(&sc);
  sc.sensors.camera.width_px = static_cast<int>(state.range(0));
  sc.sensors.camera.height_px = static_cast<int>(state.range(1));
  sc.sensors.camera.fx_px = sc.sensors.camera.fy_px = 0.78 * state.range(0);
  sc.sensors.camera.cx_px = (state.range(0) - 1) / 2.0;
  sc.sensors.camera.cy_px = (state.range(1) - 1) / 2.0;
  const sim::SceneGeometry scene = scenes::build_scene(sc.scene, sc.seed, -10, 60);
  sim::StereoRenderer renderer(pipeline::rig_of(sc.sensors.camera), sc.render);
  renderer.upload(scene);
  pipeline::set_water_surface(&renderer, sc);
  // A camera 0.5 m above the water looking along the river, slowly moving.
  double t = 0;
  for (auto _ : state) {
    const double x = basin ? 0.5 + 0.1 * t : 0.6 * t;
    const SE3 T_W_C(quat_from_euler_zyx({0, 0, basin ? 0.0 : 0.5}) * Quat(R_frd_optical()),
                    Vec3(x, 0, -0.5));
    benchmark::DoNotOptimize(renderer.render(T_W_C, t, false));
    t += 1.0 / 13;
  }
  state.counters["pairs_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["triangles"] = static_cast<double>(renderer.triangles());
}

void BM_RenderRiverReach(benchmark::State& state) {
  render_bench(state, "river_crossing.yaml", false);
}
BENCHMARK(BM_RenderRiverReach)
    ->Args({640, 480})
    ->Args({1024, 768})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The reflection pass's settings at 1024x768: the third argument is 2 r + m, with r the
// render.reflection_resolution (0 half, 1 half_height, 2 full: the default) and m 1 for 4x MSAA
// in the pass (render.reflection_msaa_samples: 4).
void BM_RenderRiverReachReflection(benchmark::State& state) {
  render_bench(state, "river_crossing.yaml", false, [](sim::RenderOptions* o, std::int64_t mode) {
    o->reflection_msaa_samples = mode % 2 == 1 ? 4 : 1;
    o->reflection_resolution = static_cast<sim::ReflectionResolution>(mode / 2);
  });
}
BENCHMARK(BM_RenderRiverReachReflection)
    ->Args({1024, 768, 0})
    ->Args({1024, 768, 1})
    ->Args({1024, 768, 2})
    ->Args({1024, 768, 3})
    ->Args({1024, 768, 4})
    ->Args({1024, 768, 5})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The river paper's breeze on the water (water.wind: 4.4 m/s, the middle of the paper's
// 3.4-5.4 m/s, a quarter of it reaching the water between the banks): the water's fragment shader
// draws the ripples and blurs the mirror image, which is mip-mapped every frame.
void BM_RenderRiverReachWind(benchmark::State& state) {
  render_bench(state, "river_crossing.yaml", false, nullptr, [](pipeline::Scenario* sc) {
    sc->water.wind.speed_mps = 4.4;
    sc->water.wind.shelter = 0.25;
  });
}
BENCHMARK(BM_RenderRiverReachWind)
    ->Args({640, 480})
    ->Args({1024, 768})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The same frames through the EGL backend (render.backend: egl): Mesa's llvmpipe on a machine
// without a GPU (about the OSMesa figure), the vendor's driver where there is one. The speed
// issue's target on a GPU: 1,000 pairs/s. The third argument is unused.
void BM_RenderRiverReachEgl(benchmark::State& state) {
  try {
    render_bench(state, "river_crossing.yaml", false, [](sim::RenderOptions* o, std::int64_t) {
      o->backend = sim::RenderBackend::kEgl;
    });
  } catch (const UserError& e) {
    state.SkipWithError(e.what());
  }
}
BENCHMARK(BM_RenderRiverReachEgl)
    ->Args({640, 480, 0})
    ->Args({1024, 768, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_RenderWaveBasin(benchmark::State& state) { render_bench(state, "basin_exp4.yaml", true); }
BENCHMARK(BM_RenderWaveBasin)
    ->Args({640, 480})
    ->Args({1024, 768})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
