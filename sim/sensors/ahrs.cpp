#include "sim/sensors/ahrs.hpp"

#include <fmt/format.h>

#include <cmath>

#include "core/error.hpp"

namespace driftlab::sim {

namespace {

// Predicted direction d seen from the sensor, v = R(q)^T d, and its 3x4 Jacobian with respect
// to (w, x, y, z) of a not necessarily unit q: v = (w^2 - |u|^2) d + 2 (u.d) u - 2 w (u x d).
void predicted_direction(const Quat& q, const Vec3& d, Vec3* v, Eigen::Matrix<double, 3, 4>* J) {
  const double w = q.w();
  const Vec3 u = q.vec();
  *v = (w * w - u.squaredNorm()) * d + 2.0 * u.dot(d) * u - 2.0 * w * u.cross(d);
  J->col(0) = 2.0 * w * d - 2.0 * u.cross(d);
  for (int i = 0; i < 3; ++i) {
    const Vec3 e = Vec3::Unit(i);
    J->col(i + 1) = -2.0 * u[i] * d + 2.0 * d[i] * u + 2.0 * u.dot(d) * e - 2.0 * w * e.cross(d);
  }
}

}  // namespace

Quat madgwick_marg_update(const Quat& q, const Vec3& gyro_S, const Vec3& accel_S, const Vec3& mag_S,
                          double beta_rad_s, double dt_s) {
  // Rate of change from the gyroscope: q_dot = 1/2 q (x) (0, w).
  const Quat w(0.0, gyro_S.x(), gyro_S.y(), gyro_S.z());
  Eigen::Vector4d q_dot = 0.5 * (q * w).coeffs();  // Eigen's coeffs(): x, y, z, w
  // The gradient of 1/2 |f|^2, f = predicted - measured directions, stacked for the specific
  // force (reference (0, 0, -1) in NED) and the field (reference levelled from the measured one).
  Eigen::Vector4d grad = Eigen::Vector4d::Zero();  // in (w, x, y, z) order
  Vec3 v;
  Eigen::Matrix<double, 3, 4> J;
  if (accel_S.norm() > 0) {
    predicted_direction(q, Vec3(0.0, 0.0, -1.0), &v, &J);
    grad += J.transpose() * (v - accel_S.normalized());
  }
  if (mag_S.norm() > 0) {
    const Vec3 m = mag_S.normalized();
    const Vec3 h = q * m;  // the measured field in the earth frame
    const Vec3 b(std::hypot(h.x(), h.y()), 0.0, h.z());
    predicted_direction(q, b, &v, &J);
    grad += J.transpose() * (v - m);
  }
  if (grad.norm() > 0) {
    grad.normalize();
    q_dot -= beta_rad_s * Eigen::Vector4d(grad[1], grad[2], grad[3], grad[0]);
  }
  Quat out;
  out.coeffs() = q.coeffs() + q_dot * dt_s;
  out.normalize();
  return out;
}

AhrsSimulator::AhrsSimulator(const AhrsOptions& options, const Vec3& earth_field_W_nt,
                             const RngStreams& rng, std::string name)
    // Validated before any member uses a field (members initialise in order).
    : options_((validate_sensor_options(options, "sensors." + name), options)),
      imu_(options.imu(), rng, name),
      earth_W_(earth_field_W_nt),
      mag_noise_(rng.stream(name + ".magnetometer_noise")),
      dt_s_(1.0 / options.update_rate_hz) {}

std::optional<AhrsSample> AhrsSimulator::update(const BodySample& b) {
  // The truth in the filter's earth frame, magnetic NED: world NED turned by the declination.
  const Quat q_M_W(Eigen::AngleAxisd(-std::atan2(earth_W_.y(), earth_W_.x()), Vec3::UnitZ()));
  const Quat q_true = (q_M_W * b.state.q_W_B * Quat(imu_.mount().R_B_S)).normalized();
  if (updates_ == 0) q_W_S_ = q_true;
  const std::optional<ImuSample> m = imu_.measure(b);
  Vec3 mag = q_true.conjugate() * (q_M_W * earth_W_);
  for (int i = 0; i < 3; ++i) mag[i] += options_.magnetometer_noise_nt * mag_noise_.normal();
  if (updates_ > 0 && m) {
    q_W_S_ =
        madgwick_marg_update(q_W_S_, m->gyro_rad_s, m->accel_m_s2, mag, options_.beta_rad_s, dt_s_);
  }
  const bool report = updates_ % options_.updates_per_sample() == 0;
  ++updates_;
  if (!report) return std::nullopt;
  return AhrsSample{b.t_ns, euler_zyx_from_quat(q_W_S_), euler_zyx_from_quat(q_true)};
}

AhrsCsvWriter::AhrsCsvWriter(const std::filesystem::path& path)
    : rows_(path, "t_ns,roll_deg,pitch_deg,yaw_deg\n", "AHRS") {}

void AhrsCsvWriter::write(const AhrsSample& s) {
  const EulerZYX& e = s.euler;
  DRIFTLAB_DEMAND_MSG(
      std::isfinite(e.roll_rad) && std::isfinite(e.pitch_rad) && std::isfinite(e.yaw_rad),
      fmt::format("AHRS sample at t = {} ns is not finite", s.t_ns));
  std::string* line = rows_.begin_row(s.t_ns);
  for (double a : {e.roll_rad, e.pitch_rad, e.yaw_rad}) csv_detail::append_double(line, rad2deg(a));
  rows_.end_row();
}

}  // namespace driftlab::sim
