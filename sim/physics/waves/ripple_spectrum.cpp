// Wind ripples from the Elfouhaily et al. (1997) spectrum by FFT.
//
// References:
//   [E97] T. Elfouhaily, B. Chapron, K. Katsaros, D. Vandemark (1997), "A unified
//         directional spectrum for long and short wind-driven waves", J. Geophys.
//         Res. 102(C7), 15781-15796. Long waves B_l (Sec. 3.1), short waves B_h
//         (Sec. 3.2), fetch through Omega_c (Sec. 3.1), spreading Delta (Sec. 4).
//   [T01] J. Tessendorf (2001), "Simulating Ocean Water", SIGGRAPH course notes,
//         Sec. 4.3-4.4: random amplitudes on a periodic grid, advanced in time by
//         the dispersion relation, one inverse FFT per field.
//   [OB10] M. Olano, D. Baker (2010), "LEAN mapping", I3D: filtered first and
//         second moments of slope give the slope variance a filter footprint hides.

#include "sim/physics/waves/ripple_spectrum.hpp"

#include <fftw3.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <complex>
#include <cstdint>
#include <mutex>
#include <numbers>

#include "core/error.hpp"
#include "core/yaml_io.hpp"
#include "sim/physics/waves/wave_field.hpp"

// Same bytes whether or not a compiler would fuse a * b + c (see core/rng.cpp).
#ifdef __clang__
#pragma STDC FP_CONTRACT OFF
#endif

