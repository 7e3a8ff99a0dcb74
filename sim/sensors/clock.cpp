#include "sim/sensors/clock.hpp"

#include <algorithm>
#include <cmath>

#include "core/rotation.hpp"

namespace driftlab::sim {

SensorClock::SensorClock(const ClockOptions& options, const RngStreams& rng, std::string_view name)
    : options_(options),
      jitter_(rng.stream(std::string(name) + ".clock.jitter")),
      drop_(rng.stream(std::string(name) + ".clock.drop")) {
  validate_sensor_options(options_, "sensors." + std::string(name) + ".clock");
}

SampleTime SensorClock::stamp(TimeNs t_true_ns) {
  // Truncated at 3 sigma so that the ordering rule of ClockOptions (6 sigma
  // below one period) guarantees increasing stamps; clamping rather than
  // redrawing keeps exactly one draw per sample.
  const double jitter_s = options_.jitter_ms * 1e-3 * std::clamp(jitter_.normal(), -3.0, 3.0);
  const bool dropped = drop_.uniform() < options_.drop_probability;
  SampleTime s;
  s.t_true_ns = t_true_ns;
  s.t_stamp_ns = t_true_ns + seconds_to_ns(options_.offset_ms * 1e-3 + jitter_s);
  s.dropped = dropped;
  return s;
}

std::vector<SampleTime> stamp_times(const std::vector<TimeNs>& true_times_ns,
                                    const ClockOptions& options, const RngStreams& rng,
                                    std::string_view name) {
  SensorClock clock(options, rng, name);
  std::vector<SampleTime> out;
  out.reserve(true_times_ns.size());
  for (const TimeNs t : true_times_ns) out.push_back(clock.stamp(t));
  return out;
}

SensorMount SensorMount::from_options(const MountOptions& mount) {
  SensorMount m;
  m.R_B_S = quat_from_euler_zyx(
                {deg2rad(mount.rpy_deg[0]), deg2rad(mount.rpy_deg[1]), deg2rad(mount.rpy_deg[2])})
                .toRotationMatrix();
  m.p_B = Vec3(mount.position_frd_m[0], mount.position_frd_m[1], mount.position_frd_m[2]);
  return m;
}

}  // namespace driftlab::sim
