#include "eval/regression.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <iostream>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/error.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab::eval {
namespace {

using driftlab::test::kPi;

// Log relative error: the number of significant digits `got` shares with `certified`, as NIST
// StRD grades a package (McCullough 1998). Capped at 15 (an exact match).
double lre(double got, double certified) {
  const double rel = std::abs(got - certified) / std::abs(certified);
  return rel == 0 ? 15.0 : std::min(15.0, -std::log10(rel));
}

// Every number a result holds must be a number (infinite t/F only on an exact fit).
void expect_no_nan(const OlsResult& r) {
  for (const double v :
       {r.r2, r.adj_r2, r.f, r.f_p, r.sigma, r.rss, r.tss, r.diagnostics.jarque_bera,
        r.diagnostics.jarque_bera_p, r.diagnostics.shapiro_wilk_w, r.diagnostics.shapiro_wilk_p,
        r.diagnostics.breusch_pagan_lm, r.diagnostics.breusch_pagan_p, r.diagnostics.durbin_watson,
        r.diagnostics.max_vif, r.diagnostics.condition_number})
    EXPECT_FALSE(std::isnan(v));
  for (const auto& c : r.coefficients)
    for (const double v : {c.estimate, c.std_error, c.t, c.p, c.vif}) EXPECT_FALSE(std::isnan(v));
  for (const double v : r.residuals) EXPECT_FALSE(std::isnan(v));
  for (const double v : r.fitted) EXPECT_FALSE(std::isnan(v));
  const std::string brief = r.brief();
  EXPECT_EQ(brief.find("nan"), std::string::npos) << brief;
  EXPECT_EQ(brief.find("NaN"), std::string::npos) << brief;
}

// ---------------------------------------------------------------------------------------------
// NIST StRD Longley (Longley 1967): 16 observations, y = total derived employment,
// x1 = GNP implicit price deflator, x2 = GNP, x3 = unemployed, x4 = armed forces,
// x5 = non-institutional population >= 14, x6 = year. Data and certified values as published
// at https://www.itl.nist.gov/div898/strd/lls/data/Longley.shtml (certified to 15 digits),
// transcribed from the copies in GSL's and Apache Commons Math's test suites, which agree.
struct Longley {
  std::vector<double> y{60323, 61122, 60171, 61187, 63221, 63639, 64989, 63761,
                        66019, 67857, 68169, 66513, 68655, 69564, 69331, 70551};
  std::vector<std::vector<double>> x{
      {83.0, 88.5, 88.2, 89.5, 96.2, 98.1, 99.0, 100.0, 101.2, 104.6, 108.4, 110.8, 112.6, 114.2,
       115.7, 116.9},
      {234289, 259426, 258054, 284599, 328975, 346999, 365385, 363112, 397469, 419180, 442769,
       444546, 482704, 502601, 518173, 554894},
      {2356, 2325, 3682, 3351, 2099, 1932, 1870, 3578, 2904, 2822, 2936, 4681, 3813, 3931, 4806,
       4007},
      {1590, 1456, 1616, 1650, 3099, 3594, 3547, 3350, 3048, 2857, 2798, 2637, 2552, 2514, 2572,
       2827},
      {107608, 108632, 109773, 110929, 112075, 113270, 115094, 116219, 117388, 118734, 120445,
       121950, 123366, 125368, 127852, 130081},
      {1947, 1948, 1949, 1950, 1951, 1952, 1953, 1954, 1955, 1956, 1957, 1958, 1959, 1960, 1961,
       1962}};
  std::vector<std::string> names{"x1", "x2", "x3", "x4", "x5", "x6"};

