// Linear (Airy) wave fields: calm water, regular waves, sums of regular waves
// and a discretised JONSWAP sea with cos-2s directional spreading.
//
// References for the formulas:
//   [DD]  R. G. Dean, R. A. Dalrymple, "Water Wave Mechanics for Engineers and
//         Scientists", World Scientific 1991, Ch. 3-4 (linear wave theory).
//   [DNV] DNV-RP-C205 "Environmental conditions and environmental loads" (2010),
//         Sec. 3.2.2 / Table 3-1 (Airy kinematics and pressure), Sec. 3.5.5
//         (JONSWAP), Sec. 3.5.8 (directional spreading).
//   [H73] K. Hasselmann et al. (1973), "Measurements of wind-wave growth and
//         swell decay during the Joint North Sea Wave Project (JONSWAP)".
//   [LH63] M. S. Longuet-Higgins, D. E. Cartwright, N. D. Smith (1963),
//         "Observations of the directional spectrum of sea waves using the
//         motions of a floating buoy"; cos-2s form as in Mitsuyasu et al. (1975).
//   [FM90] J. D. Fenton, W. D. McKee (1990), "On calculating the lengths of
//         water waves", Coastal Engineering 14, 499-513.
//   [J87] E. R. Jefferys (1987), "Directional seas should be ergodic", Applied
//         Ocean Research 9(4), 186-191.

#include "sim/physics/waves/wave_field.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

#include "core/error.hpp"
#include "core/yaml_io.hpp"

// Same bytes whether or not a compiler would fuse a * b + c (see core/rng.cpp).
#ifdef __clang__
#pragma STDC FP_CONTRACT OFF
#endif

