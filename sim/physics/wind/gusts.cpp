#include "sim/physics/wind/gusts.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace driftlab::sim {
namespace {

constexpr double kGustTwoPi = 2 * std::numbers::pi;
constexpr double kGustLowest_hz = 0.03, kGustHighest_hz = 2.0;

// The integral scale of IEC 61400-1's Kaimal spectrum: 8.1 Lambda, Lambda = 0.7 z below 60 m.
double integral_scale_m() { return 8.1 * 0.7 * kCanopyHeight_m; }

}  // namespace

double kaimal_spectrum(double f_hz, double speed_mps) {
  const double sigma = kTurbulenceIntensity * speed_mps, l_over_u = integral_scale_m() / speed_mps;
  return 4 * sigma * sigma * l_over_u / std::pow(1 + 6 * f_hz * l_over_u, 5.0 / 3.0);
}

double sway_variance_m2(double f0_hz, double f1_hz, double speed_mps) {
  // Midpoint rule over 256 log-spaced steps: the resonance (width 2 zeta f_n = 0.07 Hz) is
  // resolved in every band.
  constexpr int kSteps = 256;
  const double ratio = std::pow(f1_hz / f0_hz, 1.0 / kSteps);
  const double drag = 2 * kSwayCompliance_s2_per_m * speed_mps;
  double v = 0;
  for (int i = 0; i < kSteps; ++i) {
    const double a = f0_hz * std::pow(ratio, i), b = a * ratio, f = std::sqrt(a * b);
    const double g = drag * sway_gain(f);
    v += g * g * kaimal_spectrum(f, speed_mps) * (b - a);
  }
  return v;
}

double sway_gain(double f_hz) {
  const double r = f_hz / kSwayFrequency_hz;
  return 1 / std::hypot(1 - r * r, 2 * kSwayDamping * r);
}

double sway_lag_rad(double f_hz) {
  const double r = f_hz / kSwayFrequency_hz;
  return std::atan2(2 * kSwayDamping * r, 1 - r * r);
}

double VegetationSway::sway_m(const Eigen::Vector2d& p_W, double t_s) const {
  const double s = direction_W.dot(p_W);
  double x = 0;
  for (const SwayComponent& c : components)
    x += c.amplitude_m * std::sin(c.omega_rad_s * t_s - c.wavenumber_rad_m * s + c.phase_rad);
  return x;
}

double VegetationSway::flutter_m(const Eigen::Vector3d& p, double t_s) const {
  return flutter_amplitude_m *
         std::sin(flutter_omega_rad_s * t_s + 37.0 * p.x() + 91.0 * p.y() + 53.0 * p.z());
}

double VegetationSway::sway_bound_m() const {
  double a = 0;
  for (const SwayComponent& c : components) a += c.amplitude_m;
  return a;
}

VegetationSway vegetation_sway(const WindOptions& wind, Rng rng) {
  VegetationSway v;
  const double u = wind.speed_mps;
  if (!wind.sway || u <= 0) return v;
  const double towards = wind.direction_deg * std::numbers::pi / 180;
  v.direction_W = Eigen::Vector2d(std::cos(towards), std::sin(towards));
  const double ratio = std::pow(kGustHighest_hz / kGustLowest_hz, 1.0 / kGustComponents);
  for (int k = 0; k < kGustComponents; ++k) {
    const double f0 = kGustLowest_hz * std::pow(ratio, k), f1 = f0 * ratio;
    const double f = std::sqrt(f0 * f1);  // the band's geometric centre
    SwayComponent c;
    c.amplitude_m = std::sqrt(2 * sway_variance_m2(f0, f1, u));
    c.omega_rad_s = kGustTwoPi * f;
    c.wavenumber_rad_m = kGustTwoPi * f / u;
    c.phase_rad = rng.uniform(0, kGustTwoPi) - sway_lag_rad(f);
    v.components.push_back(c);
  }
  v.flutter_amplitude_m = kFlutterAmplitude_m * (u / 5) * (u / 5);
  v.flutter_omega_rad_s = kGustTwoPi * kFlutterFrequency_hz;
  return v;
}

}  // namespace driftlab::sim