  // Certified regression statistics: B0..B6 and their standard deviations.
  std::vector<double> beta{-3482258.63459582, 15.0618722713733,  -0.358191792925910e-01,
                           -2.02022980381683, -1.03322686717359, -0.511041056535807e-01,
                           1829.15146461355};
  std::vector<double> sd{890420.383607373,  84.9149257747669,  0.334910077722432e-01,
                         0.488399681651699, 0.214274163161675, 0.226073200069370,
                         455.478499142212};
  double residual_sd = 304.854073561965;
  double r_squared = 0.995479004577296;
  // Certified analysis of variance.
  double regression_ss = 184172401.944494;
  double residual_ss = 836424.055505915;
  double f = 330.285339234588;
};

TEST(OlsNistTest, LongleyEveryCertifiedValueToAtLeastNineDigits) {
  const Longley d;
  const OlsResult r = ols(d.y, d.x, d.names);
  ASSERT_EQ(r.coefficients.size(), 7u);
  EXPECT_EQ(r.n, 16u);
  EXPECT_EQ(r.df_model, 6u);
  EXPECT_EQ(r.df_resid, 9u);
  EXPECT_EQ(r.coefficients[0].name, "Intercept");

  double worst = 15.0;
  auto check = [&](const std::string& what, double got, double certified) {
    const double digits = lre(got, certified);
    worst = std::min(worst, digits);
    EXPECT_GE(digits, 9.0) << what << ": got " << got << ", certified " << certified;
    std::cout << "  Longley " << what << ": " << digits << " digits\n";
  };
  for (std::size_t j = 0; j < 7; ++j) {
    check("B" + std::to_string(j), r.coefficients[j].estimate, d.beta[j]);
    check("SD(B" + std::to_string(j) + ")", r.coefficients[j].std_error, d.sd[j]);
  }
  check("residual SD", r.sigma, d.residual_sd);
  check("R^2", r.r2, d.r_squared);
  check("regression SS", r.tss - r.rss, d.regression_ss);
  check("residual SS", r.rss, d.residual_ss);
  check("F", r.f, d.f);
  std::cout << "  Longley: fewest digits " << worst << "\n";
  RecordProperty("longley_min_digits", std::to_string(worst));
  expect_no_nan(r);
  // Longley is the textbook collinear design: the VIFs are large but far below 1e6.
  EXPECT_GT(r.diagnostics.max_vif, 10.0);
  EXPECT_FALSE(r.warnings.empty());
}

// NIST StRD Norris (ozone monitor calibration; lower difficulty), y = B0 + B1 x. Data and
// certified values from https://www.itl.nist.gov/div898/strd/lls/data/Norris.shtml, via the
// copies in GSL's test suite and the GAMS test library (LS01), which agree.
TEST(OlsNistTest, NorrisCertifiedValues) {
  const std::vector<double> y{0.1,   338.8, 118.1, 888.0, 9.2,   228.1, 668.5, 998.5, 449.1,
                              778.9, 559.2, 0.3,   0.1,   778.1, 668.8, 339.3, 448.9, 10.8,
                              557.7, 228.3, 998.0, 888.8, 119.6, 0.3,   0.6,   557.6, 339.3,
                              888.0, 998.5, 778.9, 10.2,  117.6, 228.9, 668.4, 449.2, 0.2};
  const std::vector<double> x{0.2,   337.4, 118.2, 884.6, 10.1,  226.5, 666.3, 996.3, 448.6,
                              777.0, 558.2, 0.4,   0.6,   775.5, 666.9, 338.0, 447.5, 11.6,
                              556.0, 228.1, 995.8, 887.6, 120.2, 0.3,   0.3,   556.8, 339.1,
                              887.2, 999.0, 779.0, 11.1,  118.3, 229.2, 669.1, 448.9, 0.5};
  const OlsResult r = ols(y, {x}, {"x"});
  ASSERT_EQ(r.coefficients.size(), 2u);
  EXPECT_GE(lre(r.coefficients[0].estimate, -0.262323073774029), 9.0);
  EXPECT_GE(lre(r.coefficients[1].estimate, 1.00211681802045), 9.0);
  EXPECT_GE(lre(r.coefficients[0].std_error, 0.232818234301152), 9.0);
  EXPECT_GE(lre(r.coefficients[1].std_error, 0.429796848199937e-03), 9.0);
  EXPECT_GE(lre(r.sigma, 0.884796396144373), 9.0);
  EXPECT_GE(lre(r.r2, 0.999993745883712), 9.0);
  EXPECT_GE(lre(r.tss - r.rss, 4255954.13232369), 9.0);
  EXPECT_GE(lre(r.rss, 26.6173985294224), 9.0);
  EXPECT_GE(lre(r.f, 5436385.54079785), 9.0);
  // t = B0 / SD(B0) from the certified values; its two-sided p with 34 df and the slope's,
  // evaluated independently as the regularised incomplete beta I_{df/(df+t^2)}(df/2, 1/2) with
  // mpmath at 40 digits. (The GAMS test library's copy of Norris, LS01, lists 0.267746835947037
  // for the intercept: 9e-8 off.)
  EXPECT_NEAR(r.coefficients[0].t, -0.262323073774029 / 0.232818234301152, 1e-9);
  EXPECT_NEAR(r.coefficients[0].p, 0.26774674233320224, 1e-9);
  EXPECT_NEAR(r.coefficients[1].p / 4.654040852473141e-90, 1.0, 1e-6);
  EXPECT_FALSE(r.coefficients[0].significant);
  EXPECT_TRUE(r.coefficients[1].significant);
  expect_no_nan(r);
}

// NIST StRD NoInt1: y = B1 x without an intercept; R^2 is certified about zero (uncentred).
// https://www.itl.nist.gov/div898/strd/lls/data/NoInt1.shtml
TEST(OlsNistTest, NoInt1WithoutIntercept) {
  const std::vector<double> x{60, 61, 62, 63, 64, 65, 66, 67, 68, 69, 70};
  const std::vector<double> y{130, 131, 132, 133, 134, 135, 136, 137, 138, 139, 140};
  const OlsResult r = ols(y, {x}, {"x"}, {.intercept = false});
  ASSERT_EQ(r.coefficients.size(), 1u);
  EXPECT_EQ(r.coefficients[0].name, "x");
  EXPECT_EQ(r.df_resid, 10u);
  EXPECT_GE(lre(r.coefficients[0].estimate, 2.07438016528926), 9.0);
  EXPECT_GE(lre(r.coefficients[0].std_error, 0.165289256198347e-01), 9.0);
  EXPECT_GE(lre(r.sigma, 3.56753034006338), 9.0);
  EXPECT_GE(lre(r.r2, 0.999365492298663), 9.0);
  EXPECT_GE(lre(r.tss - r.rss, 200457.727272727), 9.0);
  EXPECT_GE(lre(r.rss, 127.272727272727), 9.0);
  // Uncentred VIF of a lone column is 1.
  EXPECT_NEAR(r.coefficients[0].vif, 1.0, 1e-12);
  expect_no_nan(r);
}

// ---------------------------------------------------------------------------------------------
// Distribution tails at known quantiles, given to 10 significant digits: the upper-tail
// probability at the 0.95 (two-sided: 0.975) quantile is 0.05. chi^2_{0.95, 2} = -2 ln 0.05.

TEST(OlsDistributionTest, PValuesAtPublishedQuantiles) {
  EXPECT_NEAR(t_two_sided_p(2.228138852, 10), 0.05, 1e-9);       // t_{0.975, 10}
  EXPECT_NEAR(t_two_sided_p(-2.228138852, 10), 0.05, 1e-9);      // two-sided: sign irrelevant
  EXPECT_NEAR(f_upper_p(3.098391212, 3, 20), 0.05, 1e-9);        // F_{0.95; 3, 20}
  EXPECT_NEAR(chi_squared_upper_p(5.991464547, 2), 0.05, 1e-9);  // chi^2_{0.95, 2}
  // chi^2 with 2 df has the closed-form tail exp(-x/2).
  EXPECT_NEAR(chi_squared_upper_p(3.0, 2), std::exp(-1.5), 1e-14);
  // t with 1 df is Cauchy: P(|T| > 1) = 1/2.
  EXPECT_NEAR(t_two_sided_p(1.0, 1), 0.5, 1e-14);
  EXPECT_EQ(t_two_sided_p(0.0, 5), 1.0);
  EXPECT_EQ(t_two_sided_p(std::numeric_limits<double>::infinity(), 5), 0.0);
  EXPECT_EQ(f_upper_p(std::numeric_limits<double>::infinity(), 2, 5), 0.0);
  EXPECT_THROW(t_two_sided_p(1.0, 0.0), UserError);
  EXPECT_THROW(f_upper_p(-1.0, 2, 5), UserError);
  EXPECT_THROW(chi_squared_upper_p(1.0, -2.0), UserError);
}

// ---------------------------------------------------------------------------------------------
// Residual checks on hand-computed samples.

TEST(OlsDiagnosticsTest, DurbinWatsonByHand) {
  // Differences -2, 3, -2: 4 + 9 + 4 = 17 over 1 + 1 + 4 + 0 = 6.
  EXPECT_DOUBLE_EQ(durbin_watson({1.0, -1.0, 2.0, 0.0}), 17.0 / 6.0);
  // A constant sequence has no successive differences.
  EXPECT_DOUBLE_EQ(durbin_watson({3.0, 3.0, 3.0}), 0.0);
  // Alternating signs: each difference is 2a, 4 a^2 (n-1) / (n a^2).
  EXPECT_DOUBLE_EQ(durbin_watson({1.0, -1.0, 1.0, -1.0, 1.0}), 16.0 / 5.0);
  EXPECT_THROW(durbin_watson({0.0, 0.0}), UserError);
  EXPECT_THROW(durbin_watson({1.0}), UserError);
}

TEST(OlsDiagnosticsTest, JarqueBeraByHand) {
  // {1, 2, 3, 4, 10}: mean 4, deviations -3 -2 -1 0 6; population moments m2 = 10, m3 = 36,
  // m4 = 278.8; S^2 = 1296/1000, K = 2.788; JB = 5/6 (1.296 + 0.212^2/4).
  const double expected = 5.0 / 6.0 * (1.296 + 0.212 * 0.212 / 4.0);
  const OneSampleTest r = jarque_bera({1.0, 2.0, 3.0, 4.0, 10.0});
  EXPECT_NEAR(r.statistic, expected, 1e-13);
  EXPECT_NEAR(r.p, std::exp(-expected / 2.0), 1e-13);  // chi^2(2) tail
  // {-2, 0, 2}: symmetric (S = 0), m2 = 8/3, m4 = 32/3, K = 1.5: JB = 3/6 (1.5^2 / 4).
  EXPECT_NEAR(jarque_bera({-2.0, 0.0, 2.0}).statistic, 0.5 * 2.25 / 4.0, 1e-14);
  EXPECT_THROW(jarque_bera({5.0, 5.0, 5.0}), UserError);
}

// Shapiro-Wilk W and p against published outputs of the same algorithm (Royston's AS R94):
//  - scipy's test suite (scipy/stats/tests/test_morestats.py, TestShapiro.test_basic), two
//    samples of 20, W and p from the single-precision Fortran swilk, hence 1e-6 tolerances;
//  - R's shapiro.test(mtcars$wt), printed as "W = 0.94326, p-value = 0.09265" (RPubs,
//    rstudio-pubs-static 222982), the Motor Trend car weights of R's datasets::mtcars.
TEST(OlsDiagnosticsTest, ShapiroWilkPublishedExamples) {
  const OneSampleTest a =
      shapiro_wilk({0.11, 7.87, 4.61, 10.14, 7.95, 3.14, 0.46, 4.43, 0.21, 4.75,
                    0.71, 1.52, 3.24, 0.93,  0.42, 4.97, 9.53, 4.55, 0.47, 6.66});
  EXPECT_NEAR(a.statistic, 0.90047299861907959, 2e-6);
  EXPECT_NEAR(a.p, 0.042089745402336121, 2e-6);

  const OneSampleTest b =
      shapiro_wilk({1.36, 1.14,  2.92, 2.55, 1.46, 1.06, 5.27, -1.11, 3.48, 1.10,
                    0.88, -0.51, 1.46, 0.52, 6.20, 1.69, 0.08, 3.67,  2.81, 3.49});
  EXPECT_NEAR(b.statistic, 0.9590269923210144, 2e-6);
  EXPECT_NEAR(b.p, 0.52459925413131714, 2e-5);

  const OneSampleTest wt =
      shapiro_wilk({2.620, 2.875, 2.320, 3.215, 3.440, 3.460, 3.570, 3.190, 3.150, 3.440, 3.440,
                    4.070, 3.730, 3.780, 5.250, 5.424, 5.345, 2.200, 1.615, 1.835, 2.465, 3.520,
                    3.435, 3.840, 3.845, 1.935, 2.140, 1.513, 3.170, 2.770, 3.570, 2.780});
  EXPECT_NEAR(wt.statistic, 0.94326, 5e-6);
  EXPECT_NEAR(wt.p, 0.09265, 5e-6);
}

// n = 3: the coefficients are exactly (-1/sqrt 2, 0, 1/sqrt 2) and the p value is exact,
// p = (6/pi) (asin sqrt W - asin sqrt(3/4)) (Royston 1995).
TEST(OlsDiagnosticsTest, ShapiroWilkThreePointsExact) {
  // {1, 2, 4}: W = (4 - 1)^2 / 2 / (16/9 + 1/9 + 25/9) = 4.5 / (42/9).
  const double w = 4.5 / (42.0 / 9.0);
  const OneSampleTest r = shapiro_wilk({4.0, 1.0, 2.0});
  EXPECT_NEAR(r.statistic, w, 1e-14);
  EXPECT_NEAR(r.p, 6.0 / kPi * (std::asin(std::sqrt(w)) - kPi / 3.0), 1e-13);
  // Equally spaced points are the most "normal" three points can be: W = 1, p = 1.
  const OneSampleTest even = shapiro_wilk({1.0, 2.0, 3.0});
  EXPECT_NEAR(even.statistic, 1.0, 1e-14);
  EXPECT_NEAR(even.p, 1.0, 1e-6);
}

// Portable standard normal draws (std::normal_distribution's algorithm is unspecified).
class Normal {
 public:
  explicit Normal(std::uint64_t seed) : engine_(seed) {}
  double operator()() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    const double u1 = (static_cast<double>(engine_() >> 11) + 0.5) * 0x1.0p-53;
    const double u2 = (static_cast<double>(engine_() >> 11) + 0.5) * 0x1.0p-53;
    const double radius = std::sqrt(-2.0 * std::log(u1));
    spare_ = radius * std::sin(2.0 * kPi * u2);
    has_spare_ = true;
    return radius * std::cos(2.0 * kPi * u2);
  }

