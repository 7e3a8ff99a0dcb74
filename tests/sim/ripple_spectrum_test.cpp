// Wind ripples from the Elfouhaily et al. (1997) spectrum: the spectrum against
// closed forms and published figures, the slope maps against the spectrum.
#include "sim/physics/waves/ripple_spectrum.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/error.hpp"
#include "sim/physics/waves/wave_field.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab::sim {
namespace {

using driftlab::test::kPi;

TEST(ElfouhailySpectrum, DispersionHasTheCapillaryGravityMinimumPhaseSpeed) {
  // c(k) = omega / k is least at k_m = 370 rad/m, c_m = sqrt(2 g / k_m) = 0.230 m/s.
  const double c_m = gravity_capillary_omega(370.0) / 370.0;
  EXPECT_NEAR(c_m, std::sqrt(2.0 * kGravity_m_s2 / 370.0), 1e-12);
  EXPECT_LT(c_m, gravity_capillary_omega(360.0) / 360.0);
  EXPECT_LT(c_m, gravity_capillary_omega(380.0) / 380.0);
  // Long waves: deep-water gravity waves, omega^2 = g k (capillarity adds
  // (k / k_m)^2 / 2 = 3.7e-6 of omega at 1 rad/m).
  EXPECT_NEAR(gravity_capillary_omega(1.0) / std::sqrt(kGravity_m_s2), 1.0, 4e-6);
}

TEST(ElfouhailySpectrum, FetchSetsTheInverseWaveAgeAndPeak) {
  // A very long fetch: the fully developed sea, Omega_c = 0.84, k_p = g 0.84^2 / U^2.
  const ElfouhailySpectrum open_sea(10.0, 1e9);
  EXPECT_NEAR(open_sea.inverse_wave_age(), 0.84, 1e-6);
  EXPECT_NEAR(open_sea.peak_wavenumber(), kGravity_m_s2 * 0.84 * 0.84 / 100.0, 1e-6);
  // 100 m at 4 m/s: X = g x / U^2 = 61.3, Omega_c = 0.84 tanh((X / 2.2e4)^0.4)^-0.75.
  const double x = kGravity_m_s2 * 100.0 / 16.0;
  const double omega_c = 0.84 * std::pow(std::tanh(std::pow(x / 2.2e4, 0.4)), -0.75);
  const ElfouhailySpectrum river(4.0, 100.0);
  EXPECT_NEAR(river.inverse_wave_age(), std::min(omega_c, 5.0), 1e-12);
  // The curvature spectrum peaks near k_p (JONSWAP's peak over a k^-1/2 slope).
  const double kp = river.peak_wavenumber();
  EXPECT_GT(river.curvature(kp), river.curvature(0.5 * kp));
  EXPECT_GT(river.curvature(kp), river.curvature(0.7 * kp));
  EXPECT_EQ(river.curvature(0.0), 0.0);
  // u* = sqrt(1.44e-3) U.
  EXPECT_NEAR(river.friction_velocity(), std::sqrt(1.44e-3) * 4.0, 1e-15);
}

TEST(ElfouhailySpectrum, ShortFetchSlopesAsIntegratedInTheResearchNotes) {
  // ../shared/research/realism.md (integrated independently): U = 3-5 m/s over
  // 50-200 m gives a mean square slope of 0.011-0.020 and a peak of 0.23-0.77 m.
  for (double u : {3.0, 4.0, 5.0})
    for (double fetch : {50.0, 100.0, 200.0}) {
      const ElfouhailySpectrum s(u, fetch);
      const double mss = s.mean_square_slope(0.1, 1e4);
      EXPECT_GE(mss, 0.010) << u << " m/s over " << fetch << " m";
      EXPECT_LE(mss, 0.022) << u << " m/s over " << fetch << " m";
      const double peak_m = 2.0 * kPi / s.peak_wavenumber();
      EXPECT_GE(peak_m, 0.2);
      EXPECT_LE(peak_m, 0.8);
    }
  // The spreading: long waves near the peak spread less (Delta larger) than
  // the short gravity waves past it; Delta stays in (0, 1).
  const ElfouhailySpectrum s(4.0, 100.0);
  EXPECT_GT(s.spreading(s.peak_wavenumber()), s.spreading(10.0 * s.peak_wavenumber()));
  EXPECT_GT(s.spreading(300.0), 0.0);
  EXPECT_LT(s.spreading(0.5 * s.peak_wavenumber()), 1.0);
}

struct Moments {
  double mean_x = 0, mean_y = 0, var_x = 0, var_y = 0, kurt_x = 0;
};

Moments level0_moments(const RippleMaps& maps, int tile) {
  const std::span<const float> l = maps.level(tile, 0);
  const std::size_t n = l.size() / 4;
  Moments m;
  for (std::size_t i = 0; i < n; ++i) {
    m.mean_x += l[4 * i];
    m.mean_y += l[4 * i + 1];
    m.var_x += double(l[4 * i]) * l[4 * i];
    m.var_y += double(l[4 * i + 1]) * l[4 * i + 1];
    m.kurt_x += std::pow(double(l[4 * i]), 4);
  }
  m.mean_x /= n;
  m.mean_y /= n;
  m.var_x /= n;
  m.var_y /= n;
  m.kurt_x = m.kurt_x / n / (m.var_x * m.var_x);
  return m;
}

WindOptions breeze() {
  WindOptions w;
  w.speed_mps = 4.4;
  w.shelter = 1.0;
  w.direction_deg = 0.0;  // towards north: along x
  return w;
}

TEST(RippleMaps, SlopesAreGaussianWithTheSpectrumsVariance) {
  WindOptions w = breeze();
  w.ripple_level = RippleLevel::kSpectrum;
  RippleMaps maps(w, CurrentOptions{}, RngStreams(5).stream("water.ripples"));
  ASSERT_FALSE(maps.empty());
  // The grid's expected variance against the integral of the spectrum over
  // the band the tiles hold (a second method: quadrature in ln k).
  const ElfouhailySpectrum s(4.4, w.fetch_m);
  const double integral = s.mean_square_slope(2.0 * kPi / 4.0, 2.0 * kPi / 0.02);
  EXPECT_NEAR(maps.mean_square_slope(), integral, 0.05 * integral);
  maps.bake(3.0);
  double var = 0.0, along = 0.0, across = 0.0;
  for (int tile = 0; tile < RippleMaps::kTiles; ++tile) {
    const Moments m = level0_moments(maps, tile);
    // No mean slope on a periodic tile (its k = 0 term is zero).
    EXPECT_NEAR(m.mean_x, 0.0, 1e-6);
    EXPECT_NEAR(m.mean_y, 0.0, 1e-6);
    // Gaussian: kurtosis 3 (a dozen sines gives about 2.75).
    EXPECT_NEAR(m.kurt_x, 3.0, 0.2) << "tile " << tile;
    var += m.var_x + m.var_y;
    along += m.var_x;
    across += m.var_y;
    // The coarsest level is the tile's mean: its second moments the variance.
    const std::span<const float> top = maps.level(tile, maps.levels() - 1);
    ASSERT_EQ(top.size(), 4u);
    EXPECT_NEAR(top[2], m.var_x, 1e-4 * m.var_x);
  }
  EXPECT_NEAR(var, maps.mean_square_slope(), 0.15 * maps.mean_square_slope());
  // Along the wind steeper than across (Cox and Munk: 3.16e-3 U against 1.92e-3 U + 0.003).
  EXPECT_GT(along, 1.2 * across);
}

TEST(RippleMaps, SlickLevelAndDeterminismAndTime) {
  WindOptions w = breeze();
  w.shelter = 0.25;  // the survey's breeze: 1.1 m/s at the water
  RippleMaps a(w, CurrentOptions{}, RngStreams(5).stream("water.ripples"));
  EXPECT_NEAR(a.mean_square_slope(), 1.56e-3 * 1.1, 1e-12);
  RippleMaps b(w, CurrentOptions{}, RngStreams(5).stream("water.ripples"));
  a.bake(1.0);
  b.bake(1.0);
  for (int tile = 0; tile < RippleMaps::kTiles; ++tile)
    for (int l = 0; l < a.levels(); ++l) {
      const auto x = a.level(tile, l), y = b.level(tile, l);
      ASSERT_TRUE(std::equal(x.begin(), x.end(), y.begin(), y.end())) << tile << " " << l;
    }
  const std::vector<float> at1(a.level(1, 0).begin(), a.level(1, 0).end());
  a.bake(1.1);
  const auto at11 = a.level(1, 0);
  EXPECT_FALSE(std::equal(at1.begin(), at1.end(), at11.begin()));
  // The current advects the ripples: the same at t = 0, not later.
  CurrentOptions c;
  c.speed_mps = 0.5;
  RippleMaps drifting(w, c, RngStreams(5).stream("water.ripples"));
  a.bake(0.0);
  drifting.bake(0.0);
  EXPECT_TRUE(std::equal(a.level(0, 0).begin(), a.level(0, 0).end(), drifting.level(0, 0).begin()));
  a.bake(2.0);
  drifting.bake(2.0);
  EXPECT_FALSE(
      std::equal(a.level(0, 0).begin(), a.level(0, 0).end(), drifting.level(0, 0).begin()));
}

TEST(RippleMaps, NoWindNoRipplesAndBadOptionsNamed) {
  WindOptions w = breeze();
  w.shelter = 0.0;
  EXPECT_TRUE(RippleMaps(w, CurrentOptions{}, RngStreams(1).stream("r")).empty());
  w = breeze();
  w.speed_mps = -1.0;
  try {
    RippleMaps bad(w, CurrentOptions{}, RngStreams(1).stream("r"));
    FAIL() << "no error for a negative wind speed";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("water.wind"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("speed_mps: got -1"), std::string::npos) << e.what();
  }
  w = breeze();
  w.fetch_m = 0.5;
  EXPECT_THROW(RippleMaps(w, CurrentOptions{}, RngStreams(1).stream("r")), UserError);
}

}  // namespace
}  // namespace driftlab::sim
