// Measurements and runs that the basin paper's filters' tests share (ned_filters_test.cpp,
// ned_kalman_particle_test.cpp).
#pragma once

#include <cstdint>
#include <vector>

#include "core/rng.hpp"
#include "fusion/ned_filters.hpp"

namespace driftlab::fusion::fixtures {

inline constexpr TimeNs kNedStepNs = 50'000'000;  // 20 Hz, the basin paper's frame rate
inline constexpr double kNedDt = 0.05;

inline BodyVelocityMeasurement vo_at(int k, double u, double v, double r, bool valid = true) {
  BodyVelocityMeasurement m;
  m.t_ns = k * kNedStepNs;
  m.valid = valid;
  m.dt_s = kNedDt;
  m.surge_m_s = u;
  m.sway_m_s = v;
  m.yaw_rate_rad_s = r;
  return m;
}

inline HeadingMeasurement heading_at(int k, double psi) { return {k * kNedStepNs, psi}; }

struct LinearRun {
  std::vector<BodyVelocityMeasurement> vo;
  std::vector<HeadingMeasurement> heading;
};

// A straight run at constant heading with noisy VO velocities and a precise compass: heading
// uncertainty then barely reaches the positions, and the model the PF samples is, for practical
// purposes, the KF's linear-Gaussian one.
inline LinearRun linear_run(int steps, std::uint64_t seed, const NedFilterOptions& o, double psi0) {
  LinearRun run;
  Rng rng = RngStreams(seed).stream("test.ned.data");
  const double su = *o.vo_increment_noise_m / kNedDt;
  for (int k = 0; k < steps; ++k) {
    run.vo.push_back(vo_at(k, 1.0 + rng.normal(0, su), 0.1 + rng.normal(0, su),
                           rng.normal(0.0, *o.vo_yaw_increment_noise_rad / kNedDt), k % 17 != 9));
    run.heading.push_back(heading_at(k, psi0 + rng.normal(0.0, *o.compass_noise_rad)));
  }
  return run;
}

}  // namespace driftlab::fusion::fixtures