namespace driftlab::sim {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// JONSWAP discretisation range, as multiples of the peak frequency. Below 0.5
// the spectrum holds ~exp(-20) of the energy; above 4 about 0.5 % (the f^-5
// tail), which the Hs normalisation gives back to the retained components.
constexpr double kJonswapLowCut = 0.5;
constexpr double kJonswapHighCut = 4.0;

// exp(-x) < eps / 2 for x > ~37.4, so 1 +- exp(-x) rounds to exactly 1: the
// depth terms can skip their expm1 there and give the same bytes.
constexpr double kNegligibleExponent = 40.0;

double deg_to_rad(double deg) { return deg * (std::numbers::pi / 180.0); }

// ---------------------------------------------------------------------------
// Calm water: flat and still, answers without work.

class CalmField final : public WaveField {
 public:
  double elevation(double, double, double) const override { return 0.0; }
  Vec2 slope(double, double, double) const override { return Vec2::Zero(); }
  Vec3 velocity(const Vec3&, double) const override { return Vec3::Zero(); }
  Vec3 acceleration(const Vec3&, double) const override { return Vec3::Zero(); }
  double dynamic_pressure(const Vec3&, double) const override { return 0.0; }
  bool is_calm() const override { return true; }
};

// ---------------------------------------------------------------------------
// Sum of regular components (airy, components and jonswap all use this one).
//
// Per component, with Z = -z (up) and theta = k (x cos d + y sin d) - omega t + phi,
// linear theory gives ([DD] Ch. 3-4; [DNV] Table 3-1):
//   eta   = a cos(theta)
//   u_h   = a omega cosh(k(Z+h)) / sinh(kh) cos(theta)       (along d)
//   w_up  = a omega sinh(k(Z+h)) / sinh(kh) sin(theta)
//   du_h/dt  = a omega^2 cosh(k(Z+h)) / sinh(kh) sin(theta)
//   dw_up/dt = -a omega^2 sinh(k(Z+h)) / sinh(kh) cos(theta)
//   p_dyn = rho g a cosh(k(Z+h)) / cosh(kh) cos(theta)
// Accelerations are the local dd/dt: the convective terms are second order in
// the wave steepness and linear theory drops them.
//
// The hyperbolic ratios overflow for kh > ~710 (short waves in deep water), so
// they are evaluated as (with E = exp(kZ) <= 1 and q = exp(-2k(Z+h)) <= 1):
//   cosh(k(Z+h)) / cosh(kh) = E (1 + q) / (1 + exp(-2kh))
//   cosh(k(Z+h)) / sinh(kh) = E (1 + q) / (1 - exp(-2kh))
//   sinh(k(Z+h)) / sinh(kh) = E (1 - q) / (1 - exp(-2kh))
// which tend to exp(kZ) in deep water; 1 - q comes from expm1 so that shallow
// water (k(Z+h) -> 0) keeps its precision.
//
// Vertical range: above still water (Z > 0, inside a crest) the values at
// Z = 0 are used (constant extrapolation): the linear potential is only
// defined up to Z = 0, exp(kZ) would grow without bound for short waves, and
// it makes rho g z + p_dyn vanish at a crest to first order. Below the bottom
// (Z < -h) is outside the fluid; the values at the bottom are used (clamp) so
// that a grounded hull panel still gets finite, continuous loads. Detecting
// grounding is the vessel model's job, not the water's.
class LinearWaveField final : public WaveField {
 public:
  LinearWaveField(std::vector<WaveComponent> components, double depth_m)
      : components_(std::move(components)), depth_m_(depth_m) {
    DRIFTLAB_DEMAND_MSG(std::isfinite(depth_m_) && depth_m_ > 0.0,
                        "wave field needs a finite water depth > 0");
    for (const WaveComponent& c : components_) {
      DRIFTLAB_DEMAND_MSG(std::isfinite(c.amplitude_m) && c.amplitude_m >= 0.0 &&
                              std::isfinite(c.wavenumber_rad_m) && c.wavenumber_rad_m > 0.0 &&
                              std::isfinite(c.omega_rad_s) && std::isfinite(c.direction_rad) &&
                              std::isfinite(c.phase_rad),
                          "wave component with a non-finite or out-of-range value");
      // Zero-amplitude components add exactly nothing: skip them in the sums.
      if (c.amplitude_m == 0.0) continue;
      const double k = c.wavenumber_rad_m;
      const double w = c.omega_rad_s;
      const double two_kh = 2.0 * k * depth_m_;
      const double one_plus_r = 1.0 + std::exp(-two_kh);  // 2 cosh(kh) exp(-kh)
      const double one_minus_r = -std::expm1(-two_kh);    // 2 sinh(kh) exp(-kh)
      Term t;
      t.kx = k * std::cos(c.direction_rad);
      t.ky = k * std::sin(c.direction_rad);
      t.omega = w;
      t.phase = c.phase_rad;
      t.k = k;
      t.cos_d = std::cos(c.direction_rad);
      t.sin_d = std::sin(c.direction_rad);
      t.a = c.amplitude_m;
      t.p_coef = kWaterDensity_kg_m3 * kGravity_m_s2 * c.amplitude_m / one_plus_r;
      t.u_coef = c.amplitude_m * w / one_minus_r;
      t.acc_coef = c.amplitude_m * w * w / one_minus_r;
      terms_.push_back(t);
    }
  }

  double elevation(double x_m, double y_m, double t_s) const override {
    double eta = 0.0;
    for (const Term& c : terms_) eta += c.a * std::cos(phase(c, x_m, y_m, t_s));
    return eta;
  }

  Vec2 slope(double x_m, double y_m, double t_s) const override {
    double sx = 0.0;
    double sy = 0.0;
    for (const Term& c : terms_) {
      const double s = c.a * std::sin(phase(c, x_m, y_m, t_s));
      sx -= c.kx * s;
      sy -= c.ky * s;
    }
    return {sx, sy};
  }

  Vec3 velocity(const Vec3& p_ned_m, double t_s) const override {
    DRIFTLAB_ASSERT(p_ned_m.allFinite() && std::isfinite(t_s));
    const double z_up = clamped_z_up(p_ned_m.z());
    double vn = 0.0;
    double ve = 0.0;
    double w_up = 0.0;
    for (const Term& c : terms_) {
      const DepthTerms d = depth_terms(c, z_up);
      const double th = phase(c, p_ned_m.x(), p_ned_m.y(), t_s);
      const double u_h = c.u_coef * d.cosh_part * std::cos(th);
      vn += u_h * c.cos_d;
      ve += u_h * c.sin_d;
      w_up += c.u_coef * d.sinh_part * std::sin(th);
    }
    return {vn, ve, -w_up};  // NED z is down
  }

