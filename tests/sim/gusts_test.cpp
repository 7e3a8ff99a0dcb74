// The wind in the vegetation (sim/physics/wind/gusts.hpp): the sway's variance is the integral of
// the oscillator's response to the Kaimal gusts (an independent quadrature, and the time series
// sampled), the gusts move downwind at the mean wind, and no wind is no sway.
#include "sim/physics/wind/gusts.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace driftlab::sim {
namespace {

WindOptions breeze(double speed_mps) {
  WindOptions w;
  w.speed_mps = speed_mps;
  w.direction_deg = 30;
  return w;
}

// The response variance by the trapezoid rule on a uniform grid of 200,000 steps over the
// components' range (another quadrature than the bands' log-spaced midpoints).
double trapezoid_variance(double speed_mps) {
  constexpr int kSteps = 200000;
  const double f0 = 0.03, f1 = 2.0, df = (f1 - f0) / kSteps;
  double v = 0;
  for (int i = 0; i <= kSteps; ++i) {
    const double f = f0 + i * df;
    const double g = 2 * kSwayCompliance_s2_per_m * speed_mps * sway_gain(f);
    v += (i == 0 || i == kSteps ? 0.5 : 1.0) * g * g * kaimal_spectrum(f, speed_mps) * df;
  }
  return v;
}

TEST(Gusts, SwayVarianceIsTheIntegralOfTheResponseToTheKaimalSpectrum) {
  for (double u : {2.0, 4.4, 8.0}) {
    const VegetationSway s = vegetation_sway(breeze(u), Rng(7));
    ASSERT_EQ(s.components.size(), static_cast<std::size_t>(kGustComponents));
    double components = 0;
    for (const SwayComponent& c : s.components) components += c.amplitude_m * c.amplitude_m / 2;
    EXPECT_NEAR(components, trapezoid_variance(u), 0.002 * components) << u;
    // The time series itself, sampled every 0.05 s for 4 hours at one place.
    double sum = 0, sum2 = 0;
    const int n = 288000;
    for (int i = 0; i < n; ++i) {
      const double x = s.sway_m(Eigen::Vector2d(3, -8), 0.05 * i);
      sum += x;
      sum2 += x * x;
    }
    EXPECT_NEAR(sum2 / n - (sum / n) * (sum / n), components, 0.03 * components) << u;
  }
  // At the survey's 4.4 m/s a 12 m tree's top sways a few centimetres rms: sqrt(variance).
  const double rms = std::sqrt(trapezoid_variance(4.4));
  EXPECT_GT(rms, 0.02);
  EXPECT_LT(rms, 0.08);
}

TEST(Gusts, KaimalSpectrumCarriesTheTurbulenceVariance) {
  // The integral of S over all frequencies is sigma^2 = (I U)^2 (closed form: 4 L/U over
  // (6 L/U) (2/3) = 1).
  const double u = 5;
  double v = 0;
  const double df = 1e-4;
  for (double f = df / 2; f < 200; f += df) v += kaimal_spectrum(f, u) * df;
  const double sigma = kTurbulenceIntensity * u;
  EXPECT_NEAR(v, sigma * sigma, 0.01 * sigma * sigma);
}

TEST(Gusts, GustsTravelDownwindAtTheMeanWind) {
  const WindOptions w = breeze(4.4);
  const VegetationSway s = vegetation_sway(w, Rng(3));
  const double a = w.direction_deg * std::numbers::pi / 180;
  const Eigen::Vector2d d(std::cos(a), std::sin(a));
  EXPECT_NEAR((s.direction_W - d).norm(), 0.0, 1e-12);
  for (double tau : {0.7, 5.0, 31.0}) {
    const Eigen::Vector2d p(12, -4);
    EXPECT_NEAR(s.sway_m(p + d * w.speed_mps * tau, 10 + tau), s.sway_m(p, 10), 1e-9) << tau;
  }
  // Across the wind, a gust is the same everywhere.
  const Eigen::Vector2d across(-d.y(), d.x());
  EXPECT_NEAR(s.sway_m(across * 50, 3), s.sway_m(Eigen::Vector2d::Zero(), 3), 1e-9);
}

TEST(Gusts, NoWindOrSwayOffStandsStill) {
  EXPECT_TRUE(vegetation_sway(breeze(0), Rng(1)).empty());
  WindOptions off = breeze(5);
  off.sway = false;
  EXPECT_TRUE(vegetation_sway(off, Rng(1)).empty());
  const VegetationSway s = vegetation_sway(breeze(5), Rng(1));
  EXPECT_FALSE(s.empty());
  EXPECT_NEAR(s.flutter_amplitude_m, kFlutterAmplitude_m, 1e-15);  // its reference speed
  // The same seed, the same phases; another, others.
  EXPECT_EQ(vegetation_sway(breeze(5), Rng(1)).components[3].phase_rad, s.components[3].phase_rad);
  EXPECT_NE(vegetation_sway(breeze(5), Rng(2)).components[3].phase_rad, s.components[3].phase_rad);
}

TEST(Gusts, TheOscillatorsGainAndLag) {
  EXPECT_NEAR(sway_gain(1e-6), 1.0, 1e-9);  // quasi-static: the drag's own deflection
  EXPECT_NEAR(sway_gain(kSwayFrequency_hz), 1 / (2 * kSwayDamping), 1e-12);  // resonance
  EXPECT_NEAR(sway_lag_rad(kSwayFrequency_hz), std::numbers::pi / 2, 1e-12);
  EXPECT_LT(sway_gain(2.0), 0.05);  // far above: the tree does not follow
}

}  // namespace
}  // namespace driftlab::sim
