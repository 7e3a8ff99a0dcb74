#include "sim/physics/waves/wave_field.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstring>
#include <limits>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "core/yaml_io.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab::sim {
namespace {

using driftlab::test::kPi;
constexpr double kWavesG = kGravity_m_s2;
constexpr double kRho = kWaterDensity_kg_m3;
using driftlab::test::kEps;
// Relative tolerance of values that only rounding separates (tens of
// operations, each within eps / 2).
constexpr double kRoundingTol = 1e3 * kEps;
// Central differences with step kFdStep / k: truncation ~ (kFdStep)^2 / 6 and
// rounding ~ eps / kFdStep, both far below kFdTol relative to the derivative.
constexpr double kFdStep = 1e-5;
constexpr double kFdTol = 1e-6;

Rng phases_rng(std::uint64_t seed) { return RngStreams(seed).stream("waves.phases"); }

// omega^2 = g k tanh(k h) solved for k by plain bisection: slow, but with no
// starting guess or derivative to get wrong.
double bisect_wavenumber(double omega, double depth) {
  double lo = 0.0;
  double hi = 1.0;
  while (kWavesG * hi * std::tanh(hi * depth) < omega * omega) hi *= 2.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (kWavesG * mid * std::tanh(mid * depth) < omega * omega ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

WaveComponentOptions component(double amplitude, double wavelength, double direction_deg,
                               double phase_deg = 0.0) {
  WaveComponentOptions c;
  c.amplitude_m = amplitude;
  c.wavelength_m = wavelength;
  c.direction_deg = direction_deg;
  c.phase_deg = phase_deg;
  return c;
}

WaveOptions airy(double amplitude, double wavelength, double direction_deg, double depth) {
  WaveOptions o;
  o.model = WaveModel::kAiry;
  o.water_depth_m = depth;
  o.airy = component(amplitude, wavelength, direction_deg);
  return o;
}

// Three finite-depth waves from different directions (kh from ~1.8 to ~9.7).
WaveOptions three_components() {
  WaveOptions o;
  o.model = WaveModel::kComponents;
  o.water_depth_m = 2.0;
  o.components = {component(0.05, 3.0, 20.0, 10.0), component(0.10, 7.0, -75.0, 200.0),
                  component(0.02, 1.3, 160.0, -45.0)};
  return o;
}

WaveOptions jonswap(int num_frequencies = 32, int num_directions = 8) {
  WaveOptions o;
  o.model = WaveModel::kJonswap;
  o.water_depth_m = 3.0;
  o.significant_height_m = 0.05;
  o.peak_period_s = 1.5;
  o.peak_enhancement_gamma = 3.3;
  o.mean_direction_deg = 30.0;
  o.spreading_s = 10.0;
  o.num_frequencies = num_frequencies;
  o.num_directions = num_directions;
  return o;
}

std::unique_ptr<WaveField> field_of(const WaveOptions& o, std::uint64_t seed = 1) {
  return make_wave_field(o, phases_rng(seed));
}

// Points under the surface, at several depths, for the kinematics checks.
const std::vector<Vec3> kUnderwaterPoints = {
    {0.3, -1.2, 0.2}, {2.7, 0.4, 0.5}, {-1.9, 3.3, 1.1}, {5.0, 5.0, 1.9}};
constexpr double kT = 1.7;

// ---------------------------------------------------------------------------
// Dispersion relation

TEST(Dispersion, MatchesDeepAndShallowWaterLimits) {
  // Deep water (kh >> 1): omega^2 = g k. Shallow (kh << 1): omega = k sqrt(g h) (1 - (kh)^2 / 6).
  for (const double k : {0.1, 1.0, 30.0}) {
    const double h = 60.0 / k;
    EXPECT_NEAR(dispersion_omega(k, h), std::sqrt(kWavesG * k),
                kRoundingTol * std::sqrt(kWavesG * k));
  }
  for (const double h : {0.1, 1.0, 10.0}) {
    const double k = 1e-4 / h;
    const double shallow = k * std::sqrt(kWavesG * h);
    EXPECT_NEAR(dispersion_omega(k, h), shallow, 1e-8 * shallow);
  }
  EXPECT_EQ(dispersion_omega(0.0, 1.0), 0.0);
  EXPECT_EQ(dispersion_wavenumber(0.0, 1.0), 0.0);
}

TEST(Dispersion, WavenumberMatchesBisectionAndTheTable) {
  // h = 1 m, T = 2 s: deep-water theory says 6.24 m, shallow-water theory
  // 6.26 m; at kh ~ 1.2 neither holds and the wave is ~5.2 m long.
  const double omega = 2.0 * kPi / 2.0;
  const double k = dispersion_wavenumber(omega, 1.0);
  EXPECT_NEAR(k, bisect_wavenumber(omega, 1.0), 1e-13 * k);
  EXPECT_NEAR(2.0 * kPi / k, 5.22, 0.01);
  // Tabulated linear-wave value (tables of h / L against h / L0, e.g. Dean &
  // Dalrymple's appendix): h / L0 = 0.1 gives h / L = 0.1410, with
  // L0 = g T^2 / (2 pi) the deep-water wavelength.
  const double h = 3.0;
  const double period = std::sqrt(2.0 * kPi * h / (0.1 * kWavesG));
  const double wavelength = 2.0 * kPi / dispersion_wavenumber(2.0 * kPi / period, h);
  EXPECT_NEAR(h / wavelength, 0.1410, 5e-5);
}

TEST(Dispersion, WavenumberInvertsOmegaAtEveryDepth) {
  for (double kh = 1e-6; kh < 2e4; kh *= 3.7) {
    const double h = 2.0;
    const double k = kh / h;
    const double omega = dispersion_omega(k, h);
    EXPECT_NEAR(dispersion_wavenumber(omega, h), k, 16 * kEps * k) << "kh = " << kh;
    EXPECT_NEAR(dispersion_wavenumber(omega, h), bisect_wavenumber(omega, h), 1e-12 * k);
  }
}

TEST(Dispersion, RejectsImpossibleArguments) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(dispersion_omega(1.0, 0.0), InternalError);
  EXPECT_THROW(dispersion_omega(1.0, -1.0), InternalError);
  EXPECT_THROW(dispersion_omega(nan, 1.0), InternalError);
  EXPECT_THROW(dispersion_omega(-1.0, 1.0), InternalError);
  EXPECT_THROW(dispersion_wavenumber(1.0, 0.0), InternalError);
  EXPECT_THROW(dispersion_wavenumber(1.0, nan), InternalError);
  EXPECT_THROW(dispersion_wavenumber(-1.0, 1.0), InternalError);
  try {
    dispersion_wavenumber(1.0, 0.0);
  } catch (const InternalError& e) {
    EXPECT_NE(std::string(e.what()).find("water depth must be finite and > 0"), std::string::npos)
        << e.what();
  }
}

// ---------------------------------------------------------------------------
// Regular waves and sums of them: kinematics against their defining equations

TEST(LinearWaves, SlopeIsTheGradientOfElevation) {
  const auto field = field_of(three_components());
  const double step = kFdStep * 1.3 / (2.0 * kPi);  // relative to the shortest wave
  for (const Vec3& p : kUnderwaterPoints) {
    const Vec2 s = field->slope(p.x(), p.y(), kT);
    const double dx =
        (field->elevation(p.x() + step, p.y(), kT) - field->elevation(p.x() - step, p.y(), kT)) /
        (2 * step);
    const double dy =
        (field->elevation(p.x(), p.y() + step, kT) - field->elevation(p.x(), p.y() - step, kT)) /
        (2 * step);
    // Scale: the largest slope a component can have, k a.
    const double scale = 2.0 * kPi / 7.0 * 0.10;
    EXPECT_NEAR(s.x(), dx, kFdTol * scale);
    EXPECT_NEAR(s.y(), dy, kFdTol * scale);
  }
}

TEST(LinearWaves, VelocityIsDivergenceFree) {
  // Incompressible flow: du/dx + dv/dy + dw/dz = 0 (the Laplace equation of
  // the potential). Holds in NED as in z-up coordinates.
  const auto field = field_of(three_components());
  const double step = kFdStep * 1.3 / (2.0 * kPi);
  for (const Vec3& p : kUnderwaterPoints) {
    auto v = [&](const Vec3& dp) { return field->velocity(p + dp, kT); };
    const double div = (v({step, 0, 0}).x() - v({-step, 0, 0}).x()) / (2 * step) +
                       (v({0, step, 0}).y() - v({0, -step, 0}).y()) / (2 * step) +
                       (v({0, 0, step}).z() - v({0, 0, -step}).z()) / (2 * step);
    // Scale: each term is up to k^2 a g / omega ~ omega a k / tanh(kh).
    double scale = 0.0;
    for (const WaveComponent& c : field->components())
      scale +=
          c.omega_rad_s * c.amplitude_m * c.wavenumber_rad_m / std::tanh(c.wavenumber_rad_m * 2.0);
    EXPECT_NEAR(div, 0.0, kFdTol * scale) << p.transpose();
    // The terms themselves are not small: the test has teeth.
    const double dw_dz = (v({0, 0, step}).z() - v({0, 0, -step}).z()) / (2 * step);
    EXPECT_GT(std::abs(dw_dz), 1e3 * kFdTol * scale) << p.transpose();
  }
}

TEST(LinearWaves, AccelerationIsTheTimeDerivativeOfVelocity) {
  const auto field = field_of(three_components());
  const double dt = kFdStep / (2.0 * kPi / 0.9);  // relative to the shortest period (~0.9 s)
  for (const Vec3& p : kUnderwaterPoints) {
    const Vec3 fd = (field->velocity(p, kT + dt) - field->velocity(p, kT - dt)) / (2 * dt);
    const Vec3 a = field->acceleration(p, kT);
    double scale = 0.0;
    for (const WaveComponent& c : field->components())
      scale += c.omega_rad_s * c.omega_rad_s * c.amplitude_m / std::tanh(c.wavenumber_rad_m * 2.0);
    EXPECT_LT((a - fd).norm(), kFdTol * scale) << p.transpose();
    EXPECT_GT(a.norm(), 1e-2 * scale);
  }
}

TEST(LinearWaves, SurfaceMovesWithTheWater) {
  // Linearised kinematic surface condition: w_up(z = 0) = d eta / dt; NED vz = -w_up.
  const auto field = field_of(three_components());
  const double dt = kFdStep / (2.0 * kPi / 0.9);
  for (const Vec3& p : kUnderwaterPoints) {
    const double deta_dt =
        (field->elevation(p.x(), p.y(), kT + dt) - field->elevation(p.x(), p.y(), kT - dt)) /
        (2 * dt);
    const Vec3 v = field->velocity({p.x(), p.y(), 0.0}, kT);
    EXPECT_NEAR(-v.z(), deta_dt, kFdTol * 1.0);
  }
}

TEST(LinearWaves, DynamicPressureAtStillWaterIsRhoGEta) {
  const auto field = field_of(three_components());
  for (const Vec3& p : kUnderwaterPoints) {
    const double eta = field->elevation(p.x(), p.y(), kT);
    EXPECT_NEAR(field->dynamic_pressure({p.x(), p.y(), 0.0}, kT), kRho * kWavesG * eta,
                kRoundingTol * kRho * kWavesG * 0.17);
  }
}

TEST(LinearWaves, TotalPressureVanishesAtACrest) {
  // At the surface z = -eta of a crest (above still water) the total pressure
  // rho g z + p_dyn is zero to first order: p_dyn takes its still-water value.
  const auto field = field_of(airy(0.05, 3.0, 0.0, 2.0));
  const double eta = field->elevation(0.0, 0.0, 0.0);
  ASSERT_DOUBLE_EQ(eta, 0.05);
  const Vec3 surface{0.0, 0.0, -eta};
  EXPECT_NEAR(kRho * kWavesG * surface.z() + field->dynamic_pressure(surface, 0.0), 0.0,
              kRoundingTol * kRho * kWavesG * eta);
  // Further up, still the still-water value (no growth above z = 0).
  EXPECT_EQ(field->dynamic_pressure({0.0, 0.0, -1.0}, 0.0),
            field->dynamic_pressure({0.0, 0.0, 0.0}, 0.0));
  EXPECT_EQ(field->velocity({0.0, 0.0, -1.0}, 0.3), field->velocity({0.0, 0.0, 0.0}, 0.3));
}

TEST(LinearWaves, DeepWaterMotionDecaysAsExpOfMinusKDepth) {
  // Basin wave of experiment 2: lambda = 0.21 m in 0.6 m of water, kh ~ 18.
  const auto field = field_of(airy(0.005, 0.21, 0.0, 0.6));
  const double k = 2.0 * kPi / 0.21;
  const double u0 = field->velocity({0.0, 0.0, 0.0}, 0.0).x();  // theta = 0: all horizontal
  const double omega = std::sqrt(kWavesG * k);
  EXPECT_NEAR(u0, omega * 0.005, 1e-12 * u0);    // deep water: u = a omega at the surface
  const double t_quarter = (kPi / 2.0) / omega;  // theta = -pi/2: all vertical
  const double w0 = field->velocity({0.0, 0.0, 0.0}, t_quarter).z();
  for (const double depth : {0.01, 0.05, 0.1, 0.2}) {
    const double decay = std::exp(-k * depth);
    EXPECT_NEAR(field->velocity({0.0, 0.0, depth}, 0.0).x(), u0 * decay, 1e-9 * u0) << depth;
    EXPECT_NEAR(field->velocity({0.0, 0.0, depth}, t_quarter).z(), w0 * decay, 1e-9 * u0);
  }
}

TEST(LinearWaves, ShallowWaterMotionMatchesTheLongWaveLimit) {
  // kh -> 0: u = eta sqrt(g / h), uniform over depth; w falls linearly to 0 at the bottom.
  const double h = 1.0;
  const auto field = field_of(airy(0.01, 1000.0, 0.0, h));  // kh = 0.0063
  const double eta = field->elevation(0.0, 0.0, 0.0);
  for (const double z : {0.0, 0.5, 1.0})
    EXPECT_NEAR(field->velocity({0.0, 0.0, z}, 0.0).x(), eta * std::sqrt(kWavesG / h),
                1e-4 * eta * std::sqrt(kWavesG / h));
  const double omega = field->components()[0].omega_rad_s;
  const double tq = (kPi / 2.0) / omega;
  const double w_surface = field->velocity({0.0, 0.0, 0.0}, tq).z();
  EXPECT_NEAR(field->velocity({0.0, 0.0, 0.25 * h}, tq).z(), 0.75 * w_surface,
              1e-4 * std::abs(w_surface));
}

TEST(LinearWaves, NoFlowThroughTheBottomAndBottomValuesBelowIt) {
  const auto field = field_of(three_components());
  for (const Vec3& p : kUnderwaterPoints) {
    const Vec3 at_bottom{p.x(), p.y(), 2.0};
    EXPECT_EQ(field->velocity(at_bottom, kT).z(), 0.0);
    EXPECT_EQ(field->acceleration(at_bottom, kT).z(), 0.0);
    EXPECT_EQ(field->velocity({p.x(), p.y(), 3.5}, kT), field->velocity(at_bottom, kT));
    EXPECT_EQ(field->dynamic_pressure({p.x(), p.y(), 3.5}, kT),
              field->dynamic_pressure(at_bottom, kT));
  }
}

TEST(LinearWaves, ShortWavesInDeepWaterStayFinite) {
  // kh = 6e5: cosh(kh) and sinh(kh) overflow; the field must not.
  const auto field = field_of(airy(0.0001, 0.001, 10.0, 100.0));
  const double k = 2.0 * kPi / 0.001;
  for (const double z : {0.0, 0.0003, 0.01, 50.0, 100.0, 150.0}) {
    const Vec3 v = field->velocity({0.0, 0.0, z}, 0.0);
    const Vec3 a = field->acceleration({0.0, 0.0, z}, 0.0);
    const double p = field->dynamic_pressure({0.0, 0.0, z}, 0.0);
    ASSERT_TRUE(v.allFinite() && a.allFinite() && std::isfinite(p)) << z;
    EXPECT_NEAR(p, kRho * kWavesG * 0.0001 * std::exp(-k * z), 1e-12 * kRho * kWavesG * 0.0001)
        << z;
  }
}

TEST(LinearWaves, PeriodSetsTheWaveThroughTheDispersionRelation) {
  WaveOptions o = airy(0.1, 0.21, 45.0, 1.0);
  o.airy.period_s = 2.0;  // wavelength_m is then not used
  const auto field = field_of(o);
  const double k = bisect_wavenumber(kPi, 1.0);
  EXPECT_NEAR(field->components()[0].wavenumber_rad_m, k, 1e-12 * k);
  EXPECT_DOUBLE_EQ(field->components()[0].omega_rad_s, kPi);
  for (const Vec3& p : kUnderwaterPoints)
    EXPECT_NEAR(field->elevation(p.x(), p.y(), kT + 2.0), field->elevation(p.x(), p.y(), kT),
                1e-12);
}

TEST(LinearWaves, DirectionIsWhereTheCrestsTravelClockwiseFromNorth) {
  // Towards 90 deg: crests run north-south and move east.
  const double lambda = 2.0;
  const auto field = field_of(airy(0.1, lambda, 90.0, 5.0));
  const double omega = field->components()[0].omega_rad_s;
  const double quarter_period = 0.5 * kPi / omega;
  EXPECT_DOUBLE_EQ(field->elevation(0.0, 0.0, 0.0), 0.1);  // crest at the origin at t = 0
  EXPECT_NEAR(field->elevation(0.0, lambda / 4, quarter_period), 0.1, 1e-12);
  EXPECT_NEAR(field->elevation(0.0, -lambda / 4, quarter_period), -0.1, 1e-12);
  EXPECT_NEAR(field->elevation(7.3, 0.4, 0.9), field->elevation(-2.0, 0.4, 0.9), 1e-12);
  // The water under a crest moves with it (east), under a trough against it.
  EXPECT_GT(field->velocity({0.0, 0.0, 0.1}, 0.0).y(), 0.0);
  EXPECT_NEAR(field->velocity({0.0, 0.0, 0.1}, 0.0).x(), 0.0, 1e-15);
  EXPECT_LT(field->velocity({0.0, lambda / 2, 0.1}, 0.0).y(), 0.0);
}

TEST(LinearWaves, ZeroAmplitudeIsCalm) {
  const auto field = field_of(airy(0.0, 0.21, 0.0, 0.6));
  EXPECT_TRUE(field->is_calm());
  EXPECT_EQ(field->elevation(1.0, 2.0, 3.0), 0.0);
  EXPECT_FALSE(field_of(airy(0.001, 0.21, 0.0, 0.6))->is_calm());
}

// ---------------------------------------------------------------------------
// The ship-model basin experiments (Kucic and Valcic 2020, Table 1)

struct BasinExperiment {
  double gamma_deg;
  double zeta_a_mm;
  double lambda_mm;
};

TEST(BasinExperiments, AreExpressibleExactly) {
  const BasinExperiment table[] = {{40, 5, 210}, {40, 7.5, 132}, {40, 11, 59},
                                   {0, 5, 210},  {0, 7.5, 132},  {0, 11, 59}};
  for (const BasinExperiment& e : table) {
    SCOPED_TRACE(std::to_string(e.gamma_deg) + " deg, " + std::to_string(e.zeta_a_mm) + " mm, " +
                 std::to_string(e.lambda_mm) + " mm");
    // As the scenarios write them: gamma is counter-clockwise from the towing
    // direction (north), so the wave travels towards -gamma.
    const std::string text = "model: airy\nwater_depth_m: 0.6\nairy:\n  amplitude_m: " +
                             yaml::format_double(e.zeta_a_mm / 1000) +
                             "\n  wavelength_m: " + yaml::format_double(e.lambda_mm / 1000) +
                             "\n  direction_deg: " + yaml::format_double(-e.gamma_deg) + "\n";
    WaveOptions o;
    yaml::read_into(yaml::load_string(text, "basin.yaml"), yaml::Source{"basin.yaml"}, &o);
    const auto field = field_of(o);
    const double a = e.zeta_a_mm / 1000;
    const double lambda = e.lambda_mm / 1000;
    ASSERT_EQ(field->components().size(), 1u);
    EXPECT_EQ(field->components()[0].amplitude_m, a);
    EXPECT_DOUBLE_EQ(2.0 * kPi / field->components()[0].wavenumber_rad_m, lambda);

    // Elevation over one period at an arbitrary point: extremes +-zeta_a.
    const double period = 2.0 * kPi / field->components()[0].omega_rad_s;
    double hi = -1.0;
    double lo = 1.0;
    for (int i = 0; i < 4000; ++i) {
      const double eta = field->elevation(0.123, -0.045, period * i / 4000.0);
      hi = std::max(hi, eta);
      lo = std::min(lo, eta);
    }
    EXPECT_NEAR(hi, a, 1e-6 * a);
    EXPECT_NEAR(lo, -a, 1e-6 * a);
    EXPECT_LE(hi, a * (1 + kRoundingTol));

    // Spatial period lambda along the direction of travel, none across it.
    const double d = -e.gamma_deg * kPi / 180.0;
    const Vec2 along{std::cos(d), std::sin(d)};
    const Vec2 across{-std::sin(d), std::cos(d)};
    for (const Vec3& p : kUnderwaterPoints) {
      const Vec2 q = p.head<2>();
      const double eta = field->elevation(q.x(), q.y(), kT);
      const Vec2 full = q + lambda * along;
      const Vec2 half = q + 0.5 * lambda * along;
      const Vec2 side = q + 0.77 * across;
      EXPECT_NEAR(field->elevation(full.x(), full.y(), kT), eta, 1e-12);
      EXPECT_NEAR(field->elevation(half.x(), half.y(), kT), -eta, 1e-12);
      EXPECT_NEAR(field->elevation(side.x(), side.y(), kT), eta, 1e-12);
    }
    // The crest at the origin at t = 0 has moved along `along` a little later.
    const double dt = 0.01 * period;
    const double c = field->components()[0].omega_rad_s / field->components()[0].wavenumber_rad_m;
    const Vec2 moved = c * dt * along;
    EXPECT_NEAR(field->elevation(moved.x(), moved.y(), dt), a, 1e-12);
  }
}

TEST(BasinExperiments, StillWaterIsCalm) {
  WaveOptions o;
  yaml::read_into(yaml::load_string("model: calm\nwater_depth_m: 0.6\n", "basin.yaml"),
                  yaml::Source{"basin.yaml"}, &o);
  const auto field = field_of(o);
  EXPECT_TRUE(field->is_calm());
  EXPECT_TRUE(field->components().empty());
  const Vec3 p{1.0, 2.0, 0.1};
  EXPECT_EQ(field->elevation(1.0, 2.0, 3.0), 0.0);
  EXPECT_EQ(field->slope(1.0, 2.0, 3.0), Vec2::Zero());
  EXPECT_EQ(field->velocity(p, 3.0), Vec3::Zero());
  EXPECT_EQ(field->acceleration(p, 3.0), Vec3::Zero());
  EXPECT_EQ(field->dynamic_pressure(p, 3.0), 0.0);
}

// ---------------------------------------------------------------------------
// JONSWAP sea

TEST(Jonswap, SpectrumIsPiersonMoskowitzForGammaOneAndHoldsHsSquaredOver16) {
  const double hs = 2.0;
  const double tp = 8.0;
  const double fp = 1.0 / tp;
  // Pierson-Moskowitz in frequency f [Hz] (DNV-RP-C205 Sec. 3.5.5 in Hz form),
  // S(omega) = S(f) / (2 pi).
  auto pm_hz = [&](double f) {
    return 5.0 / 16.0 * hs * hs * std::pow(fp, 4) * std::pow(f, -5) *
           std::exp(-1.25 * std::pow(f / fp, -4));
  };
  for (const double f : {0.05, 0.1, 0.125, 0.2, 0.5})
    EXPECT_NEAR(jonswap_spectrum(2 * kPi * f, hs, tp, 1.0), pm_hz(f) / (2 * kPi),
                1e-12 * pm_hz(fp));
  // m0 = Hs^2 / 16: exact for Pierson-Moskowitz, within a few percent through
  // A_gamma for gamma in [1, 7] (DNV-RP-C205 Sec. 3.5.5).
  for (const double gamma : {1.0, 3.3, 7.0}) {
    double m0 = 0.0;
    const double d = 1e-4;
    for (double w = d / 2; w < 20.0; w += d) m0 += jonswap_spectrum(w, hs, tp, gamma) * d;
    EXPECT_NEAR(m0, hs * hs / 16, (gamma == 1.0 ? 1e-4 : 0.03) * hs * hs / 16) << gamma;
  }
  const double wp = 2 * kPi / tp;
  EXPECT_GT(jonswap_spectrum(wp, hs, tp, 3.3), jonswap_spectrum(wp * 0.99, hs, tp, 3.3));
  EXPECT_GT(jonswap_spectrum(wp, hs, tp, 3.3), jonswap_spectrum(wp * 1.01, hs, tp, 3.3));
  EXPECT_EQ(jonswap_spectrum(0.0, hs, tp, 3.3), 0.0);
}

TEST(Jonswap, DiscretisedSeaHasTheSignificantHeightExactly) {
  for (const auto& [nf, nd] : {std::pair{32, 8}, std::pair{1, 1}, std::pair{7, 3}}) {
    const auto components = wave_components(jonswap(nf, nd), phases_rng(3));
    ASSERT_EQ(components.size(), static_cast<std::size_t>(nf * nd));
    double m0 = 0.0;
    for (const WaveComponent& c : components) m0 += 0.5 * c.amplitude_m * c.amplitude_m;
    EXPECT_NEAR(4.0 * std::sqrt(m0), 0.05, kRoundingTol * 0.05) << nf << " x " << nd;
  }
}

TEST(Jonswap, ComponentsHaveDistinctFrequenciesWhereTheSpectrumHasEnergy) {
  const WaveOptions o = jonswap();
  const auto components = wave_components(o, phases_rng(3));
  const double wp = 2 * kPi / o.peak_period_s;
  std::vector<double> omegas;
  for (const WaveComponent& c : components) {
    omegas.push_back(c.omega_rad_s);
    EXPECT_GE(c.omega_rad_s, 0.5 * wp);
    EXPECT_LE(c.omega_rad_s, 4.0 * wp);
    EXPECT_NEAR(c.wavenumber_rad_m, bisect_wavenumber(c.omega_rad_s, o.water_depth_m),
                1e-12 * c.wavenumber_rad_m);
    EXPECT_GE(c.phase_rad, 0.0);
    EXPECT_LT(c.phase_rad, 2 * kPi);
  }
  std::sort(omegas.begin(), omegas.end());
  EXPECT_EQ(std::adjacent_find(omegas.begin(), omegas.end()), omegas.end());
}

TEST(Jonswap, SpreadingRecoversTheMeanDirectionAndCos2sWeights) {
  const WaveOptions o = jonswap(16, 9);
  const auto components = wave_components(o, phases_rng(3));
  std::map<double, double> energy_by_direction;
  double sx = 0.0;
  double sy = 0.0;
  double total = 0.0;
  for (const WaveComponent& c : components) {
    const double e = c.amplitude_m * c.amplitude_m;
    energy_by_direction[c.direction_rad] += e;
    sx += e * std::cos(c.direction_rad);
    sy += e * std::sin(c.direction_rad);
    total += e;
  }
  const double mean = o.mean_direction_deg * kPi / 180.0;
  EXPECT_NEAR(std::atan2(sy, sx), mean, 1e-12);
  ASSERT_EQ(energy_by_direction.size(), 9u);
  // Energy share of each direction ~ cos^(2s)((theta - mean) / 2), normalised
  // over the directions, all within +-90 deg of the mean.
  double norm = 0.0;
  for (const auto& [dir, e] : energy_by_direction)
    norm += std::pow(std::cos((dir - mean) / 2), 2 * o.spreading_s);
  for (const auto& [dir, e] : energy_by_direction) {
    EXPECT_LT(std::abs(dir - mean), kPi / 2);
    EXPECT_NEAR(e / total, std::pow(std::cos((dir - mean) / 2), 2 * o.spreading_s) / norm, 1e-12);
  }
}

// Elevation record at one point: dt = Tp / 10 keeps the 4 fp cut-off below Nyquist (5 fp).
std::vector<double> elevation_record(const WaveField& field, double tp, int periods) {
  std::vector<double> eta;
  const int n = periods * 10;
  eta.reserve(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) eta.push_back(field.elevation(3.0, -2.0, i * tp / 10));
  return eta;
}

TEST(Jonswap, RecordAtOnePointHasTheSignificantHeight) {
  // Hs = 4 sigma of the surface elevation (m0 = sigma^2) over a long record.
  const WaveOptions o = jonswap();
  for (const std::uint64_t seed : {1u, 2u, 3u}) {
    const auto field = field_of(o, seed);
    const std::vector<double> eta = elevation_record(*field, o.peak_period_s, 1000);
    double mean = 0.0;
    for (const double e : eta) mean += e;
    mean /= eta.size();
    double var = 0.0;
    for (const double e : eta) var += (e - mean) * (e - mean);
    var /= eta.size();
    EXPECT_NEAR(4.0 * std::sqrt(var), o.significant_height_m, 0.05 * o.significant_height_m)
        << "seed " << seed;
  }
}

TEST(Jonswap, RecordSpectrumPeaksAtThePeakFrequency) {
  const WaveOptions o = jonswap();
  const auto field = field_of(o, 5);
  const int periods = 1000;
  const std::vector<double> eta = elevation_record(*field, o.peak_period_s, periods);
  const int n = static_cast<int>(eta.size());
  const double duration = periods * o.peak_period_s;
  const double fp = 1.0 / o.peak_period_s;
  // Periodogram on the natural frequencies m / duration, summed into bands of
  // 0.05 fp; the band with the most power is the spectral peak.
  std::vector<std::complex<double>> twiddle(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) twiddle[i] = std::polar(1.0, -2 * kPi * i / n);
  const double band = 0.05 * fp;
  std::vector<double> power(static_cast<std::size_t>(5.0 * fp / band) + 1, 0.0);
  for (int m = 1; m < n / 2; ++m) {
    std::complex<double> x = 0.0;
    for (int i = 0; i < n; ++i)
      x += eta[i] * twiddle[static_cast<std::size_t>((static_cast<long long>(m) * i) % n)];
    power[static_cast<std::size_t>((m / duration) / band)] += std::norm(x);
  }
  const auto peak = std::max_element(power.begin(), power.end()) - power.begin();
  const double f_peak = (peak + 0.5) * band;
  EXPECT_NEAR(f_peak, fp, 0.1 * fp);
  // And hardly any power outside the discretised range [0.5, 4] fp.
  double inside = 0.0;
  double all = 0.0;
  for (std::size_t b = 0; b < power.size(); ++b) {
    all += power[b];
    if ((b + 1) * band > 0.5 * fp && b * band < 4.0 * fp) inside += power[b];
  }
  EXPECT_GT(inside / all, 0.99);
}

TEST(Jonswap, SameSeedSameBytesOtherSeedOtherSea) {
  const WaveOptions o = jonswap();
  auto sample = [&](std::uint64_t seed) {
    const auto field = field_of(o, seed);
    std::vector<double> out;
    for (const Vec3& p : kUnderwaterPoints) {
      out.push_back(field->elevation(p.x(), p.y(), kT));
      const Vec2 s = field->slope(p.x(), p.y(), kT);
      const Vec3 v = field->velocity(p, kT);
      const Vec3 a = field->acceleration(p, kT);
      out.insert(out.end(), {s.x(), s.y(), v.x(), v.y(), v.z(), a.x(), a.y(), a.z(),
                             field->dynamic_pressure(p, kT)});
    }
    for (const WaveComponent& c : field->components())
      out.insert(out.end(),
                 {c.amplitude_m, c.wavenumber_rad_m, c.omega_rad_s, c.direction_rad, c.phase_rad});
    return out;
  };
  const std::vector<double> first = sample(42);
  const std::vector<double> again = sample(42);
  ASSERT_EQ(first.size(), again.size());
  EXPECT_EQ(std::memcmp(first.data(), again.data(), first.size() * sizeof(double)), 0);
  const std::vector<double> other = sample(43);
  EXPECT_NE(std::memcmp(first.data(), other.data(), first.size() * sizeof(double)), 0);
  EXPECT_NE(first[0], other[0]);
}

// ---------------------------------------------------------------------------
// Bad input

TEST(WaveOptionsErrors, ValidateNamesZeroWavelengthBadDepthAndNaN) {
  WaveOptions o = airy(0.005, 0.0, 0.0, 0.6);
  EXPECT_NE(yaml::validate(o).find("airy.wavelength_m: got 0, expected a value in (0, 2000] "
                                   "(longer than any wind wave or swell)"),
            std::string::npos)
      << yaml::validate(o);
  o = airy(0.005, 0.21, 0.0, 0.0);
  EXPECT_NE(
      yaml::validate(o).find(
          "water_depth_m: got 0, expected a value in (0, 11000] (deeper than the deepest ocean)"),
      std::string::npos);
  o = airy(0.005, 0.21, 0.0, -1.0);
  EXPECT_NE(
      yaml::validate(o).find(
          "water_depth_m: got -1, expected a value in (0, 11000] (deeper than the deepest ocean)"),
      std::string::npos);
  o = airy(std::numeric_limits<double>::quiet_NaN(), 0.21, 0.0, 0.6);
  EXPECT_NE(yaml::validate(o).find("airy.amplitude_m: got nan, expected a finite number"),
            std::string::npos);
  o = airy(0.005, 0.21, 0.0, 0.6);
  o.airy.period_s = -2.0;
  EXPECT_NE(yaml::validate(o).find(
                "airy.period_s: got -2, expected a value in [0, 60] (longer than any swell)"),
            std::string::npos);
  EXPECT_EQ(yaml::validate(airy(0.005, 0.21, 0.0, 0.6)), "");
  EXPECT_EQ(yaml::validate(jonswap()), "");
  EXPECT_EQ(yaml::validate(three_components()), "");
}

TEST(WaveOptionsErrors, YamlWithZeroWavelengthOrNaNFailsWithFileAndLine) {
  auto error_of = [](const std::string& text) {
    WaveOptions o;
    try {
      yaml::read_into(yaml::load_string(text, "w.yaml"), yaml::Source{"w.yaml"}, &o);
    } catch (const UserError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error_of("model: airy\nairy:\n  wavelength_m: 0\n")
                .find("w.yaml:3:17: airy.wavelength_m: got 0, expected a value in (0, 2000] "
                      "(longer than any wind wave or swell)"),
            std::string::npos)
      << error_of("model: airy\nairy:\n  wavelength_m: 0\n");
  EXPECT_NE(error_of("water_depth_m: .nan\n").find("water_depth_m: got '.nan', expected a finite"),
            std::string::npos)
      << error_of("water_depth_m: .nan\n");
}

TEST(WaveOptionsErrors, TroughsBelowTheBottomAreRejected) {
  EXPECT_NE(yaml::validate(airy(0.7, 10.0, 0.0, 0.6))
                .find("airy: expected an amplitude_m below water_depth_m"),
            std::string::npos);
  WaveOptions o = three_components();
  o.components[1].amplitude_m = 1.95;
  EXPECT_NE(yaml::validate(o).find("components: expected a sum of amplitude_m below"),
            std::string::npos);
  o = jonswap();
  o.significant_height_m = 3.0;
  EXPECT_NE(yaml::validate(o).find("significant_height_m: expected a significant height below"),
            std::string::npos);
}

TEST(WaveOptionsErrors, MakeWaveFieldThrowsUserErrorNamingTheField) {
  // Options built in code, never validated: make_wave_field checks them itself.
  auto error_of = [](const WaveOptions& o) {
    try {
      make_wave_field(o, phases_rng(1));
    } catch (const UserError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error_of(airy(0.005, 0.0, 0.0, 0.6)).find("water.waves: invalid options"),
            std::string::npos);
  EXPECT_NE(error_of(airy(0.005, 0.0, 0.0, 0.6)).find("airy.wavelength_m: got 0"),
            std::string::npos);
  EXPECT_NE(error_of(airy(0.005, 0.21, 0.0, -1.0)).find("water_depth_m: got -1"),
            std::string::npos);
  WaveOptions o = jonswap();
  o.peak_period_s = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(error_of(o).find("peak_period_s: got nan, expected a finite number"),
            std::string::npos);
  o = three_components();
  o.components.clear();
  EXPECT_NE(error_of(o).find("at least one component"), std::string::npos);
  EXPECT_THROW(wave_components(airy(0.7, 10.0, 0.0, 0.6), phases_rng(1)), UserError);
}

// ---------------------------------------------------------------------------
// Current

TEST(Current, UniformFlowsTowardsItsDirectionEverywhere) {
  CurrentOptions c;
  c.speed_mps = 0.2;
  c.direction_deg = 90.0;  // towards east
  for (const Vec2& p : {Vec2{0, 0}, Vec2{100, -40}, Vec2{-3, 7}}) {
    const Vec3 v = current_velocity(c, p.x(), p.y(), 10.0);
    EXPECT_NEAR(v.x(), 0.0, 1e-16);
    EXPECT_DOUBLE_EQ(v.y(), 0.2);
    EXPECT_EQ(v.z(), 0.0);
  }
  c.direction_deg = 0.0;
  EXPECT_EQ(current_velocity(c, 1.0, 2.0, 0.0), Vec3(0.2, 0.0, 0.0));  // width unused
}

TEST(Current, BankToBankProfileIsParabolicAcrossTheChannel) {
  CurrentOptions c;
  c.speed_mps = 0.25;     // the top of the river paper's measured range
  c.direction_deg = 0.0;  // flowing north: across the channel is east
  c.profile = CurrentProfile::kBankToBank;
  const double w = 10.0;
  EXPECT_DOUBLE_EQ(current_velocity(c, 0.0, 0.0, w).x(), 0.25);
  EXPECT_DOUBLE_EQ(current_velocity(c, 37.0, 0.0, w).x(), 0.25);  // nothing changes along it
  EXPECT_DOUBLE_EQ(current_velocity(c, 0.0, 5.0, w).x(), 0.25 * 0.75);
  EXPECT_DOUBLE_EQ(current_velocity(c, 0.0, -5.0, w).x(), 0.25 * 0.75);
  EXPECT_EQ(current_velocity(c, 0.0, 10.0, w).x(), 0.0);
  EXPECT_EQ(current_velocity(c, 0.0, -25.0, w), Vec3::Zero());  // beyond the bank: still
  c.direction_deg = 90.0;  // flowing east: across is north-south
  const Vec3 v = current_velocity(c, -5.0, 123.0, w);
  EXPECT_NEAR(v.y(), 0.25 * 0.75, 1e-15);
  EXPECT_NEAR(v.x(), 0.0, 1e-16);
  EXPECT_THROW(current_velocity(c, 0.0, 0.0, 0.0), InternalError);
  EXPECT_THROW(current_velocity(c, 0.0, 0.0, std::numeric_limits<double>::quiet_NaN()),
               InternalError);
}

TEST(WindRipples, CoxMunkSlickSurfaceWindTerm) {
  // The wind term of Cox and Munk's slick-surface fit: 1.56e-3 per m/s.
  EXPECT_DOUBLE_EQ(ripple_mean_square_slope(4.4), 1.56e-3 * 4.4);
  EXPECT_EQ(ripple_mean_square_slope(0.0), 0.0);
}

}  // namespace
}  // namespace driftlab::sim