  Vec3 acceleration(const Vec3& p_ned_m, double t_s) const override {
    DRIFTLAB_ASSERT(p_ned_m.allFinite() && std::isfinite(t_s));
    const double z_up = clamped_z_up(p_ned_m.z());
    double an = 0.0;
    double ae = 0.0;
    double a_up = 0.0;
    for (const Term& c : terms_) {
      const DepthTerms d = depth_terms(c, z_up);
      const double th = phase(c, p_ned_m.x(), p_ned_m.y(), t_s);
      const double a_h = c.acc_coef * d.cosh_part * std::sin(th);
      an += a_h * c.cos_d;
      ae += a_h * c.sin_d;
      a_up -= c.acc_coef * d.sinh_part * std::cos(th);
    }
    return {an, ae, -a_up};
  }

  double dynamic_pressure(const Vec3& p_ned_m, double t_s) const override {
    DRIFTLAB_ASSERT(p_ned_m.allFinite() && std::isfinite(t_s));
    const double z_up = clamped_z_up(p_ned_m.z());
    double p = 0.0;
    for (const Term& c : terms_) {
      const DepthTerms d = depth_terms(c, z_up);
      p += c.p_coef * d.cosh_part * std::cos(phase(c, p_ned_m.x(), p_ned_m.y(), t_s));
    }
    return p;
  }

  bool is_calm() const override { return terms_.empty(); }
  std::span<const WaveComponent> components() const override { return components_; }

 private:
  // Everything about one component that does not depend on the query point.
  struct Term {
    double kx, ky;  // k cos d, k sin d [rad/m]
    double omega;   // [rad/s]
    double phase;   // [rad]
    double k;       // [rad/m]
    double cos_d, sin_d;
    double a;         // amplitude [m]
    double p_coef;    // rho g a / (1 + exp(-2kh))
    double u_coef;    // a omega / (1 - exp(-2kh))
    double acc_coef;  // a omega^2 / (1 - exp(-2kh))
  };
  // E (1 + q) and E (1 - q) of the class comment.
  struct DepthTerms {
    double cosh_part;
    double sinh_part;
  };

  static double phase(const Term& c, double x_m, double y_m, double t_s) {
    return c.kx * x_m + c.ky * y_m - c.omega * t_s + c.phase;
  }

  // Z = -z clamped to [-h, 0] (see the class comment). NaN stays NaN.
  double clamped_z_up(double z_ned_m) const {
    double z_up = -z_ned_m;
    if (z_up > 0.0) z_up = 0.0;
    if (z_up < -depth_m_) z_up = -depth_m_;
    return z_up;
  }

  DepthTerms depth_terms(const Term& c, double z_up) const {
    const double e = std::exp(c.k * z_up);
    const double x = 2.0 * c.k * (z_up + depth_m_);  // >= 0
    // em = q - 1 in (-1, 0]; beyond kNegligibleExponent it rounds to -1 anyway.
    const double em = x > kNegligibleExponent ? -1.0 : std::expm1(-x);
    return {e * (2.0 + em), e * -em};
  }

