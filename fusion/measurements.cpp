#include "fusion/measurements.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
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

SecondDifferenceNoise::SecondDifferenceNoise(std::size_t channels, std::size_t window,
                                             std::size_t min_differences)
    : chains_(channels), window_(window), min_differences_(min_differences) {
  DRIFTLAB_DEMAND(channels > 0 && window > 0 && min_differences > 0 && min_differences <= window);
}

void SecondDifferenceNoise::add(std::size_t channel, double x) {
  DRIFTLAB_DEMAND(channel < chains_.size());
  Chain& c = chains_[channel];
  if (!std::isfinite(x)) {  // a broken sample breaks the chain like a gap
    c = Chain{};
    return;
  }
  if (c.n == 2) {
    abs_differences_.push_back(std::abs(x - 2.0 * c.x1 + c.x2));
    if (abs_differences_.size() > window_) abs_differences_.pop_front();
  }
  c.x2 = c.x1;
  c.x1 = x;
  c.n = std::min(c.n + 1, 2);
}

void SecondDifferenceNoise::gap() {
  for (Chain& c : chains_) c = Chain{};
}

std::optional<double> SecondDifferenceNoise::sigma() const {
  if (abs_differences_.size() < min_differences_) return std::nullopt;
  std::vector<double> d(abs_differences_.begin(), abs_differences_.end());
  const auto mid = d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2);
  std::nth_element(d.begin(), mid, d.end());
  double median = *mid;
  if (d.size() % 2 == 0) median = 0.5 * (median + *std::max_element(d.begin(), mid));
  // 0.6745: the standard normal's third quartile, median |N(0, 1)|.
  return median / (0.6744897501960817 * std::sqrt(6.0));
}

void SecondDifferenceNoise::reset() {
  gap();
  abs_differences_.clear();
}

}  // namespace driftlab::fusion