 private:
  std::mt19937_64 engine_;
  double spare_ = 0;
  bool has_spare_ = false;
};

// Under normality the p value is uniform: the rejection rate at 0.05 and 0.10 must be close
// to nominal. Independent of any published number, and covers the small-sample (4..11) and
// large-sample branches of the p approximation.
TEST(OlsDiagnosticsTest, ShapiroWilkRejectsAtNominalRateUnderNormality) {
  Normal normal(20240521);
  for (const std::size_t n : {4u, 5u, 8u, 11u, 30u}) {
    const int trials = 20000;
    int below_05 = 0, below_10 = 0;
    std::vector<double> x(n);
    for (int t = 0; t < trials; ++t) {
      for (double& v : x) v = normal();
      const double p = shapiro_wilk(x).p;
      below_05 += p < 0.05;
      below_10 += p < 0.10;
    }
    // Binomial SD is 0.0015 / 0.0021; Royston reports the approximation within about 0.005.
    EXPECT_NEAR(below_05 / static_cast<double>(trials), 0.05, 0.01) << "n = " << n;
    EXPECT_NEAR(below_10 / static_cast<double>(trials), 0.10, 0.012) << "n = " << n;
  }
}

TEST(OlsDiagnosticsTest, ShapiroWilkRejectsSkewedData) {
  // Exponential-like sample of 40: strongly right-skewed.
  std::vector<double> x;
  for (int i = 1; i <= 40; ++i) x.push_back(-std::log(1.0 - (i - 0.5) / 40.0));
  const OneSampleTest r = shapiro_wilk(x);
  EXPECT_LT(r.p, 0.01);
  EXPECT_LT(r.statistic, 0.95);
  EXPECT_THROW(shapiro_wilk({1.0, 2.0}), UserError);
  EXPECT_THROW(shapiro_wilk({2.0, 2.0, 2.0, 2.0}), UserError);
  EXPECT_THROW(shapiro_wilk(std::vector<double>(5001, 1.0)), UserError);
}

