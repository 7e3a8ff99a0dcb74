// Cameras and scenes the renderer's tests share (render_test.cpp, render_backends_test.cpp,
// cutout_test.cpp).
#pragma once

#include "core/rotation.hpp"
#include "sim/render/renderer.hpp"

namespace driftlab::sim::fixtures {

/// A camera looking north, level: optical axes = body FRD axes of a vessel heading north.
inline SE3 camera_at(const Vec3& p) { return SE3(R_frd_optical(), p); }

/// 640x480, fx = fy = 500, cx = 319.5, cy = 239.5, baseline 0.12 m.
inline StereoRig rig_640() {
  StereoRig rig;
  rig.camera = PinholeCamera{};
  rig.baseline_m = 0.12;
  return rig;
}

/// Unlit, black-sky scene for geometric tests: a white texel saturates to 255, nothing else is
/// drawn.
inline SceneGeometry dark_scene() {
  SceneGeometry s;
  s.lighting.ambient = 2.0f;  // a vertical surface saturates to white
  s.lighting.diffuse = 0.0f;
  s.lighting.sky_brightness = 0.0f;
  s.lighting.fog_distance_m = 1e9f;
  s.water.enabled = false;
  return s;
}

}  // namespace driftlab::sim::fixtures
