// One scenario run, stage by stage, into an output folder written atomically
// (docs/design.md, "Data contract of a run"). Stages are wired in as they land:
// physics (vessel motion and ground truth) now; sensors, render, VO, fusion
// and evaluation with their issues.
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/rotation.hpp"
#include "core/se3.hpp"
#include "core/trajectory_io.hpp"
#include "dataset/dataset.hpp"
#include "pipeline/camera_stage.hpp"
#include "pipeline/frame_cache.hpp"
#include "pipeline/run_record.hpp"
#include "pipeline/scenario.hpp"
#include "pipeline/sensor_stage.hpp"
#include "sim/physics/vessel/simulator.hpp"
#include "sim/render/scene_geometry.hpp"

namespace driftlab::pipeline {

struct RunOptions {
  bool replace_existing = false;
  bool only_motion = false;       // stop after the physics stage
  std::FILE* progress = nullptr;  // progress of the frame loop (e.g. stderr); null: none
  bool progress_tty = false;      // redraw a bar in place (a terminal) instead of plain lines
  FrameCacheOptions frame_cache;  // where frames are kept and replayed (no folder: nowhere)
};

/// What a scenario run measured, as Ceres' Solver::Summary: one typed record its stages fill,
/// turned into metrics.json's record by run_record() and summed up in a line by brief().
struct RunSummary {
  std::string scenario;
  std::uint64_t seed = 0;
  sim::MotionSummary motion;
  std::size_t frames = 0;     ///< camera frames with ground truth
  double track_length_m = 0;  ///< camera-left path length
  StagesRecord stages;
  record::SensorsRecord sensors;  ///< per sensor: samples and errors (SensorData::stats)
  double physics_s = 0;           ///< wall-clock time of the physics stage
  double sensors_s = 0;           ///< of the sensor stage
  double total_s = 0;
  std::optional<VisionRecord> vision;  ///< render, VO, fusion, evaluation (when they ran)
  std::string brief() const;
  /// metrics.json (docs/metrics-reference.md).
  record::RunRecord run_record() const;
};

/// Pose of the left camera (optical frame) in the body (FRD) frame, from the
/// mount options: the nominal mounting looks along the bow (optical z = body
/// x), then roll, pitch, yaw (ZYX) of the mount rotate it.
SE3 camera_mount_T_B_C(const sim::MountOptions& mount);

/// Pose of the IMU's frame S in the body frame (sensors.imu.mount); the identity without an IMU.
SE3 imu_mount_T_B_S(const Scenario& scenario);

/// The physics stage: simulates the scenario's vessel along its mission;
/// `on_physics` gets every physics step, `on_frame` the body at every camera
/// frame time (round(k * 1e9 / rate) ns, up to pipeline.max_frames).
sim::MotionSummary simulate_scenario_motion(
    const Scenario& scenario, const std::function<void(const sim::BodySample&)>& on_physics,
    const std::function<void(const sim::BodySample&)>& on_frame);

/// The same, with `on_extra` called at every time of `extra_times` (sorted, unique), e.g. the
/// other sensors' sample times, in time order interleaved with `on_frame`.
sim::MotionSummary simulate_scenario_motion(
    const Scenario& scenario, const std::function<void(const sim::BodySample&)>& on_physics,
    const std::function<void(const sim::BodySample&)>& on_frame,
    const std::vector<TimeNs>& extra_times,
    const std::function<void(const sim::BodySample&)>& on_extra);

/// How long the scenario's motion runs [s]: mission.duration_s, cut to pipeline.max_frames
/// camera frames; without either, the simulator's hard limit (the mission ends it earlier).
double motion_end_s(const Scenario& scenario);

/// The truth at the camera frames of a scenario's mission.
struct MissionTruth {
  sim::MotionSummary motion;
  Trajectory camera_gt;            ///< left camera at each frame time
  std::vector<FrameTruth> frames;  ///< body pose and twist at each frame (the camera stage)
  std::vector<EulerZYX> platform;  ///< body attitude at each frame (covariate h)
  /// The IMU frame's true state at most every 5 ms (EuRoC's ground truth), when asked for.
  std::vector<dataset::BodyState> imu_states;
};

/// The physics stage: the mission simulated, `on_physics` called at every physics step and
/// `sensors` (may be null) fed at its sample times; `imu_states`: keep them (EuRoC exports).
MissionTruth simulate_mission(const Scenario& scenario,
                              const std::function<void(const sim::BodySample&)>& on_physics,
                              SensorStage* sensors, bool imu_states = false);

/// The scene around a camera track (river reach tiles covering its northings).
sim::SceneGeometry scene_for_track(const Scenario& scenario, const Trajectory& camera_gt);

/// Runs `scenario` into `out_dir` (temporary folder renamed at the end).
RunSummary run_scenario(const Scenario& scenario, const std::filesystem::path& out_dir,
                        const RunOptions& options);

}  // namespace driftlab::pipeline