// ---------------------------------------------------------------------------------------------
// Breusch-Pagan (Koenker): n R^2 of e^2 on x.

double pearson(const std::vector<double>& a, const std::vector<double>& b) {
  const double n = static_cast<double>(a.size());
  double ma = 0, mb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ma += a[i] / n;
    mb += b[i] / n;
  }
  double sab = 0, saa = 0, sbb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    sab += (a[i] - ma) * (b[i] - mb);
    saa += (a[i] - ma) * (a[i] - ma);
    sbb += (b[i] - mb) * (b[i] - mb);
  }
  return sab / std::sqrt(saa * sbb);
}

struct Simulated {
  std::vector<double> x, y;
};

Simulated straight_line(std::size_t n, std::uint64_t seed,
                        const std::function<double(double)>& noise_sd) {
  Normal normal(seed);
  Simulated s;
  for (std::size_t i = 0; i < n; ++i) {
    const double x = 10.0 * static_cast<double>(i) / static_cast<double>(n);
    s.x.push_back(x);
    s.y.push_back(1.0 + 0.5 * x + noise_sd(x) * normal());
  }
  return s;
}

TEST(OlsDiagnosticsTest, BreuschPaganDetectsVarianceGrowingWithX) {
  const Simulated s = straight_line(200, 7, [](double x) { return 0.1 + x; });
  const OlsResult r = ols(s.y, {s.x}, {"x"});
  ASSERT_TRUE(r.diagnostics.breusch_pagan_available);
  EXPECT_LT(r.diagnostics.breusch_pagan_p, 0.01);
  // Independently: with one regressor, R^2 of e^2 on x is corr(e^2, x)^2.
  std::vector<double> e2;
  for (const double e : r.residuals) e2.push_back(e * e);
  const double rho = pearson(e2, s.x);
  EXPECT_NEAR(r.diagnostics.breusch_pagan_lm, 200.0 * rho * rho, 1e-9);
  // chi^2(1) tail: P(Z^2 > LM) = erfc(sqrt(LM / 2)).
  EXPECT_NEAR(r.diagnostics.breusch_pagan_p, std::erfc(std::sqrt(100.0 * rho * rho)), 1e-12);
}

