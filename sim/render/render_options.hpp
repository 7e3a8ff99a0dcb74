// Options of the off-screen renderer (scenario section `render`).
#pragma once

#include <array>

#include "core/yaml_io.hpp"

namespace driftlab::sim {

enum class RenderBackend { kOsmesa, kEgl };
constexpr auto enum_table(RenderBackend) {
  return std::array{std::pair{RenderBackend::kOsmesa, "osmesa"},
                    std::pair{RenderBackend::kEgl, "egl"}};
}

// The size of the water's reflection pass against the camera's image.
enum class ReflectionResolution { kHalf, kHalfHeight, kFull };
constexpr auto enum_table(ReflectionResolution) {
  return std::array{std::pair{ReflectionResolution::kHalf, "half"},
                    std::pair{ReflectionResolution::kHalfHeight, "half_height"},
                    std::pair{ReflectionResolution::kFull, "full"}};
}

struct RenderOptions {
  RenderBackend backend = RenderBackend::kOsmesa;
  int msaa_samples = 1;
  ReflectionResolution reflection_resolution = ReflectionResolution::kFull;
  int reflection_msaa_samples = 1;
  bool ground_truth_depth = false;
  bool reflections = true;
  int motion_blur_samples = 1;
  double motion_blur_step_px = 0;
  double rolling_shutter_step_px = 0.2;
  int rolling_shutter_max_bands = 64;
  double rolling_shutter_near_m = 1.0;

  template <class A>
  void visit(A& a) {
    a("backend", backend, "OpenGL context backend");
    a("msaa_samples", msaa_samples,
      "Multisample anti-aliasing samples (1 = off; 4 costs about 3x on llvmpipe, see "
      "docs/renderer-and-scenes.md)",
      yaml::in_range(1, 16));
    a("reflection_resolution", reflection_resolution,
      "Size of the water's reflection pass: full (the camera's; mirror images move by their "
      "true sub-pixel amounts), half_height (full width, half the rows) or half (a quarter of "
      "the fill, but the mirror image's motion snaps to steps of up to 2 px; see "
      "docs/renderer-and-scenes.md)");
    a("reflection_msaa_samples", reflection_msaa_samples,
      "Multisample anti-aliasing samples of the water's reflection pass (1 = off)",
      yaml::in_range(1, 16));
    a("ground_truth_depth", ground_truth_depth, "Also render per-pixel ground-truth depth");
    a("reflections", reflections,
      "Planar reflection of the scene on the water (one extra geometry pass per eye)");
    a("motion_blur_samples", motion_blur_samples,
      "Motion blur: renders averaged over the exposure (sensors.camera.exposure_ms) along the "
      "true motion; 1 = off, each sample costs one more render",
      yaml::in_range(1, 64));
    a("motion_blur_step_px", motion_blur_step_px,
      "With motion_blur_samples > 1: the farthest the image may move between two samples; each "
      "frame then takes as few samples as its rotation over the exposure needs (at least 1, at "
      "most motion_blur_samples), so only the turns pay for blur. 0 = every frame takes "
      "motion_blur_samples [px]",
      yaml::at_least(0));
    a("rolling_shutter_step_px", rolling_shutter_step_px,
      "With sensors.camera.shutter: rolling, the image is drawn in bands of rows, each from the "
      "pose at its centre row's time: as few bands as keep the image's motion from one band to "
      "the next within this step, so no row is off by more than half of it (rotation over the "
      "readout, and translation seen at rolling_shutter_near_m) [px]",
      yaml::positive() & yaml::up_to(100, "no rolling shutter at all"));
    a("rolling_shutter_max_bands", rolling_shutter_max_bands,
      "Most bands of rows a rolling-shutter image is drawn in (each costs one more pass)",
      yaml::in_range(1, 4096));
    a("rolling_shutter_near_m", rolling_shutter_near_m,
      "Nearest depth whose motion the rolling shutter's bands keep within "
      "rolling_shutter_step_px [m]",
      yaml::positive());
  }
};

}  // namespace driftlab::sim