  std::vector<WaveComponent> components_;
  std::vector<Term> terms_;
  double depth_m_;
};

// ---------------------------------------------------------------------------
// Building the components.

WaveComponent regular_component(const WaveComponentOptions& o, double depth_m) {
  WaveComponent c;
  c.amplitude_m = o.amplitude_m;
  if (o.period_s > 0.0) {
    c.omega_rad_s = kTwoPi / o.period_s;
    c.wavenumber_rad_m = dispersion_wavenumber(c.omega_rad_s, depth_m);
  } else {
    c.wavenumber_rad_m = kTwoPi / o.wavelength_m;
    c.omega_rad_s = dispersion_omega(c.wavenumber_rad_m, depth_m);
  }
  c.direction_rad = deg_to_rad(o.direction_deg);
  c.phase_rad = deg_to_rad(o.phase_deg);
  return c;
}

// Frequencies of `count` equal-energy bins of the JONSWAP spectrum over
// [kJonswapLowCut, kJonswapHighCut] x omega_p, each at its bin's energy
// midpoint (the frequency below which half the bin's energy lies). Equal-energy
// bins give incommensurate frequencies, so the sea does not repeat itself after
// 2 pi / d_omega as it does with equal spacing, and put the components where
// the energy is.
std::vector<double> equal_energy_frequencies(const WaveOptions& o, int count) {
  const double omega_p = kTwoPi / o.peak_period_s;
  const double lo = kJonswapLowCut * omega_p;
  const double hi = kJonswapHighCut * omega_p;
  // Fine grid for the cumulative energy (trapezoid rule); 16 cells per bin
  // resolve the bins, with a floor for small counts and a cap on memory.
  const int cells = std::clamp(16 * count, 4096, 1 << 20);
  const double d = (hi - lo) / cells;
  std::vector<double> cumulative(static_cast<std::size_t>(cells) + 1, 0.0);
  double s_prev =
      jonswap_spectrum(lo, o.significant_height_m, o.peak_period_s, o.peak_enhancement_gamma);
  for (int g = 1; g <= cells; ++g) {
    const double s = jonswap_spectrum(lo + g * d, o.significant_height_m, o.peak_period_s,
                                      o.peak_enhancement_gamma);
    cumulative[g] = cumulative[g - 1] + 0.5 * (s_prev + s) * d;
    s_prev = s;
  }
  const double total = cumulative.back();
  DRIFTLAB_DEMAND_MSG(total > 0.0 && std::isfinite(total), "JONSWAP spectrum without energy");

  std::vector<double> omegas;
  omegas.reserve(static_cast<std::size_t>(count));
  int g = 0;
  for (int b = 0; b < count; ++b) {
    const double target = (b + 0.5) / count * total;
    while (g < cells - 1 && cumulative[g + 1] < target) ++g;
    // Linear inverse of the cumulative energy within grid cell g.
    const double de = cumulative[g + 1] - cumulative[g];
    const double f = de > 0.0 ? std::clamp((target - cumulative[g]) / de, 0.0, 1.0) : 0.5;
    omegas.push_back(lo + (g + f) * d);
  }
  return omegas;
}

std::vector<WaveComponent> jonswap_components(const WaveOptions& o, double depth_m, Rng& rng) {
  const int n_freq = o.num_frequencies;
  const int n_dir = o.num_directions;
  const double mean_dir = deg_to_rad(o.mean_direction_deg);

  // cos-2s spreading D(theta) ~ cos^(2s)((theta - theta_m) / 2) [LH63], at the
  // midpoints of n_dir equal sectors of +-90 deg about the mean ([DNV] 3.5.8
  // limits spreading to the half plane); weights normalised over the sectors,
  // so the energy the cos-2s tail puts beyond +-90 deg is given to the rest.
  std::vector<double> dir(static_cast<std::size_t>(n_dir));
  std::vector<double> weight(static_cast<std::size_t>(n_dir));
  double weight_sum = 0.0;
  for (int j = 0; j < n_dir; ++j) {
    const double offset = -0.5 * std::numbers::pi + (j + 0.5) * (std::numbers::pi / n_dir);
    dir[j] = mean_dir + offset;
    weight[j] = std::pow(std::cos(0.5 * offset), 2.0 * o.spreading_s);
    weight_sum += weight[j];
  }
  for (double& w : weight) w /= weight_sum;

  // Every component gets a frequency of its own: with one frequency shared by
  // all directions, the components of a frequency interfere into a pattern
  // fixed in space, and the variance at a point depends on the point and on
  // the phases drawn, not on the spectrum alone (a non-ergodic sea, [J87]).
  // So each of the n_freq equal-energy bands is split into n_dir equal-energy
  // sub-bands, and sub-band j of band i carries direction (i + j) mod n_dir
  // (rotating the pairing so no direction keeps the low edge of every band).
  // Amplitude from a = sqrt(2 S(omega) d_omega D(theta) d_theta): the band's
  // energy m0 / n_freq times the direction's weight.
  const std::vector<double> omegas = equal_energy_frequencies(o, n_freq * n_dir);
  const double m0 = o.significant_height_m * o.significant_height_m / 16.0;  // Hs = 4 sqrt(m0)
  std::vector<WaveComponent> out;
  out.reserve(omegas.size());
  for (int i = 0; i < n_freq; ++i) {
    for (int j = 0; j < n_dir; ++j) {
      const int d = (i + j) % n_dir;
      WaveComponent c;
      c.omega_rad_s = omegas[static_cast<std::size_t>(i * n_dir + j)];
      c.wavenumber_rad_m = dispersion_wavenumber(c.omega_rad_s, depth_m);
      c.amplitude_m = std::sqrt(2.0 * m0 / n_freq * weight[d]);
      c.direction_rad = dir[d];
      c.phase_rad = kTwoPi * rng.uniform();
      out.push_back(c);
    }
  }
  // Scale so that the discretised spectrum has 4 sqrt(m0) = Hs to rounding,
  // whatever the rounding of the weights above.
  double m0_discrete = 0.0;
  for (const WaveComponent& c : out) m0_discrete += 0.5 * c.amplitude_m * c.amplitude_m;
  const double scale = o.significant_height_m / (4.0 * std::sqrt(m0_discrete));
  for (WaveComponent& c : out) c.amplitude_m *= scale;
  return out;
}

}  // namespace