TEST(OlsDiagnosticsTest, BreuschPaganQuietOnHomoscedasticData) {
  const Simulated s = straight_line(200, 11, [](double) { return 1.0; });
  const OlsResult r = ols(s.y, {s.x}, {"x"});
  ASSERT_TRUE(r.diagnostics.breusch_pagan_available);
  EXPECT_GT(r.diagnostics.breusch_pagan_p, 0.05);
  for (const auto& w : r.warnings) EXPECT_EQ(w.find("heteroscedastic"), std::string::npos) << w;
  // Homoscedastic normal noise: the other checks stay quiet too.
  EXPECT_GT(r.diagnostics.jarque_bera_p, 0.01);
  EXPECT_GT(r.diagnostics.shapiro_wilk_p, 0.01);
  EXPECT_NEAR(r.diagnostics.durbin_watson, 2.0, 0.5);
}

// ---------------------------------------------------------------------------------------------
// Collinearity.

TEST(OlsCollinearityTest, VifOfTwoCorrelatedColumnsIsOneOverOneMinusRSquared) {
  Normal normal(3);
  std::vector<double> a, b, y;
  for (int i = 0; i < 50; ++i) {
    const double u = normal();
    a.push_back(5.0 + u);
    b.push_back(-2.0 + 0.8 * u + 0.6 * normal());
    y.push_back(1.0 + a.back() - b.back() + 0.3 * normal());
  }
  const OlsResult r = ols(y, {a, b}, {"a", "b"});
  const double rho = pearson(a, b);
  const double expected = 1.0 / (1.0 - rho * rho);
  ASSERT_EQ(r.coefficients.size(), 3u);
  EXPECT_EQ(r.coefficients[0].vif, 0.0);  // intercept
  EXPECT_NEAR(r.coefficients[1].vif, expected, 1e-12 * expected);
  EXPECT_NEAR(r.coefficients[2].vif, expected, 1e-12 * expected);
  EXPECT_NEAR(r.diagnostics.max_vif, expected, 1e-12 * expected);
  expect_no_nan(r);
}

