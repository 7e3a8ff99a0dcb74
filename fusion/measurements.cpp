#include "fusion/measurements.hpp"

#include <cmath>

#include "core/rotation.hpp"

namespace driftlab::fusion {

BodyVelocityMeasurement body_velocity_from_vo(TimeNs t_ns, double dt_s, const vo::VoResult& vo,
                                              const SE3& T_B_C) {
  BodyVelocityMeasurement m;
  m.t_ns = t_ns;
  m.dt_s = dt_s;
  if (!vo.valid || !(dt_s > 0.0) || !std::isfinite(dt_s) || !vo::detail::is_finite(vo.T_prev_curr))
    return m;
  // Basin paper Section 3.1: t_k gives the body velocities and R_k's Euler angles the
  // rotation; both are first carried from the camera into the body frame.
  const SE3 T_Bprev_Bcurr = T_B_C * vo.T_prev_curr * T_B_C.inverse();
  const Vec3& t = T_Bprev_Bcurr.translation();
  const double yaw = euler_zyx_from_quat(T_Bprev_Bcurr.quaternion()).yaw_rad;
  m.surge_m_s = t.x() / dt_s;
  m.sway_m_s = t.y() / dt_s;
  m.yaw_rate_rad_s = yaw / dt_s;
  m.valid =
      std::isfinite(m.surge_m_s) && std::isfinite(m.sway_m_s) && std::isfinite(m.yaw_rate_rad_s);
  if (!m.valid) m.surge_m_s = m.sway_m_s = m.yaw_rate_rad_s = 0.0;
  return m;
}

GpsPositionMeasurement GpsPositionMeasurement::with_sd(TimeNs t_ns, const Vec3& p_W_m,
                                                       double sd_horizontal_m,
                                                       double sd_vertical_m) {
  GpsPositionMeasurement g;
  g.t_ns = t_ns;
  g.p_W_m = p_W_m;
  g.covariance_m2 = Vec3(sd_horizontal_m * sd_horizontal_m, sd_horizontal_m * sd_horizontal_m,
                         sd_vertical_m * sd_vertical_m)
                        .asDiagonal();
  return g;
}

}  // namespace driftlab::fusion