// ---------------------------------------------------------------------------

double dispersion_omega(double k_rad_m, double depth_m) {
  DRIFTLAB_DEMAND_MSG(std::isfinite(k_rad_m) && k_rad_m >= 0.0,
                      "dispersion_omega: wavenumber must be finite and >= 0");
  DRIFTLAB_DEMAND_MSG(std::isfinite(depth_m) && depth_m > 0.0,
                      "dispersion_omega: water depth must be finite and > 0");
  // omega^2 = g k tanh(k h) ([DD] Ch. 3; [DNV] 3.2.2).
  return std::sqrt(kGravity_m_s2 * k_rad_m * std::tanh(k_rad_m * depth_m));
}

double dispersion_wavenumber(double omega_rad_s, double depth_m) {
  DRIFTLAB_DEMAND_MSG(std::isfinite(omega_rad_s) && omega_rad_s >= 0.0,
                      "dispersion_wavenumber: angular frequency must be finite and >= 0");
  DRIFTLAB_DEMAND_MSG(std::isfinite(depth_m) && depth_m > 0.0,
                      "dispersion_wavenumber: water depth must be finite and > 0");
  if (omega_rad_s == 0.0) return 0.0;
  // Solve x tanh(x) = y for x = k h, with y = omega^2 h / g.
  const double y = omega_rad_s * omega_rad_s * depth_m / kGravity_m_s2;
  DRIFTLAB_DEMAND_MSG(std::isfinite(y), "dispersion_wavenumber: omega^2 h / g overflows");
  // Explicit start within 1.7 % of the root at any depth [FM90]:
  // L = L0 tanh((k0 h)^(3/4))^(2/3), k0 = omega^2 / g.
  double x = y / std::pow(std::tanh(std::pow(y, 0.75)), 2.0 / 3.0);
  // Newton on f(x) = x tanh(x) - y, f' = tanh(x) + x (1 - tanh^2 x) > 0 for
  // x > 0 (and written without cosh, which overflows in deep water); from the
  // start above it converges quadratically, to a few ulps in 3-4 steps.
  for (int iteration = 0; iteration < 50; ++iteration) {
    const double t = std::tanh(x);
    const double step = (x * t - y) / (t + x * (1.0 - t * t));
    x -= step;
    if (std::abs(step) <= 4.0 * std::numeric_limits<double>::epsilon() * x) break;
  }
  return x / depth_m;
}