// ---------------------------------------------------------------------------------------------
// Bad input: each gives a UserError whose message names the problem.

void expect_user_error(const std::function<void()>& f, std::initializer_list<std::string> parts) {
  try {
    f();
    ADD_FAILURE() << "no UserError thrown; expected a message with '" << *parts.begin() << "'";
  } catch (const UserError& e) {
    const std::string what = e.what();
    for (const auto& part : parts)
      EXPECT_NE(what.find(part), std::string::npos) << "'" << part << "' not in: " << what;
  }
}

struct Sections {
  std::vector<double> y{0.05, 0.07, 0.04, 0.10, 0.08, 0.12, 0.06, 0.09};
  std::vector<double> v{0.3, 0.5, 0.2, 0.9, 0.6, 1.1, 0.4, 0.7};
  std::vector<double> h{5.0, 12.0, 3.0, 30.0, 11.0, 40.0, 7.0, 18.0};
};

TEST(OlsBadInputTest, SizeMismatch) {
  Sections s;
  s.h.pop_back();
  expect_user_error(
      [&] {
        ols(s.y, {s.v, s.h}, {"v", "h"});
      },
      {"column 'h'", "7 values", "y has 8"});
  expect_user_error([&] { ols(s.y, {s.v, s.v}, {"v"}); }, {"2 columns", "1 names"});
}

TEST(OlsBadInputTest, NonFiniteValuesNameColumnAndRow) {
  Sections s;
  s.h[2] = std::numeric_limits<double>::quiet_NaN();
  expect_user_error([&] { ols(s.y, {s.v, s.h}, {"v", "h"}); }, {"column 'h'", "row 2", "NaN"});
  Sections t;
  t.y[0] = std::numeric_limits<double>::infinity();
  expect_user_error([&] { ols(t.y, {t.v, t.h}, {"v", "h"}); }, {"y row 0", "+inf"});
}

TEST(OlsBadInputTest, TooFewSections) {
  const std::vector<double> y{1, 2, 3, 4, 6}, a{1, 0, 2, 5, 1}, b{3, 1, 4, 1, 5}, c{2, 7, 1, 8, 2},
      d{1, 4, 1, 4, 2};
  expect_user_error(
      [&] {
        ols(y, {a, b, c, d}, {"a", "b", "c", "d"});
      },
      {"got 5 sections, need at least 6 for 5 regressors"});
  expect_user_error([&] { ols(std::vector<double>{}, {std::vector<double>{}}, {"a"}); },
                    {"got 0 sections, need at least 3 for 2 regressors"});
}

TEST(OlsBadInputTest, ConstantColumnWithIntercept) {
  Sections s;
  const std::vector<double> constant(8, 0.5);
  expect_user_error(
      [&] {
        ols(s.y, {s.v, constant}, {"v", "c"});
      },
      {"column 'c' is constant", "every value is 0.5", "intercept"});
  // Without an intercept a constant column is the intercept, and fine.
  const OlsResult r = ols(s.y, {s.v, constant}, {"v", "c"}, {.intercept = false});
  EXPECT_EQ(r.coefficients.size(), 2u);
  expect_no_nan(r);
  const std::vector<double> zeros(8, 0.0);
  expect_user_error([&] { ols(s.y, {zeros}, {"z"}, {.intercept = false}); },
                    {"column 'z' is all zeros"});
}