namespace driftlab::sim {

namespace {

constexpr double kKm_rad_m = 370.0;  // [E97] k_m: the minimum phase speed's wavenumber
constexpr double kCm_m_s = 0.23;     // [E97] c_m: the minimum phase speed
constexpr double kDrag10 = 1.44e-3;  // [E97] neutral drag coefficient at 10 m, u* = sqrt(C_D) U10

// FFTW's planner is not thread-safe (its executor is): plans are made and
// destroyed under one lock.
std::mutex& fftw_planner_mutex() {
  static std::mutex m;
  return m;
}

}  // namespace

std::string fft_library_version() { return fftwf_version; }

double gravity_capillary_omega(double k_rad_m) {
  const double r = k_rad_m / kKm_rad_m;
  return std::sqrt(kGravity_m_s2 * k_rad_m * (1.0 + r * r));
}

ElfouhailySpectrum::ElfouhailySpectrum(double u10_mps, double fetch_m) : u10_(u10_mps) {
  DRIFTLAB_DEMAND_MSG(u10_mps > 0.0 && fetch_m > 0.0, "ElfouhailySpectrum needs u10, fetch > 0");
  // [E97] Sec. 3.1: the inverse wave age of a fetch-limited sea, within the
  // fit's range from a fully developed sea (0.84) to a very young one (5).
  const double k0 = kGravity_m_s2 / (u10_mps * u10_mps);
  const double x = k0 * fetch_m;
  omega_c_ = 0.84 * std::pow(std::tanh(std::pow(x / 2.2e4, 0.4)), -0.75);
  omega_c_ = std::clamp(omega_c_, 0.84, 5.0);
  k_p_ = k0 * omega_c_ * omega_c_;
  c_p_ = gravity_capillary_omega(k_p_) / k_p_;
  u_star_ = std::sqrt(kDrag10) * u10_mps;
  alpha_p_ = 6e-3 * std::pow(omega_c_, 0.55);
  // alpha_m: the short waves' equilibrium range; it vanishes in light air
  // (u* below c_m / e, U10 below about 2.2 m/s), where the fit goes negative.
  const double lm = std::log(u_star_ / kCm_m_s);
  alpha_m_ = std::max(0.0, 0.01 * (u_star_ <= kCm_m_s ? 1.0 + lm : 1.0 + 3.0 * lm));
  gamma_ = omega_c_ < 1.0 ? 1.7 : 1.7 + 6.0 * std::log10(omega_c_);
  sigma_ = 0.08 * (1.0 + 4.0 / (omega_c_ * omega_c_ * omega_c_));
}

double ElfouhailySpectrum::curvature(double k) const {
  if (k <= 0.0) return 0.0;
  const double c = gravity_capillary_omega(k) / k;
  const double sk = std::sqrt(k / k_p_);
  const double l_pm = std::exp(-1.25 * (k_p_ / k) * (k_p_ / k));  // Pierson-Moskowitz shape
  const double big_gamma = std::exp(-(sk - 1.0) * (sk - 1.0) / (2.0 * sigma_ * sigma_));
  const double j_p = std::pow(gamma_, big_gamma);  // JONSWAP peak enhancement
  const double omega = u10_ / c_p_;
  const double f_p = l_pm * j_p * std::exp(-omega / std::sqrt(10.0) * (sk - 1.0));
  const double b_l = 0.5 * alpha_p_ * (c_p_ / c) * f_p;
  const double f_m = l_pm * j_p * std::exp(-0.25 * (k / kKm_rad_m - 1.0) * (k / kKm_rad_m - 1.0));
  const double b_h = 0.5 * alpha_m_ * (kCm_m_s / c) * f_m;
  return b_l + b_h;
}

double ElfouhailySpectrum::spreading(double k) const {
  const double c = gravity_capillary_omega(k) / k;
  const double a_m = 0.13 * u_star_ / kCm_m_s;
  return std::tanh(std::log(2.0) / 4.0 + 4.0 * std::pow(c / c_p_, 2.5) +
                   a_m * std::pow(kCm_m_s / c, 2.5));
}

double ElfouhailySpectrum::directional(double k, double phi) const {
  if (k <= 0.0) return 0.0;
  const double s = curvature(k) / (k * k * k);  // S(k) [m^3]
  return s * (1.0 + spreading(k) * std::cos(2.0 * phi)) / (2.0 * std::numbers::pi) / k;
}

double ElfouhailySpectrum::mean_square_slope(double k_lo, double k_hi) const {
  // Simpson's rule in ln k: integral of B(k) d(ln k).
  constexpr int n = 2000;
  const double a = std::log(k_lo), h = (std::log(k_hi) - a) / n;
  double sum = 0.0;
  for (int i = 0; i <= n; ++i) {
    const double w = (i == 0 || i == n) ? 1.0 : (i % 2 == 1 ? 4.0 : 2.0);
    sum += w * curvature(std::exp(a + h * i));
  }
  return sum * h / 3.0;
}

// ---------------------------------------------------------------------------

struct RippleMaps::Impl {
  static constexpr int N = kResolution;
  struct Tile {
    double size_m = 0.0;
    std::vector<std::complex<double>> h0;  // [E97] amplitudes at t = 0, row (ky) major
    std::vector<double> omega;             // omega(k) + k . U [rad/s]
    std::vector<std::uint32_t> active;     // the indices of non-zero h0
    std::vector<double> variance;          // 2 k^2 E|h0(k)|^2: the expected slope variance
    std::vector<std::vector<float>> levels;
  };
  std::array<Tile, kTiles> tiles;
  double mean_square_slope = 0.0;
  bool empty = true;
  bool baked = false;
  double baked_t = 0.0;
  // The FFT in single precision (the maps are floats): fftwf_malloc'ed, N * N.
  std::complex<float>* buffer = nullptr;
  fftwf_plan plan = nullptr;

