// Fixed-step RK4 integration of the vessel along its mission. Ground truth
// comes out at every physics step and, exactly, at every requested sample
// time (camera frames) by a partial RK4 step from the last physics state
// with the same held inputs, so that the main integration is unchanged.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "core/time.hpp"
#include "sim/physics/vessel/guidance.hpp"
#include "sim/physics/vessel/vessel_model.hpp"

namespace driftlab::sim {

/// Ground truth of the body at one instant.
struct BodySample {
  TimeNs t_ns = 0;
  VesselState state;
  Vec3 v_dot_B = Vec3::Zero();  // d v_B / dt [m/s^2] (body axes)
  Vec3 w_dot_B = Vec3::Zero();  // d w_B / dt [rad/s^2]
};

struct MotionOptions {
  double physics_rate_hz = 400.0;
  double max_duration_s = 0.0;  // 0: until the mission completes (capped by hard_limit_s)
  double hard_limit_s = 4 * 3600.0;
  VesselInputs fixed_inputs;  // used when there is no guidance
};

/// Summary of a motion run (Ceres' Solver::Summary in spirit).
struct MotionSummary {
  bool mission_completed = false;
  std::size_t steps = 0;
  double duration_s = 0;
  double distance_m = 0;  // path length of the CG
  double mean_speed_mps = 0;
  std::string brief() const;
};

/// One RK4 step of `dt_s` from `state` at `t_s` with held inputs.
VesselState rk4_step(const VesselModel& model, const VesselState& state, const VesselInputs& in,
                     const Environment& env, double t_s, double dt_s);

/// Initial state: at `start` (north, east), heading, floating level at the design draft.
VesselState initial_state(const VesselModel& model, const Vec2& start_ne, double heading_rad);

/// Runs the mission. `on_physics` gets every physics step (including t = 0);
/// `on_sample` gets the state at each time of `sample_times_ns` (sorted) that
/// falls within the run. Throws InternalError if the state stops being finite
/// (the NaN guard), naming the step.
MotionSummary simulate(const VesselModel& model, const Environment& env, Guidance* guidance,
                       const VesselState& initial, const MotionOptions& options,
                       const std::vector<TimeNs>& sample_times_ns,
                       const std::function<void(const BodySample&)>& on_physics,
                       const std::function<void(const BodySample&)>& on_sample);

/// Sample times at `rate_hz` from 0 up to `end_s`: round(k * 1e9 / rate) ns.
std::vector<TimeNs> sample_times(double rate_hz, double end_s);

}  // namespace driftlab::sim
