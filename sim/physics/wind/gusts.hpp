// The wind in the vegetation (docs/renderer-and-scenes.md, "Wind in the vegetation"): the gusts of
// water.wind, and how the river bank's trees, bushes and reeds sway in them, in closed form so that
// every instant a renderer draws has its exact pose.
//
// Gusts: the along-wind turbulence u'(t) of a mean wind U has the Kaimal spectrum of IEC
// 61400-1 (Annex C), S(f) = 4 sigma^2 (L / U) / (1 + 6 f L / U)^(5/3), sigma = I U with the
// turbulence intensity I = kTurbulenceIntensity and the integral scale L = 8.1 x 0.7 z at
// z = kCanopyHeight_m; it is a sum of kGustComponents sinusoids over log-spaced bands,
// amplitude sqrt(2 S(f_k) df_k), and moves downwind with the mean wind (Taylor's frozen
// turbulence), so neighbouring trees sway together and a gust crosses the reach at U.
// Each component carries the response variance of its band (sway_variance_m2), at the
// band's geometric centre frequency.
//
// Sway: a plant is a damped oscillator (its first bending mode: natural frequency
// kSwayFrequency_hz, damping ratio kSwayDamping) driven by the fluctuating drag, linearised about
// the mean, 2 C U u'(t): a unit-weight vertex (the top of a kReferenceTreeHeight_m tree) moves
// downwind by x(t) = sum_k 2 C U a_k |H(f_k)| sin(2 pi f_k (t - s / U) + phi_k - arg H(f_k)), H(f)
// = 1 / (1 - r^2 + 2 i zeta r), r = f / f_n, s the vertex's distance along the wind, C the
// compliance kSwayCompliance_s2_per_m (mean top deflection over U^2). The mean deflection itself
// is a static bend, left out. Leaves also flutter: kFlutterFrequency_hz, amplitude
// kFlutterAmplitude_m (U / 5 m/s)^2, a phase from the vertex's position.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "core/rng.hpp"
#include "sim/physics/waves/wave_options.hpp"

namespace driftlab::sim {

inline constexpr double kTurbulenceIntensity = 0.2;        // near a tree line (IEC class A: 0.16)
inline constexpr double kCanopyHeight_m = 10.0;            // the height the gusts are taken at
inline constexpr int kGustComponents = 8;                  // 0.03-2 Hz, log-spaced
inline constexpr double kSwayFrequency_hz = 0.35;          // a 10-15 m broadleaf tree in leaf
inline constexpr double kSwayDamping = 0.1;                // structural and aerodynamic (0.05-0.2)
inline constexpr double kSwayCompliance_s2_per_m = 0.004;  // 10 cm of mean top bend at 5 m/s
inline constexpr double kReferenceTreeHeight_m = 12.0;
inline constexpr double kFlutterFrequency_hz = 3.0;
inline constexpr double kFlutterAmplitude_m = 0.01;  // at 5 m/s

/// One sinusoid of the sway of a unit-weight vertex: amplitude [m], angular frequency [rad/s],
/// wavenumber along the wind [rad/m] (omega / U), phase [rad] (the gust's, less the lag of H).
struct SwayComponent {
  double amplitude_m = 0;
  double omega_rad_s = 0;
  double wavenumber_rad_m = 0;
  double phase_rad = 0;
};

/// How the vegetation moves in one wind (empty: it stands still).
struct VegetationSway {
  Eigen::Vector2d direction_W = Eigen::Vector2d::UnitX();  // downwind, north-east, unit
  std::vector<SwayComponent> components;
  double flutter_amplitude_m = 0;
  double flutter_omega_rad_s = 0;

  bool empty() const { return components.empty() && flutter_amplitude_m == 0; }
  /// The downwind sway [m] of a unit-weight vertex at north-east position p_W at time t.
  double sway_m(const Eigen::Vector2d& p_W, double t_s) const;
  /// The flutter [m] of a unit-flutter vertex at p_W (NED) at time t (the shader's phase).
  double flutter_m(const Eigen::Vector3d& p_W, double t_s) const;
  /// The most a unit-weight vertex can sway: the sum of the amplitudes [m].
  double sway_bound_m() const;
};

/// The sway of water.wind (none when its speed is 0 or sway is off), phases from `rng`.
VegetationSway vegetation_sway(const WindOptions& wind, Rng rng);

/// The Kaimal spectrum of the along-wind gusts, S(f) [m^2/s^2 / Hz], of a mean wind U.
double kaimal_spectrum(double f_hz, double speed_mps);

/// The variance [m^2] of a unit-weight vertex's sway from the gusts between f0 and f1:
/// the integral of (2 C U |H(f)|)^2 S(f) (each SwayComponent carries its band's).
double sway_variance_m2(double f0_hz, double f1_hz, double speed_mps);

/// |H(f)| and arg H(f) of the damped oscillator of the sway.
double sway_gain(double f_hz);
double sway_lag_rad(double f_hz);

}  // namespace driftlab::sim
