// Wave fields: one object answers every question about the water surface and
// the flow beneath it, so that vessel physics and renderer see the same sea.
//
// Frames and signs: world NED (x north, y east, z down), still water at z = 0.
// Surface elevation eta is positive UP, so the surface is at z = -eta(x, y, t).
// Time t in seconds (double: this is used inside integrators).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <span>
#include <vector>

#include "core/rng.hpp"
#include "sim/physics/waves/wave_options.hpp"

namespace driftlab::sim {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;

constexpr double kGravity_m_s2 = 9.80665;
constexpr double kWaterDensity_kg_m3 = 1000.0;

/// One regular (Airy) component of a linear wave field, fully resolved:
/// eta = amplitude * cos(k (x cos(direction) + y sin(direction)) - omega t + phase).
struct WaveComponent {
  double amplitude_m = 0.0;       ///< zeta_a [m]
  double wavenumber_rad_m = 0.0;  ///< k = 2 pi / lambda [rad/m]
  double omega_rad_s = 0.0;       ///< angular frequency [rad/s], omega^2 = g k tanh(k h)
  double direction_rad = 0.0;     ///< direction of travel, clockwise from north [rad]
  double phase_rad = 0.0;         ///< phase at the origin at t = 0 [rad]
};

class WaveField {
 public:
  virtual ~WaveField() = default;

  /// Surface elevation eta [m], positive up, at horizontal position (north, east).
  virtual double elevation(double x_m, double y_m, double t_s) const = 0;
  /// Surface slope (d eta / dx, d eta / dy) [-].
  virtual Vec2 slope(double x_m, double y_m, double t_s) const = 0;
  /// Orbital velocity of the water [m/s] in NED at a point (NED, z down).
  virtual Vec3 velocity(const Vec3& p_ned_m, double t_s) const = 0;
  /// Orbital acceleration [m/s^2] in NED at a point.
  virtual Vec3 acceleration(const Vec3& p_ned_m, double t_s) const = 0;
  /// Dynamic (wave) pressure [Pa] at a point: total pressure is
  /// rho * g * z + dynamic_pressure (linear theory; above still water the value
  /// at z = 0 is used, so that the total pressure vanishes at a crest).
  virtual double dynamic_pressure(const Vec3& p_ned_m, double t_s) const = 0;
  /// True for a flat, still surface (lets callers skip work).
  virtual bool is_calm() const { return false; }
  /// The regular components this field sums (empty when calm), e.g. for a
  /// renderer that evaluates the same surface on the GPU.
  virtual std::span<const WaveComponent> components() const { return {}; }
};

/// Builds the wave field of `options`; random phases (JONSWAP) come from
/// `rng` (the scenario's "waves.phases" stream). Throws UserError naming the
/// field and value for options that validate() rejects (options built in code
/// may not have been validated); the physically impossible ones (a trough
/// reaching the bottom) are among those, through require() rules in visit().
std::unique_ptr<WaveField> make_wave_field(const WaveOptions& options, Rng rng);

/// The components make_wave_field() sums for `options` (empty for calm), with
/// the same random phases for the same `rng`. Throws UserError like it.
std::vector<WaveComponent> wave_components(const WaveOptions& options, Rng rng);

/// Mean-square slope of wind ripples at wind speed u [m/s] over the water:
/// the wind term of Cox and Munk's fit for a slick-covered surface,
/// sigma^2 = 1.56e-3 u (Cox & Munk 1954, J. Opt. Soc. Am. 44(11), Eq. 4b; the
/// constant 0.008 of that fit comes from the open sea's longer waves, which a
/// river does not have).
double ripple_mean_square_slope(double u_mps);

/// JONSWAP spectral density S(omega) [m^2 s/rad] of significant height hs [m],
/// peak period tp [s] and peak enhancement gamma >= 1 (Hasselmann et al. 1973,
/// in the form of DNV-RP-C205 Sec. 3.5.5); 0 for omega <= 0.
double jonswap_spectrum(double omega_rad_s, double hs_m, double tp_s, double gamma);

/// Finite-depth dispersion relation omega^2 = g k tanh(k h): angular frequency
/// [rad/s] of wavenumber k [rad/m] in depth h [m].
double dispersion_omega(double k_rad_m, double depth_m);
/// Inverse of dispersion_omega(): wavenumber of angular frequency omega.
double dispersion_wavenumber(double omega_rad_s, double depth_m);

/// Water current [m/s] in NED at a horizontal position (uniform, or a
/// bank-to-bank profile across a channel of `channel_half_width_m`).
Vec3 current_velocity(const CurrentOptions& options, double x_m, double y_m,
                      double channel_half_width_m);

}  // namespace driftlab::sim
