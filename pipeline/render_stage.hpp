// The render stage: stereo images of the scenario's scene along the vessel's
// ground-truth trajectory, written as PNG files (`driftlab render`).
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "core/camera.hpp"
#include "core/time.hpp"
#include "core/trajectory_io.hpp"
#include "pipeline/scenario.hpp"
#include "sim/render/renderer.hpp"
#include "sim/render/scene_geometry.hpp"

namespace driftlab::sim {
class StereoRenderer;
}

namespace driftlab::pipeline {

struct RenderSequenceOptions {
  int max_frames = 0;  // 0: every frame of the mission (or pipeline.max_frames)
  bool depth = false;  // also write depth/NNNNNN.pfm (metres, float)
  bool masks = false;  // also write mask/NNNNNN.png (255: a moving thing; sim::TruthImages)
  bool replace_existing = false;
  bool profile = false;  // time the renderer's passes (sim::StereoRenderer::set_profiling)
};

struct RenderSequenceSummary {
  std::size_t frames = 0;
  std::size_t triangles = 0;
  double scene_build_s = 0;
  double render_s = 0;  // rendering and read-back only
  double pairs_per_s = 0;
  std::string context;                         // GL version and renderer
  std::optional<sim::RenderPassTimes> passes;  // with RenderSequenceOptions::profile
  std::string brief() const;
};

/// The stereo rig of the scenario's camera options.
StereoRig rig_of(const sim::CameraOptions& camera);

/// Shows the scenario's water and wind on `renderer`: the wave field (with the phases
/// the vessel physics uses), the wind ripples and the vegetation's sway.
void set_water_surface(sim::StereoRenderer* renderer, const Scenario& scenario);

/// Whether anything in the scene moves as `sc` renders it: its movers, or its vegetation in
/// water.wind's gusts (StereoRenderer::has_moving_things before the upload).
bool scene_moves(const Scenario& sc, const sim::SceneGeometry& scene);

/// The frames `driftlab render` writes, one at a time: the scenario's motion simulated and its
/// scene built around the track and uploaded when constructed, then each delivered frame
/// rendered with the camera's effects (blur, rig error, lens, noise) at its clock's stamp.
class RenderSequence {
 public:
  struct Frame {
    std::size_t k = 0;  ///< index of the frame time (dropped frames are skipped)
    TimeNs t_ns = 0;    ///< the camera clock's stamp
    sim::StereoImages images;
    double moving_px = 0;  ///< share of the left image showing moving things (with masks)
  };
  /// `max_frames` > 0 overrides pipeline.max_frames; depth and masks: also the left image's true
  /// depth and mask of moving things (images.depth_left, images.moving_left).
  RenderSequence(const Scenario& scenario, int max_frames, bool depth, bool masks,
                 bool profile = false);
  ~RenderSequence();
  RenderSequence(const RenderSequence&) = delete;
  RenderSequence& operator=(const RenderSequence&) = delete;

  /// The next delivered frame, or nothing after the last.
  std::optional<Frame> next();
  /// The left camera's true pose at every frame time.
  const Trajectory& poses() const;
  /// Frames delivered so far, the scene and the render times.
  RenderSequenceSummary summary() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Renders every frame of a RenderSequence into out_dir/{left,right}/NNNNNN.png (+
/// depth/NNNNNN.pfm, mask/NNNNNN.png) and out_dir/times.csv (frame, t_ns, moving_px: the mask's
/// share of the image, 0 in a scene without movers); the folder appears only when complete.
RenderSequenceSummary render_sequence(const Scenario& scenario,
                                      const std::filesystem::path& out_dir,
                                      const RenderSequenceOptions& options);

}  // namespace driftlab::pipeline