TEST(OlsBadInputTest, ExactlyCollinearColumnsAreNamed) {
  Sections s;
  std::vector<double> h2;
  for (const double h : s.h) h2.push_back(2.0 * h);
  expect_user_error(
      [&] {
        ols(s.y, {s.v, s.h, h2}, {"v", "h", "h2"});
      },
      {"'h' and 'h2'", "exactly collinear", "condition number"});
  // Three-way: w = v + h is collinear with both.
  std::vector<double> w;
  for (std::size_t i = 0; i < s.v.size(); ++i) w.push_back(s.v[i] + s.h[i] / 10.0);
  expect_user_error(
      [&] {
        ols(s.y, {s.v, s.h, w}, {"v", "h", "w"});
      },
      {"'v', 'h' and 'w'", "exactly collinear"});
}

TEST(OlsBadInputTest, NearlyCollinearColumnsGiveVifAndConditionNumber) {
  Sections s;
  std::vector<double> h2;
  for (std::size_t i = 0; i < s.h.size(); ++i)
    h2.push_back(2.0 * s.h[i] + ((i % 2) ? 1e-4 : -1e-4));
  expect_user_error(
      [&] {
        ols(s.y, {s.v, s.h, h2}, {"v", "h", "h2"});
      },
      {"'h' and 'h2'", "nearly collinear", "VIF of", "collinearity_vif = 1e+06",
       "condition number"});
  // A looser threshold accepts the same design, with a multicollinearity warning.
  const OlsResult r = ols(s.y, {s.v, s.h, h2}, {"v", "h", "h2"},
                          {.collinearity_vif = std::numeric_limits<double>::infinity()});
  EXPECT_GT(r.diagnostics.max_vif, 1e6);
  bool warned = false;
  for (const auto& w : r.warnings)
    warned = warned || w.find("multicollinearity") != std::string::npos;
  EXPECT_TRUE(warned);
  expect_no_nan(r);
}

TEST(OlsBadInputTest, NamesOptionsAndResponse) {
  Sections s;
  expect_user_error([&] { ols(s.y, {s.v, s.h}, {"v", "v"}); }, {"'v' appears more than once"});
  expect_user_error([&] { ols(s.y, {s.v, s.h}, {"v", ""}); }, {"column 1", "empty name"});
  expect_user_error([&] { ols(s.y, {s.v}, {"Intercept"}); }, {"reserved for the intercept"});
  expect_user_error([&] { ols(s.y, {}, {}); }, {"no regressors"});
  expect_user_error([&] { ols(s.y, {s.v}, {"v"}, {.alpha = 0.0}); }, {"alpha: got 0"});
  expect_user_error([&] { ols(s.y, {s.v}, {"v"}, {.collinearity_vif = 0.5}); },
                    {"collinearity_vif: got 0.5"});
  const std::vector<double> flat(8, 0.07);
  expect_user_error([&] { ols(flat, {s.v}, {"v"}); }, {"y is constant"});
  EXPECT_EQ(validate(OlsOptions{}), "");
}

// ---------------------------------------------------------------------------------------------
// Perfect fit: no division by zero, no NaN.

TEST(OlsPerfectFitTest, ExactLineIsReportedAsExactWithoutNaN) {
  std::vector<double> x, y;
  for (int i = 0; i < 10; ++i) {
    x.push_back(i);
    y.push_back(3.0 + 2.0 * i);
  }
  const OlsResult r = ols(y, {x}, {"x"});
  EXPECT_NEAR(r.coefficients[0].estimate, 3.0, 1e-12);
  EXPECT_NEAR(r.coefficients[1].estimate, 2.0, 1e-12);
  EXPECT_EQ(r.rss, 0.0);
  EXPECT_EQ(r.sigma, 0.0);
  EXPECT_EQ(r.r2, 1.0);
  EXPECT_EQ(r.adj_r2, 1.0);
  for (const auto& c : r.coefficients) {
    EXPECT_EQ(c.std_error, 0.0) << c.name;
    EXPECT_EQ(c.t, std::numeric_limits<double>::infinity()) << c.name;
    EXPECT_EQ(c.p, 0.0) << c.name;
    EXPECT_TRUE(c.significant) << c.name;
  }
  EXPECT_EQ(r.f, std::numeric_limits<double>::infinity());
  EXPECT_EQ(r.f_p, 0.0);
  for (std::size_t i = 0; i < y.size(); ++i) {
    EXPECT_EQ(r.residuals[i], 0.0);
    EXPECT_EQ(r.fitted[i], y[i]);
  }
  EXPECT_FALSE(r.diagnostics.jarque_bera_available);
  EXPECT_FALSE(r.diagnostics.shapiro_wilk_available);
  EXPECT_FALSE(r.diagnostics.breusch_pagan_available);
  EXPECT_FALSE(r.diagnostics.durbin_watson_available);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings.front().find("perfect fit"), std::string::npos) << r.warnings.front();
  EXPECT_NE(r.brief().find("n/a"), std::string::npos) << r.brief();
  expect_no_nan(r);
}