double jonswap_spectrum(double omega_rad_s, double hs_m, double tp_s, double gamma) {
  DRIFTLAB_DEMAND_MSG(std::isfinite(hs_m) && hs_m >= 0.0 && std::isfinite(tp_s) && tp_s > 0.0 &&
                          std::isfinite(gamma) && gamma >= 1.0,
                      "jonswap_spectrum: needs hs >= 0, tp > 0, gamma >= 1, all finite");
  if (!(omega_rad_s > 0.0)) return 0.0;
  const double omega_p = kTwoPi / tp_s;
  const double r = omega_rad_s / omega_p;
  const double r4 = r * r * r * r;
  // Pierson-Moskowitz ([DNV] 3.5.5):
  // S_PM = 5/16 Hs^2 omega_p^4 omega^-5 exp(-5/4 (omega / omega_p)^-4).
  const double s_pm = 5.0 / 16.0 * hs_m * hs_m / (omega_p * r4 * r) * std::exp(-1.25 / r4);
  // JONSWAP ([H73]; [DNV] 3.5.5): peak shape sigma = 0.07 below the peak,
  // 0.09 above; A_gamma = 1 - 0.287 ln(gamma) keeps m0 close to Hs^2 / 16.
  const double sigma = omega_rad_s <= omega_p ? 0.07 : 0.09;
  const double u = (omega_rad_s - omega_p) / (sigma * omega_p);
  const double a_gamma = 1.0 - 0.287 * std::log(gamma);
  return a_gamma * s_pm * std::pow(gamma, std::exp(-0.5 * u * u));
}

std::vector<WaveComponent> wave_components(const WaveOptions& options, Rng rng) {
  // Options built in code may have skipped validation; the same rules apply.
  yaml::validate_or_throw(options, "water.waves");
  const double h = options.water_depth_m;
  switch (options.model) {
    case WaveModel::kCalm:
      return {};
    case WaveModel::kAiry:
      return {regular_component(options.airy, h)};
    case WaveModel::kComponents: {
      std::vector<WaveComponent> out;
      out.reserve(options.components.size());
      for (const WaveComponentOptions& c : options.components)
        out.push_back(regular_component(c, h));
      return out;
    }
    case WaveModel::kJonswap:
      return jonswap_components(options, h, rng);
  }
  DRIFTLAB_DEMAND_MSG(false, "unknown wave model");
  return {};
}

double ripple_mean_square_slope(double u_mps) { return 1.56e-3 * std::max(0.0, u_mps); }

std::unique_ptr<WaveField> make_wave_field(const WaveOptions& options, Rng rng) {
  std::vector<WaveComponent> components = wave_components(options, std::move(rng));
  if (options.model == WaveModel::kCalm) return std::make_unique<CalmField>();
  return std::make_unique<LinearWaveField>(std::move(components), options.water_depth_m);
}

Vec3 current_velocity(const CurrentOptions& options, double x_m, double y_m,
                      double channel_half_width_m) {
  const double d = deg_to_rad(options.direction_deg);
  const double cd = std::cos(d);
  const double sd = std::sin(d);
  double speed = options.speed_mps;
  if (options.profile == CurrentProfile::kBankToBank) {
    DRIFTLAB_DEMAND_MSG(std::isfinite(channel_half_width_m) && channel_half_width_m > 0.0,
                        "bank_to_bank current needs a finite channel half width > 0");
    // Signed distance across the channel from the centre line (the line
    // through the origin along the flow), positive to the right of the flow.
    // Parabolic profile, fastest mid-channel and zero at the banks: the
    // laminar (Poiseuille) shape, a simple stand-in for the measured
    // 0-0.24 m/s spread of the river paper (Kriechbaumer et al. 2015, Sec. 2.1).
    const double s = -x_m * sd + y_m * cd;
    const double r = s / channel_half_width_m;
    speed *= std::max(0.0, 1.0 - r * r);
  }
  return {speed * cd, speed * sd, 0.0};
}

}  // namespace driftlab::sim
