// Wind ripples from a spectrum: the short-fetch wind-wave spectrum of
// Elfouhaily et al. (1997), sampled on two periodic tiles and turned into slope
// maps by FFT once per time step (Tessendorf's method), shared by both eyes.
//
// Frames: world NED (x north, y east), slopes d(eta)/dx, d(eta)/dy with eta up.
#pragma once

#include <array>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "core/rng.hpp"
#include "sim/physics/waves/wave_options.hpp"

namespace driftlab::sim {

/// The FFT library's version and build ("fftw-3.3.10-sse2-avx2"): its plans, and so the
/// slope maps' last bits, depend on them (a part of the frame cache's key).
std::string fft_library_version();

/// Deep-water dispersion of gravity-capillary waves:
/// omega^2 = g k (1 + (k / k_m)^2), k_m = 370 rad/m (Elfouhaily et al. 1997, Sec. 2).
double gravity_capillary_omega(double k_rad_m);

/// The unified directional spectrum of wind waves of Elfouhaily, Chapron,
/// Katsaros and Vandemark (1997), "A unified directional spectrum for long and
/// short wind-driven waves", J. Geophys. Res. 102(C7), 15781-15796: a long-wave
/// part set by the fetch (inverse wave age Omega_c) and a short-wave
/// (capillary) part set by the friction velocity u*, with the spreading
/// Phi(k, phi) = (1 + Delta(k) cos 2 phi) / (2 pi).
class ElfouhailySpectrum {
 public:
  /// Wind speed at 10 m u10 > 0 [m/s] and fetch > 0 [m].
  ElfouhailySpectrum(double u10_mps, double fetch_m);

  /// Curvature spectrum B(k) = k^3 S(k) [-], S the omnidirectional elevation
  /// spectrum [m^3] (Sec. 3: B = B_l + B_h).
  double curvature(double k_rad_m) const;
  /// Delta(k) of the spreading function (Sec. 4).
  double spreading(double k_rad_m) const;
  /// Elevation spectrum per unit wavenumber area Psi(kx, ky) =
  /// S(k) Phi(k, phi) / k [m^4], phi measured from the wind (towards).
  double directional(double k_rad_m, double phi_rad) const;

  double inverse_wave_age() const { return omega_c_; }  ///< Omega_c
  double peak_wavenumber() const { return k_p_; }       ///< k_p [rad/m]
  double friction_velocity() const { return u_star_; }  ///< u* [m/s]
  /// Mean square slope of the waves from k_lo to k_hi: the integral of B(k) / k.
  double mean_square_slope(double k_lo_rad_m, double k_hi_rad_m) const;

 private:
  double u10_, omega_c_, k_p_, c_p_, u_star_, alpha_p_, alpha_m_, gamma_, sigma_;
};

/// The wind ripples as slope maps: two square tiles of incommensurate size
/// (4 m and 4 / phi^3 m, phi the golden ratio) share the spectrum between
/// them (waves longer than kSplitWavelength_m on the large tile, shorter ones
/// down to kShortestWavelength_m on the small one), each sampled at
/// kResolution^2 wave vectors with Gaussian amplitudes, all travelling
/// downwind, and advected by the surface current (omega + k . U). bake(t)
/// gives for each tile the mip levels of the slope moments (sx, sy, sx^2,
/// sy^2): a level's mean of the squares less the square of its mean is the
/// slope variance of the ripples too short for that level (LEAN mapping,
/// Olano and Baker 2010), which the renderer turns into the rough mirror's blur.
class RippleMaps {
 public:
  static constexpr int kResolution = 256;
  static constexpr int kTiles = 2;
  static constexpr double kSplitWavelength_m = 0.125;
  static constexpr double kShortestWavelength_m = 0.02;

  /// The ripples of `wind` (speed times shelter at the water) over `current`
  /// (its speed and direction; uniform), random amplitudes and phases from
  /// `rng`. Throws UserError for invalid options. empty() without wind.
  RippleMaps(const WindOptions& wind, const CurrentOptions& current, Rng rng);
  ~RippleMaps();
  RippleMaps(const RippleMaps&) = delete;
  RippleMaps& operator=(const RippleMaps&) = delete;

  bool empty() const;
  double tile_size_m(int tile) const;
  int levels() const;  ///< mip levels per tile: log2(kResolution) + 1
  /// The expected mean square slope of the maps (both tiles, both axes).
  double mean_square_slope() const;

  /// Computes the maps at time t_s (once per t: a repeated t returns at once).
  void bake(double t_s);
  /// Level `level` of `tile` after bake(): (kResolution >> level)^2 texels of
  /// four floats (sx, sy, sx^2, sy^2), row-major; columns run along x (north),
  /// rows along y (east), texel (0, 0) at the tile's origin.
  std::span<const float> level(int tile, int level) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace driftlab::sim
