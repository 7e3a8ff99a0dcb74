#include "sim/physics/vessel/simulator.hpp"

#include <fmt/format.h>

#include <cmath>

#include "core/error.hpp"

namespace driftlab::sim {
namespace {

VesselState add(const VesselState& s, const VesselStateDot& d, double h) {
  VesselState o = s;
  o.p_W += h * d.p_dot;
  o.q_W_B.coeffs() += h * d.q_dot;
  o.v_B += h * d.v_dot;
  o.w_B += h * d.w_dot;
  for (int i = 0; i < 2; ++i) o.thrust_n[i] += h * d.thrust_dot[i];
  return o;
}

bool finite(const VesselState& s) {
  return s.p_W.allFinite() && s.q_W_B.coeffs().allFinite() && s.v_B.allFinite() &&
         s.w_B.allFinite() && std::isfinite(s.thrust_n[0]) && std::isfinite(s.thrust_n[1]);
}

BodySample sample_of(const VesselModel& model, const VesselState& s, const VesselInputs& in,
                     const Environment& env, TimeNs t_ns) {
  BodySample b;
  b.t_ns = t_ns;
  b.state = s;
  const VesselStateDot d = model.derivative(s, in, env, ns_to_seconds(t_ns));
  b.v_dot_B = d.v_dot;
  b.w_dot_B = d.w_dot;
  return b;
}

}  // namespace

std::string MotionSummary::brief() const {
  return fmt::format("motion: {} steps, {:.2f} s, {:.2f} m at a mean {:.3f} m/s, mission {}", steps,
                     duration_s, distance_m, mean_speed_mps,
                     mission_completed ? "completed" : "stopped by the time limit");
}

VesselState rk4_step(const VesselModel& model, const VesselState& s, const VesselInputs& in,
                     const Environment& env, double t, double h) {
  const VesselStateDot k1 = model.derivative(s, in, env, t);
  const VesselStateDot k2 = model.derivative(add(s, k1, h / 2), in, env, t + h / 2);
  const VesselStateDot k3 = model.derivative(add(s, k2, h / 2), in, env, t + h / 2);
  const VesselStateDot k4 = model.derivative(add(s, k3, h), in, env, t + h);
  VesselStateDot sum;
  sum.p_dot = (k1.p_dot + 2 * k2.p_dot + 2 * k3.p_dot + k4.p_dot) / 6;
  sum.q_dot = (k1.q_dot + 2 * k2.q_dot + 2 * k3.q_dot + k4.q_dot) / 6;
  sum.v_dot = (k1.v_dot + 2 * k2.v_dot + 2 * k3.v_dot + k4.v_dot) / 6;
  sum.w_dot = (k1.w_dot + 2 * k2.w_dot + 2 * k3.w_dot + k4.w_dot) / 6;
  for (int i = 0; i < 2; ++i)
    sum.thrust_dot[i] =
        (k1.thrust_dot[i] + 2 * k2.thrust_dot[i] + 2 * k3.thrust_dot[i] + k4.thrust_dot[i]) / 6;
  VesselState out = add(s, sum, h);
  out.q_W_B.normalize();  // RK4 drifts off the unit sphere by O(h^5) per step
  return out;
}

VesselState initial_state(const VesselModel& model, const Vec2& start_ne, double heading_rad) {
  VesselState s;
  s.p_W = Vec3(start_ne.x(), start_ne.y(), model.design_cg_z_m());
  s.q_W_B = Quat(Eigen::AngleAxisd(heading_rad, Vec3::UnitZ()));
  return s;
}

std::vector<TimeNs> sample_times(double rate_hz, double end_s) {
  DRIFTLAB_DEMAND(rate_hz > 0);
  std::vector<TimeNs> out;
  const TimeNs end_ns = seconds_to_ns(end_s);
  for (std::int64_t k = 0;; ++k) {
    const TimeNs t = static_cast<TimeNs>(std::llround(static_cast<double>(k) * 1e9 / rate_hz));
    if (t > end_ns) break;
    out.push_back(t);
  }
  return out;
}

MotionSummary simulate(const VesselModel& model, const Environment& env, Guidance* guidance,
                       const VesselState& initial, const MotionOptions& options,
                       const std::vector<TimeNs>& samples,
                       const std::function<void(const BodySample&)>& on_physics,
                       const std::function<void(const BodySample&)>& on_sample) {
  DRIFTLAB_DEMAND(options.physics_rate_hz > 0);
  const TimeNs dt_ns = seconds_to_ns(1.0 / options.physics_rate_hz);
  const double limit_s = options.max_duration_s > 0 ? options.max_duration_s : options.hard_limit_s;
  const TimeNs limit_ns = seconds_to_ns(limit_s);
  MotionSummary summary;
  VesselState s = initial;
  TimeNs t_ns = 0;
  std::size_t next_sample = 0;
  while (next_sample < samples.size() && samples[next_sample] < 0) ++next_sample;
  while (true) {
    const double t = ns_to_seconds(t_ns);
    const double h = ns_to_seconds(dt_ns);
    const VesselInputs in = guidance ? guidance->update(s, t, h) : options.fixed_inputs;
    const bool finished = (guidance && guidance->done()) || t_ns >= limit_ns;
    if (on_physics) on_physics(sample_of(model, s, in, env, t_ns));
    // Samples in [t, t + dt): a partial step from this physics state.
    while (next_sample < samples.size() && samples[next_sample] < t_ns + dt_ns) {
      const TimeNs ts = samples[next_sample];
      if (finished && ts > t_ns) break;  // past the end of the run
      const VesselState ss =
          ts == t_ns ? s : rk4_step(model, s, in, env, t, ns_to_seconds(ts - t_ns));
      if (on_sample) on_sample(sample_of(model, ss, in, env, ts));
      ++next_sample;
    }
    if (finished) {
      summary.mission_completed = guidance && guidance->done();
      break;
    }
    const VesselState next = rk4_step(model, s, in, env, t, h);
    if (!finite(next))
      throw InternalError(fmt::format(
          "vessel physics: the state stopped being finite at step {} (t = {} s); the time step "
          "{} s may be too long for this vessel",
          summary.steps, t, h));
    summary.distance_m += (next.p_W - s.p_W).norm();
    s = next;
    t_ns += dt_ns;
    ++summary.steps;
  }
  summary.duration_s = ns_to_seconds(t_ns);
  summary.mean_speed_mps = summary.duration_s > 0 ? summary.distance_m / summary.duration_s : 0;
  return summary;
}

}  // namespace driftlab::sim
