#include "sim/sensors/compass.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "core/rotation.hpp"
#include "sim/sensors/csv_detail.hpp"
#include "sim/sensors/imu.hpp"

namespace driftlab::sim {

Vec3 earth_field_ned_nt(const CompassOptions& o) {
  const double inc = deg2rad(o.inclination_deg), dec = deg2rad(o.declination_deg);
  const double h = o.field_intensity_nt * std::cos(inc);
  return Vec3(h * std::cos(dec), h * std::sin(dec), o.field_intensity_nt * std::sin(inc));
}

Vec3 anomaly_field_ned_nt(const std::vector<MagneticAnomalyOptions>& anomalies, const Vec3& p) {
  Vec3 sum = Vec3::Zero();
  for (const auto& a : anomalies) {
    const Vec3 from(a.from_ned_m[0], a.from_ned_m[1], a.from_ned_m[2]);
    const Vec3 to(a.to_ned_m[0], a.to_ned_m[1], a.to_ned_m[2]);
    const Vec3 seg = to - from;
    const double len2 = seg.squaredNorm();
    const double s = len2 > 0 ? std::clamp((p - from).dot(seg) / len2, 0.0, 1.0) : 0.0;
    const double d = (p - (from + s * seg)).norm();
    // Smooth at the structure, power-law in the far field: a sheet-pile wall is
    // a line of induced dipoles, whose field falls as 1/d^2 (exponent 2); a
    // compact steel mass as a dipole, 1/d^3.
    const double scale = 1.0 / (1.0 + std::pow(d / a.decay_length_m, a.decay_exponent));
    sum += scale * Vec3(a.field_ned_nt[0], a.field_ned_nt[1], a.field_ned_nt[2]);
  }
  return sum;
}

double tilt_compensated_heading_rad(const Vec3& field_S, double roll_rad, double pitch_rad,
                                    double declination_rad) {
  // Undo roll then pitch: R_W_S = Rz(yaw) Ry(pitch) Rx(roll), so
  // Ry(pitch) Rx(roll) m_S = Rz(yaw)^T m_W, the field in the yawed, level frame,
  // whose horizontal part is H (cos(yaw - dec), -sin(yaw - dec)).
  const Vec3 level = Eigen::AngleAxisd(pitch_rad, Vec3::UnitY()) *
                     (Eigen::AngleAxisd(roll_rad, Vec3::UnitX()) * field_S);
  return wrap_angle_rad(std::atan2(-level.y(), level.x()) + declination_rad);
}

CompassSimulator::CompassSimulator(const CompassOptions& options, const RngStreams& rng,
                                   std::string name)
    // Validated before any member uses a field (members initialise in order).
    : options_((validate_sensor_options(options, "sensors." + name), options)),
      mount_(SensorMount::from_options(options.mount)),
      earth_W_(earth_field_ned_nt(options)),
      soft_iron_(
          Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(options.soft_iron.data())),
      hard_iron_(options.hard_iron_nt[0], options.hard_iron_nt[1], options.hard_iron_nt[2]),
      field_noise_(rng.stream(name + ".field_noise")),
      heading_noise_(rng.stream(name + ".heading_noise")),
      clock_(options.clock, rng, name) {}

CompassSimulator::Levelling CompassSimulator::levelling(const BodySample& b,
                                                        const EulerZYX& truth) const {
  switch (options_.levelling) {
    case CompassLevelling::kTrueAttitude:
      return {truth.roll_rad, truth.pitch_rad};
    case CompassLevelling::kAccelerometer: {
      // At rest the specific force is -g along the sensor's down: f = (g sin(pitch),
      // -g sin(roll) cos(pitch), -g cos(roll) cos(pitch)); any acceleration tilts it.
      const Vec3 f = ideal_imu(b, mount_).accel_m_s2;
      return {std::atan2(-f.y(), -f.z()), std::atan2(f.x(), std::hypot(f.y(), f.z()))};
    }
    case CompassLevelling::kNone:
      return {0.0, 0.0};
  }
  return {truth.roll_rad, truth.pitch_rad};
}

std::optional<CompassSample> CompassSimulator::measure(const BodySample& b) {
  const Quat q_W_S = b.state.q_W_B * Quat(mount_.R_B_S);
  const Vec3 p_W = b.state.p_W + b.state.q_W_B * mount_.p_B;
  // Field at the sensor: Earth + structures (world), turned into the sensor
  // frame, then the installation's soft iron (a linear distortion) and hard
  // iron (an offset): h_measured = C_si h + b_hi, the model of Gebre-Egziabher
  // et al., "Calibration of strapdown magnetometers in magnetic field domain",
  // J. Aerospace Engineering 19(2), 2006.
  const Vec3 world = earth_W_ + anomaly_field_ned_nt(options_.anomalies, p_W);
  const Vec3 distorted = soft_iron_ * (q_W_S.conjugate() * world) + hard_iron_;
  const EulerZYX e = euler_zyx_from_quat(q_W_S);
  const Levelling level = levelling(b, e);

  CompassSample s;
  s.true_heading_rad = e.yaw_rad;
  s.field_S_nt = distorted;
  for (int i = 0; i < 3; ++i) s.field_S_nt[i] += options_.field_noise_nt * field_noise_.normal();
  // The heading comes from the distorted but noise-free field: its noise is
  // sigma_deg by definition, not a by-product of field_noise_nt.
  s.heading_rad =
      wrap_angle_rad(tilt_compensated_heading_rad(distorted, level.roll_rad, level.pitch_rad,
                                                  deg2rad(options_.declination_deg)) +
                     deg2rad(options_.sigma_deg) * heading_noise_.normal());
  const SampleTime t = clock_.stamp(b.t_ns);
  if (t.dropped) return std::nullopt;
  s.t_ns = t.t_stamp_ns;
  return s;
}

CompassCsvWriter::CompassCsvWriter(const std::filesystem::path& path)
    : rows_(path, "#timestamp [ns],heading [deg],m_S_x [nT],m_S_y [nT],m_S_z [nT]\n", "compass") {}

void CompassCsvWriter::write(const CompassSample& s) {
  DRIFTLAB_DEMAND_MSG(std::isfinite(s.heading_rad) && s.field_S_nt.allFinite(),
                      fmt::format("compass sample at t = {} ns is not finite", s.t_ns));
  std::string* line = rows_.begin_row(s.t_ns);
  double deg = rad2deg(s.heading_rad);
  if (deg < 0) deg += 360.0;
  if (deg >= 360.0) deg -= 360.0;  // -tiny + 360 can round to 360
  csv_detail::append_double(line, deg);
  for (int i = 0; i < 3; ++i) csv_detail::append_double(line, s.field_S_nt[i]);
  rows_.end_row();
}

}  // namespace driftlab::sim