  // Wave vector of grid index i (0..N-1) on a tile of size L: FFT order.
  static double wavenumber(int i, double L) {
    return 2.0 * std::numbers::pi * (i < N / 2 ? i : i - N) / L;
  }
  void fill_tile(Tile* tile, const ElfouhailySpectrum& spectrum, double k_lo, double k_hi,
                 double wind_rad, const Vec2& current, Rng* rng) const;
  void moments(Tile* tile) const;
};

void RippleMaps::Impl::fill_tile(Tile* tile, const ElfouhailySpectrum& spectrum, double k_lo,
                                 double k_hi, double wind_rad, const Vec2& current,
                                 Rng* rng) const {
  const double L = tile->size_m, dk = 2.0 * std::numbers::pi / L;
  const Vec2 w(std::cos(wind_rad), std::sin(wind_rad));
  tile->h0.assign(static_cast<std::size_t>(N) * N, {0.0, 0.0});
  tile->omega.assign(static_cast<std::size_t>(N) * N, 0.0);
  tile->variance.assign(static_cast<std::size_t>(N) * N, 0.0);
  for (int r = 0; r < N; ++r) {
    for (int c = 0; c < N; ++c) {
      const Vec2 k(wavenumber(c, L), wavenumber(r, L));
      const double kn = k.norm();
      const std::size_t i = static_cast<std::size_t>(r) * N + c;
      // The draw comes first so that every index takes the same two normals.
      const double xr = rng->normal(), xi = rng->normal();
      tile->omega[i] = gravity_capillary_omega(kn) + k.dot(current);
      // The Nyquist row and column have no partner -k on the grid: left out.
      if (r == N / 2 || c == N / 2 || kn < k_lo || kn >= k_hi) continue;
      // [T01] Eq. 42: Gaussian amplitudes of variance Psi dk^2; the waves
      // travel downwind (the half plane k . w > 0 holds all of it).
      const double cos_phi = k.dot(w) / kn;
      const double side = cos_phi > 0.0 ? 1.0 : (cos_phi == 0.0 ? 0.5 : 0.0);
      const double phi = std::atan2(w.x() * k.y() - w.y() * k.x(), k.dot(w));
      const double var = side * spectrum.directional(kn, phi) * dk * dk;
      tile->h0[i] = std::sqrt(0.5 * var) * std::complex<double>(xr, xi);
      tile->variance[i] = 2.0 * kn * kn * var;  // with its partner at -k
      if (var > 0.0) tile->active.push_back(static_cast<std::uint32_t>(i));
    }
  }
}

void RippleMaps::Impl::moments(Tile* tile) const {
  // Level 0 from the FFT's output: real part sx, imaginary part sy.
  tile->levels.resize(static_cast<std::size_t>(std::countr_zero(unsigned(N)) + 1));
  std::vector<float>& l0 = tile->levels[0];
  l0.resize(4 * static_cast<std::size_t>(N) * N);
  for (std::size_t i = 0; i < static_cast<std::size_t>(N) * N; ++i) {
    const float sx = buffer[i].real(), sy = buffer[i].imag();
    l0[4 * i] = sx;
    l0[4 * i + 1] = sy;
    l0[4 * i + 2] = sx * sx;
    l0[4 * i + 3] = sy * sy;
  }
  // [OB10] Each coarser level the mean of 2 x 2 texels of the one above.
  for (std::size_t l = 1; l < tile->levels.size(); ++l) {
    const int n = N >> l, m = 2 * n;
    const std::vector<float>& up = tile->levels[l - 1];
    std::vector<float>& out = tile->levels[l];
    out.resize(4 * static_cast<std::size_t>(n) * n);
    for (int r = 0; r < n; ++r)
      for (int c = 0; c < n; ++c)
        for (int ch = 0; ch < 4; ++ch) {
          auto at = [&](int rr, int cc) {
            return double(up[4 * (static_cast<std::size_t>(rr) * m + cc) + ch]);
          };
          const double s = at(2 * r, 2 * c) + at(2 * r, 2 * c + 1) + at(2 * r + 1, 2 * c) +
                           at(2 * r + 1, 2 * c + 1);
          out[4 * (static_cast<std::size_t>(r) * n + c) + ch] = static_cast<float>(0.25 * s);
        }
  }
}

RippleMaps::RippleMaps(const WindOptions& wind, const CurrentOptions& current, Rng rng)
    : impl_(std::make_unique<Impl>()) {
  yaml::validate_or_throw(wind, "water.wind");
  yaml::validate_or_throw(current, "water.current");
  const double u = wind.speed_mps * wind.shelter;
  if (u <= 0.0) return;
  Impl& m = *impl_;
  m.empty = false;
  const ElfouhailySpectrum spectrum(u, wind.fetch_m);
  const double golden = (1.0 + std::sqrt(5.0)) / 2.0;
  m.tiles[0].size_m = 4.0;
  m.tiles[1].size_m = 4.0 / (golden * golden * golden);
  const double k_split = 2.0 * std::numbers::pi / kSplitWavelength_m;
  const double k_short = 2.0 * std::numbers::pi / kShortestWavelength_m;
  const double cd = current.direction_deg * std::numbers::pi / 180.0;
  const Vec2 U = current.speed_mps * Vec2(std::cos(cd), std::sin(cd));
  const double wind_rad = wind.direction_deg * std::numbers::pi / 180.0;
  m.fill_tile(&m.tiles[0], spectrum, 0.0, k_split, wind_rad, U, &rng);
  m.fill_tile(&m.tiles[1], spectrum, k_split, k_short, wind_rad, U, &rng);
  // The expected slope variance the tiles hold.
  for (const Impl::Tile& t : m.tiles)
    for (std::size_t i = 0; i < t.h0.size(); ++i) m.mean_square_slope += t.variance[i];
  // Light air over a short fetch: a spectrum peaked at waves shorter than the
  // tiles hold, whose slopes underflow to zero; the water stays a mirror.
  if (!(m.mean_square_slope > 0.0)) {
    m.empty = true;
    return;
  }
  if (wind.ripple_level == RippleLevel::kSlick) {
    // Cox and Munk's slick-surface level; the spectrum gives the shape.
    const double target = ripple_mean_square_slope(u);
    const double scale = std::sqrt(target / m.mean_square_slope);
    for (Impl::Tile& t : m.tiles)
      for (auto& h : t.h0) h *= scale;
    m.mean_square_slope = target;
  }
  const std::lock_guard lock(fftw_planner_mutex());
  m.buffer = static_cast<std::complex<float>*>(
      fftwf_malloc(sizeof(std::complex<float>) * Impl::N * Impl::N));
  auto* b = reinterpret_cast<fftwf_complex*>(m.buffer);
  // FFTW_ESTIMATE: the same plan on every run (a measured plan may differ, and
  // with it the rounding).
  m.plan = fftwf_plan_dft_2d(Impl::N, Impl::N, b, b, FFTW_BACKWARD, FFTW_ESTIMATE);
}

RippleMaps::~RippleMaps() {
  if (!impl_ || impl_->buffer == nullptr) return;
  const std::lock_guard lock(fftw_planner_mutex());
  fftwf_destroy_plan(impl_->plan);
  fftwf_free(impl_->buffer);
}

bool RippleMaps::empty() const { return impl_->empty; }
double RippleMaps::tile_size_m(int tile) const {
  return impl_->tiles[static_cast<std::size_t>(tile)].size_m;
}
int RippleMaps::levels() const { return std::countr_zero(unsigned(kResolution)) + 1; }
double RippleMaps::mean_square_slope() const { return impl_->mean_square_slope; }

void RippleMaps::bake(double t_s) {
  Impl& m = *impl_;
  DRIFTLAB_DEMAND_MSG(!m.empty, "RippleMaps::bake without wind");
  if (m.baked && m.baked_t == t_s) return;
  constexpr int N = Impl::N;
  for (Impl::Tile& tile : m.tiles) {
    // [T01] Eq. 43: h(k, t) = h0(k) e^{-i omega(k) t} + conj(h0(-k)) e^{i omega(-k) t};
    // the slopes i k h packed as one complex field, sx + i sy (both real). Only
    // one of h0(k), h0(-k) is non-zero (the waves travel downwind): each wave
    // adds its term at k and its conjugate at -k.
    std::fill(m.buffer, m.buffer + static_cast<std::size_t>(N) * N, std::complex<float>());
    for (const std::uint32_t i : tile.active) {
      const int r = static_cast<int>(i) / N, c = static_cast<int>(i) % N;
      const std::size_t j = static_cast<std::size_t>((N - r) % N) * N + (N - c) % N;
      const std::complex<double> a = tile.h0[i] * std::polar(1.0, -tile.omega[i] * t_s);
      const double kx = Impl::wavenumber(c, tile.size_m), ky = Impl::wavenumber(r, tile.size_m);
      m.buffer[i] += std::complex<float>(std::complex<double>(-ky, kx) * a);
      m.buffer[j] += std::complex<float>(std::complex<double>(ky, -kx) * std::conj(a));
    }
    fftwf_execute(m.plan);
    m.moments(&tile);
  }
  m.baked = true;
  m.baked_t = t_s;
}

std::span<const float> RippleMaps::level(int tile, int level) const {
  DRIFTLAB_DEMAND_MSG(impl_->baked, "RippleMaps::level before bake()");
  return impl_->tiles[static_cast<std::size_t>(tile)].levels[static_cast<std::size_t>(level)];
}

}  // namespace driftlab::sim