TEST(OlsPerfectFitTest, ZeroCoefficientsOfAnExactFitAreNotSignificant) {
  // y = -4 x exactly: the intercept and z contribute nothing, up to rounding.
  const std::vector<double> x{1, 2, 3, 4, 5, 6}, z{0.3, -1.2, 2.5, 0.7, -0.4, 1.9};
  std::vector<double> y;
  for (const double v : x) y.push_back(-4.0 * v);
  const OlsResult r = ols(y, {x, z}, {"x", "z"});
  ASSERT_EQ(r.coefficients.size(), 3u);
  EXPECT_EQ(r.coefficients[0].t, 0.0);
  EXPECT_EQ(r.coefficients[0].p, 1.0);
  EXPECT_FALSE(r.coefficients[0].significant);
  EXPECT_EQ(r.coefficients[1].t, -std::numeric_limits<double>::infinity());
  EXPECT_TRUE(r.coefficients[1].significant);
  EXPECT_EQ(r.coefficients[2].t, 0.0);
  EXPECT_EQ(r.coefficients[2].p, 1.0);
  EXPECT_FALSE(r.coefficients[2].significant);
  expect_no_nan(r);
}

// ---------------------------------------------------------------------------------------------
// The shape of river paper Eq. (13): four covariates plus intercept, read back by name.

TEST(OlsSummaryTest, PaperShapedFitAndBrief) {
  Normal normal(96);
  std::vector<double> y, v, h, f, d;
  for (int i = 0; i < 96; ++i) {
    v.push_back(0.57 + 0.37 * normal());
    h.push_back(17.4 + 18.4 * std::abs(normal()));
    f.push_back(233 + 90 * normal());
    d.push_back(21.6 + 9.3 * normal());
    y.push_back(-0.02 + 0.0023 * h.back() + 0.0015 * d.back() + 0.03 * normal());
  }
  const OlsResult r = ols(y, {v, h, f, d}, {"v", "h", "f", "d"});
  ASSERT_EQ(r.coefficients.size(), 5u);
  EXPECT_EQ(r.coefficients[1].name, "v");
  EXPECT_EQ(r.coefficients[4].name, "d");
  EXPECT_TRUE(r.coefficients[2].significant);  // h drives the error
  EXPECT_TRUE(r.coefficients[4].significant);  // and d
  EXPECT_LT(r.f_p, 0.05);
  EXPECT_EQ(r.df_model, 4u);
  EXPECT_EQ(r.df_resid, 91u);
  // Adjusted R^2 from its definition.
  EXPECT_NEAR(r.adj_r2, 1.0 - (1.0 - r.r2) * 95.0 / 91.0, 1e-14);
  // Residuals and fitted values add back to y; residuals are orthogonal to each regressor.
  double dot_h = 0;
  for (std::size_t i = 0; i < y.size(); ++i) {
    EXPECT_NEAR(r.fitted[i] + r.residuals[i], y[i], 1e-15);
    dot_h += r.residuals[i] * h[i];
  }
  EXPECT_NEAR(dot_h, 0.0, 1e-12);
  const std::string brief = r.brief();
  for (const std::string part :
       {"96 observations", "R^2", "F(4, 91)", "Intercept", "h ", "*", "Jarque-Bera", "Shapiro-Wilk",
        "Breusch-Pagan", "Durbin-Watson", "max VIF"})
    EXPECT_NE(brief.find(part), std::string::npos) << "'" << part << "' not in: " << brief;
  expect_no_nan(r);
}

TEST(OlsSummaryTest, ShapiroWilkUnavailableBeyondFiveThousandSections) {
  const Simulated s = straight_line(6000, 5, [](double) { return 1.0; });
  const OlsResult r = ols(s.y, {s.x}, {"x"});
  EXPECT_FALSE(r.diagnostics.shapiro_wilk_available);
  EXPECT_TRUE(r.diagnostics.jarque_bera_available);
  EXPECT_TRUE(r.diagnostics.breusch_pagan_available);
  EXPECT_TRUE(r.diagnostics.durbin_watson_available);
  bool warned = false;
  for (const auto& w : r.warnings) warned = warned || w.find("Shapiro-Wilk not computed") == 0;
  EXPECT_TRUE(warned);
  EXPECT_NE(r.brief().find("Shapiro-Wilk n/a"), std::string::npos) << r.brief();
  expect_no_nan(r);
}

}  // namespace
}  // namespace driftlab::eval
