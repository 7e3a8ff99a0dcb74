// The frame cache's key (docs/design.md, "Frame cache"): a text naming everything that decides the
// bytes of a run's frames, so that two runs share cached frames exactly when their frames would
// come out the same. It holds
//   - the renderer's identity: the code (renderer_code_identity(): the SHA-256 of every source
//     under core/, sim/, scenes/ and the camera-stage files of pipeline/, and of the compiler
//     and flags, computed at build time by cmake/DriftlabRendererIdentity.cmake), the OpenCV
//     library's version (camera effects), and the GL context's own description (Mesa and LLVM
//     versions, or the GPU driver's);
//   - the resolved scenario without what decides no frame (its name and description, the
//     evaluation, and the pipeline but for pipeline.max_frames): seed, scene, water, vessel,
//     mission, sensors, render and any section added later;
//   - fingerprints (FNV-1a 64) of what the run computed from them: the scene geometry as built
//     (meshes, textures, including photographs read from Debian packages), the true frame
//     poses and times (so a change of the physics misses too), and the camera clock's stamps
//     and dropped frames.
// docs/design.md "Frame cache".
#pragma once

#include <string>
#include <vector>

#include "pipeline/camera_stage.hpp"
#include "pipeline/scenario.hpp"
#include "sim/render/scene_geometry.hpp"
#include "sim/sensors/clock.hpp"

namespace driftlab::pipeline {

/// The build-time part of the renderer's identity: "SHA256 (N files)" (generated source).
const char* renderer_code_identity();

/// The renderer's identity as the key's first lines: code, OpenCV, FFTW (the wind ripples'
/// slope maps), and `gl_context` (the
/// context's description, sim::GlContext::description()).
std::string renderer_identity(const std::string& gl_context);

/// FNV-1a 64 fingerprints of what a run computed (hex).
std::string scene_fingerprint(const sim::SceneGeometry& scene);
std::string truth_fingerprint(const std::vector<FrameTruth>& truth,
                              const std::vector<sim::SampleTime>& stamps);

/// The whole key: `identity` (renderer_identity()), the scenario's frame-deciding sections and
/// the fingerprints.
std::string frame_cache_key(const std::string& identity, const Scenario& scenario,
                            const sim::SceneGeometry& scene, const std::vector<FrameTruth>& truth,
                            const std::vector<sim::SampleTime>& stamps);

}  // namespace driftlab::pipeline
