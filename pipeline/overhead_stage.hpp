// The basin paper's reference (Section 3.2), simulated: the basin's overhead camera renders
// the ship model with its red and green markers at every stereo frame, and the paper's colour
// tracker and Eqs. (11)-(20) turn each frame into the model's position, heading and
// velocities (`sensors.overhead`).
#pragma once

#include <filesystem>
#include <string>

#include "core/camera.hpp"
#include "core/se3.hpp"
#include "eval/track.hpp"
#include "pipeline/run.hpp"
#include "sim/render/scene_geometry.hpp"
#include "sim/sensors/overhead.hpp"

namespace driftlab::pipeline {

struct OverheadResult {
  sim::MarkerReference reference;
  OverheadRecord record;
};

/// The overhead camera of `overhead` in a wave basin: its intrinsics and its pose (at the
/// ceiling mount, looking straight down, image columns along north: the optical frame's axes
/// are the world's).
PinholeCamera overhead_camera(const sim::OverheadOptions& overhead);
SE3 overhead_camera_pose(const Scenario& scenario);

/// Where a pixel's ray meets the horizontal plane at height z (NED, down positive): the
/// calibration of an overhead camera whose intrinsics and pose are known exactly.
std::array<double, 2> pixel_to_plane_ne(const PinholeCamera& camera, const SE3& T_W_C,
                                        const cv::Point2d& px, double plane_z_m);

/// Renders the overhead camera at every frame of `mission` over `scene` (the basin, to which
/// the ship model is added), tracks the markers and writes dir/overhead_reference.csv (one row
/// per frame) and dir/overhead_frame.png (the middle frame).
OverheadResult run_overhead_camera(const Scenario& scenario, const sim::SceneGeometry& scene,
                                   const MissionTruth& mission, const std::filesystem::path& dir);

/// The tracker's reference as the evaluation takes it.
eval::PlanarReference planar_reference(const sim::MarkerReference& reference);

}  // namespace driftlab::pipeline
