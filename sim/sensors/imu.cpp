#include "sim/sensors/imu.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "sim/physics/waves/wave_field.hpp"
#include "sim/sensors/csv_detail.hpp"

namespace driftlab::sim {

static_assert(kImuStandardGravity_m_s2 == kGravity_m_s2,
              "datasheet g must be the simulation's gravity");

ImuSample ideal_imu(const BodySample& b, const SensorMount& mount) {
  const VesselState& s = b.state;
  const Vec3& w = s.w_B;
  const Vec3& r = mount.p_B;
  // Acceleration of the mount point relative to inertial space, in body axes.
  // v_dot_B differentiates the body-axes velocity in the rotating body frame,
  // hence the w x v term (transport theorem: d/dt (R v_B) = R (v_dot_B + w_B x v_B)).
  const Vec3 a_B = b.v_dot_B + w.cross(s.v_B) + b.w_dot_B.cross(r) + w.cross(w.cross(r));
  const Vec3 g_B = s.q_W_B.conjugate() * Vec3(0.0, 0.0, kGravity_m_s2);
  ImuSample out;
  out.t_ns = b.t_ns;
  out.gyro_rad_s = mount.R_B_S.transpose() * w;
  out.accel_m_s2 = mount.R_B_S.transpose() * (a_B - g_B);
  return out;
}

ImuSimulator::Triad::Triad(const ImuTriadOptions& options, const RngStreams& rng,
                           const std::string& prefix)
    : o(options), noise(rng.stream(prefix + ".noise")), walk(rng.stream(prefix + ".bias_walk")) {
  Rng turn_on = rng.stream(prefix + ".turn_on");
  Rng intrinsics = rng.stream(prefix + ".intrinsics");
  for (int i = 0; i < 3; ++i) state.bias[i] = o.turn_on_bias * turn_on.normal();
  // Diagonal first, then the six off-diagonal entries row by row: a fixed
  // draw order so that the matrix is reproducible from the seed.
  for (int i = 0; i < 3; ++i) state.M(i, i) = 1.0 + o.scale_factor_ppm * 1e-6 * intrinsics.normal();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (i != j) state.M(i, j) = o.misalignment_mrad * 1e-3 * intrinsics.normal();
}

Vec3 ImuSimulator::Triad::apply(const Vec3& truth, double dt, bool first) {
  // Kalibr's discretisation: the bias takes one random-walk step of
  // sigma_b * sqrt(dt) per sample, the white noise of density sigma has the
  // discrete standard deviation sigma / sqrt(dt) (band-limited to Nyquist).
  if (!first) {
    const double step = o.random_walk * std::sqrt(dt);
    for (int i = 0; i < 3; ++i) state.bias[i] += step * walk.normal();
  }
  const double white = o.noise_density / std::sqrt(dt);
  Vec3 y = state.M * truth + state.bias;
  for (int i = 0; i < 3; ++i) {
    y[i] += white * noise.normal();
    if (o.range > 0) y[i] = std::clamp(y[i], -o.range, o.range);
  }
  return y;
}

ImuSimulator::ImuSimulator(const ImuOptions& options, const RngStreams& rng, std::string name)
    // Validated before any member uses a field (members initialise in order).
    : options_((validate_sensor_options(options, "sensors." + name), options)),
      mount_(SensorMount::from_options(options.mount)),
      dt_s_(1.0 / options.rate_hz),
      gyro_(options.gyro(), rng, name + ".gyro"),
      accel_(options.accel(), rng, name + ".accel"),
      clock_(options.clock, rng, name) {}

std::optional<ImuSample> ImuSimulator::measure(const BodySample& b) {
  const ImuSample truth = ideal_imu(b, mount_);
  ImuSample out;
  out.gyro_rad_s = gyro_.apply(truth.gyro_rad_s, dt_s_, first_);
  out.accel_m_s2 = accel_.apply(truth.accel_m_s2, dt_s_, first_);
  first_ = false;
  const SampleTime t = clock_.stamp(b.t_ns);
  if (t.dropped) return std::nullopt;
  out.t_ns = t.t_stamp_ns;
  return out;
}

ImuCsvWriter::ImuCsvWriter(const std::filesystem::path& path)
    : rows_(path,
            "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
            "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n",
            "IMU") {}

void ImuCsvWriter::write(const ImuSample& s) {
  DRIFTLAB_DEMAND_MSG(s.gyro_rad_s.allFinite() && s.accel_m_s2.allFinite(),
                      fmt::format("IMU sample at t = {} ns is not finite", s.t_ns));
  std::string* line = rows_.begin_row(s.t_ns);
  for (const Vec3* v : {&s.gyro_rad_s, &s.accel_m_s2})
    for (int i = 0; i < 3; ++i) csv_detail::append_double(line, (*v)[i]);
  rows_.end_row();
}

}  // namespace driftlab::sim
