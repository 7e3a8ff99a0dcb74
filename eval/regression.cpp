#include "eval/regression.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <numbers>
#include <set>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <Eigen/Dense>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/fisher_f.hpp>
#include <boost/math/distributions/normal.hpp>
#include <boost/math/distributions/students_t.hpp>

#include "core/error.hpp"

namespace driftlab::eval {
namespace {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

constexpr const char* kInterceptName = "Intercept";
constexpr double kEps = std::numeric_limits<double>::epsilon();
constexpr double kInf = std::numeric_limits<double>::infinity();
// A column whose values differ by no more than a few dozen roundings of their magnitude carries
// no information beyond its mean: with an intercept, it is the intercept again.
constexpr double kConstantSpread = 64 * kEps;
// Pivots of the unit-norm design below this (relative to the largest) mean VIF > 1e20: past
// anything double precision can resolve, so the regressors are reported as exactly collinear.
constexpr double kRankTolerance = 1e-10;
// The usual multicollinearity rule of thumb (e.g. Kutner et al., Applied Linear Statistical
// Models, Sec. 10.5): warn, but fit.
constexpr double kVifWarning = 10.0;
// Residuals below 1e-12 of the response's spread (1 - R^2 <= 1e-24) are rounding noise of exact
// data: t and F computed from them would measure the arithmetic, not the data.
constexpr double kPerfectFitRss = 1e-24;
// Shapiro-Wilk p values are validated for these sample sizes only (Royston 1995).
constexpr std::size_t kShapiroWilkMinN = 3;
constexpr std::size_t kShapiroWilkMaxN = 5000;

std::string value_text(double v) {
  if (std::isnan(v)) return "NaN";
  if (std::isinf(v)) return v > 0 ? "+inf" : "-inf";
  return fmt::format("{:.17g}", v);
}

std::string quoted_list(const std::vector<std::string>& names) {
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (i > 0) out += (i + 1 == names.size()) ? " and " : ", ";
    out += "'" + names[i] + "'";
  }
  return out;
}

// Mean with one refinement pass, so that a large common offset does not leave a bias that
// centring would then spread over every row.
double mean_of(const double* x, std::size_t n) {
  double sum = 0;
  for (std::size_t i = 0; i < n; ++i) sum += x[i];
  const double m = sum / static_cast<double>(n);
  double correction = 0;
  for (std::size_t i = 0; i < n; ++i) correction += x[i] - m;
  return m + correction / static_cast<double>(n);
}

double mean_of(const std::vector<double>& x) { return mean_of(x.data(), x.size()); }

// True when the values differ only by rounding (or not at all).
bool is_constant(const std::vector<double>& x) {
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  const double magnitude = std::max(std::abs(*lo), std::abs(*hi));
  return *hi - *lo <= kConstantSpread * magnitude;
}

std::string constant_description(const std::vector<double>& x) {
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  if (*lo == *hi) return fmt::format("every value is {}", value_text(*lo));
  return fmt::format("its values differ only by rounding, {:.3g} around {}", *hi - *lo,
                     value_text(*lo));
}

void check_finite(const std::vector<double>& x, const std::string& what) {
  for (std::size_t i = 0; i < x.size(); ++i)
    if (!std::isfinite(x[i]))
      throw UserError(
          fmt::format("ols: {} row {} is {} (rows count from 0); expected a finite number", what, i,
                      value_text(x[i])));
}

void check_inputs(const std::vector<double>& y, const std::vector<std::vector<double>>& columns,
                  const std::vector<std::string>& names, const OlsOptions& options) {
  if (const std::string problems = validate(options); !problems.empty())
    throw UserError("ols: invalid options: " + problems);
  if (columns.empty())
    throw UserError(
        "ols: no regressors given; expected at least one column (river paper Eq. (13) has four)");
  if (names.size() != columns.size())
    throw UserError(fmt::format("ols: got {} columns but {} names; expected one name per column",
                                columns.size(), names.size()));
  std::set<std::string> seen;
  for (std::size_t j = 0; j < names.size(); ++j) {
    if (names[j].empty())
      throw UserError(fmt::format("ols: column {} (counting from 0) has an empty name", j));
    if (options.intercept && names[j] == kInterceptName)
      throw UserError(fmt::format(
          "ols: column {} is named '{}', which is reserved for the intercept; rename it", j,
          kInterceptName));
    if (!seen.insert(names[j]).second)
      throw UserError(fmt::format("ols: column name '{}' appears more than once", names[j]));
  }
  for (std::size_t j = 0; j < columns.size(); ++j)
    if (columns[j].size() != y.size())
      throw UserError(
          fmt::format("ols: column '{}' has {} values but y has {}; expected one value per row",
                      names[j], columns[j].size(), y.size()));
  check_finite(y, "y");
  for (std::size_t j = 0; j < columns.size(); ++j)
    check_finite(columns[j], "column '" + names[j] + "'");

  const std::size_t params = columns.size() + (options.intercept ? 1 : 0);
  if (y.size() < params + 1)
    throw UserError(fmt::format("ols: got {} sections, need at least {} for {} regressors{}",
                                y.size(), params + 1, params,
                                options.intercept ? " (the intercept included)" : ""));

  for (std::size_t j = 0; j < columns.size(); ++j) {
    if (options.intercept && is_constant(columns[j]))
      throw UserError(
          fmt::format("ols: column '{}' is constant ({}): with an intercept it is "
                      "collinear with it; drop the column or fit without an intercept",
                      names[j], constant_description(columns[j])));
    if (!options.intercept &&
        std::all_of(columns[j].begin(), columns[j].end(), [](double v) { return v == 0.0; }))
      throw UserError(
          fmt::format("ols: column '{}' is all zeros; it cannot be estimated", names[j]));
  }
  if (options.intercept && is_constant(y))
    throw UserError(fmt::format("ols: y is constant ({}): there is no variation to explain",
                                constant_description(y)));
  if (!options.intercept && std::all_of(y.begin(), y.end(), [](double v) { return v == 0.0; }))
    throw UserError("ols: y is all zeros: there is nothing to explain");
}

// Columns minus their means (when `centre`), each scaled to unit norm; `scale` gets the norms.
// Columns whose norm is zero after centring are left zero with scale 0.
MatrixXd unit_columns(const std::vector<std::vector<double>>& columns, bool centre, VectorXd* mean,
                      VectorXd* scale) {
  const Index n = static_cast<Index>(columns.front().size());
  const Index k = static_cast<Index>(columns.size());
  MatrixXd z(n, k);
  mean->setZero(k);
  scale->setZero(k);
  for (Index j = 0; j < k; ++j) {
    const auto& c = columns[static_cast<std::size_t>(j)];
    (*mean)(j) = centre ? mean_of(c) : 0.0;
    for (Index i = 0; i < n; ++i) z(i, j) = c[static_cast<std::size_t>(i)] - (*mean)(j);
    (*scale)(j) = z.col(j).stableNorm();
    if ((*scale)(j) > 0) z.col(j) /= (*scale)(j);
  }
  return z;
}

// Names of the regressors that carry the design's weakest direction (smallest right singular
// vector): the ones to drop or combine. At least two are named.
std::vector<std::string> weakest_direction_columns(const VectorXd& v,
                                                   const std::vector<std::string>& names) {
  std::vector<Index> order(static_cast<std::size_t>(v.size()));
  for (Index j = 0; j < v.size(); ++j) order[static_cast<std::size_t>(j)] = j;
  std::stable_sort(order.begin(), order.end(),
                   [&](Index a, Index b) { return std::abs(v(a)) > std::abs(v(b)); });
  const double largest = std::abs(v(order.front()));
  std::vector<bool> involved(static_cast<std::size_t>(v.size()), false);
  for (std::size_t r = 0; r < order.size(); ++r)
    if (r < 2 || std::abs(v(order[r])) >= 0.1 * largest)
      involved[static_cast<std::size_t>(order[r])] = true;
  std::vector<std::string> out;
  for (std::size_t j = 0; j < involved.size(); ++j)
    if (involved[j]) out.push_back(names[j]);
  return out;
}

// Residual checks that may be impossible (e.g. all residuals zero) report availability instead
// of throwing, so that ols() can still return its fit.
struct Check {
  double statistic = 0;
  double p = 1;
  bool available = false;
};

Check jarque_bera_check(const VectorXd& e) {
  const double n = static_cast<double>(e.size());
  if (e.size() < 2) return {};
  const double m = mean_of(e.data(), static_cast<std::size_t>(e.size()));
  double m2 = 0, m3 = 0, m4 = 0;
  for (Index i = 0; i < e.size(); ++i) {
    const double d = e(i) - m;
    const double d2 = d * d;
    m2 += d2;
    m3 += d2 * d;
    m4 += d2 * d2;
  }
  m2 /= n;
  m3 /= n;
  m4 /= n;
  if (!(m2 > 0)) return {};
  const double skew2 = m3 * m3 / (m2 * m2 * m2);
  const double excess = m4 / (m2 * m2) - 3.0;
  const double jb = n / 6.0 * (skew2 + 0.25 * excess * excess);
  return {jb, chi_squared_upper_p(jb, 2.0), true};
}

double poly(const double* c, int count, double x) {
  double r = 0;
  for (int i = count - 1; i >= 0; --i) r = r * x + c[i];
  return r;
}

// Royston (1992) "Approximating the Shapiro-Wilk W-test for non-normality", Stat. Comput. 2,
// 117-119, with the n = 3 exact p and the 4 <= n <= 11 branch of Remark AS R94 (Royston 1995).
Check shapiro_wilk_check(std::vector<double> x) {
  const std::size_t n = x.size();
  if (n < kShapiroWilkMinN || n > kShapiroWilkMaxN) return {};
  std::sort(x.begin(), x.end());
  const double range = x.back() - x.front();
  if (!(range > 0)) return {};
  const double dn = static_cast<double>(n);

  // Coefficients of the upper half, largest order statistic first; a is antisymmetric.
  const std::size_t half = n / 2;
  const boost::math::normal standard;
  std::vector<double> m(half), a(half);
  double summ2 = 0;
  for (std::size_t i = 0; i < half; ++i) {
    m[i] = -boost::math::quantile(standard, (static_cast<double>(i + 1) - 0.375) / (dn + 0.25));
    summ2 += 2.0 * m[i] * m[i];
  }
  if (n == 3) {
    a[0] = std::sqrt(0.5);
  } else {
    static constexpr double kC1[] = {0.0, 0.221157, -0.147981, -2.071190, 4.434685, -2.706056};
    static constexpr double kC2[] = {0.0, 0.042981, -0.293762, -1.752461, 5.682633, -3.582633};
    const double u = 1.0 / std::sqrt(dn);
    const double root_summ2 = std::sqrt(summ2);
    a[0] = m[0] / root_summ2 + poly(kC1, 6, u);
    std::size_t first_plain = 1;
    double num = summ2 - 2.0 * m[0] * m[0];
    double den = 1.0 - 2.0 * a[0] * a[0];
    if (n > 5) {
      a[1] = m[1] / root_summ2 + poly(kC2, 6, u);
      num -= 2.0 * m[1] * m[1];
      den -= 2.0 * a[1] * a[1];
      first_plain = 2;
    }
    const double fac = std::sqrt(num / den);
    for (std::size_t i = first_plain; i < half; ++i) a[i] = m[i] / fac;
  }

  // W is the squared correlation of the data with a (sum a = 0, sum a^2 = 1); 1 - W is formed
  // as a product of a sum and a difference so that W near 1 keeps its digits for log(1 - W).
  const double mean = mean_of(x);
  double ssx = 0, ax = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double d = (x[i] - mean) / range;  // range units: no overflow, offsets cancel first
    ssx += d * d;
  }
  for (std::size_t i = 0; i < half; ++i) ax += a[i] * (x[n - 1 - i] - x[i]) / range;
  const double root_ssx = std::sqrt(ssx);
  double one_minus_w = (root_ssx - ax) * (root_ssx + ax) / ssx;
  one_minus_w = std::clamp(one_minus_w, 0.0, 1.0);
  const double w = 1.0 - one_minus_w;

  double p = 1.0;
  if (n == 3) {
    // Exact: W is then a function of one angle, uniform under normality.
    p = 6.0 / std::numbers::pi * (std::asin(std::sqrt(w)) - std::asin(std::sqrt(0.75)));
  } else if (one_minus_w == 0.0) {
    p = 1.0;
  } else if (n <= 11) {
    static constexpr double kGamma[] = {-2.273, 0.459};
    static constexpr double kMu[] = {0.5440, -0.39978, 0.025054, -6.714e-4};
    static constexpr double kSigma[] = {1.3822, -0.77857, 0.062767, -0.0020322};
    const double gamma = poly(kGamma, 2, dn);
    const double y = std::log(one_minus_w);
    if (y >= gamma) {
      p = 0.0;  // beyond the transformation's support: W far below any normal sample's
    } else {
      const double z = (-std::log(gamma - y) - poly(kMu, 4, dn)) / std::exp(poly(kSigma, 4, dn));
      p = boost::math::cdf(boost::math::complement(standard, z));
    }
  } else {
    static constexpr double kMu[] = {-1.5861, -0.31082, -0.083751, 0.0038915};
    static constexpr double kSigma[] = {-0.4803, -0.082676, 0.0030302};
    const double ln_n = std::log(dn);
    const double z = (std::log(one_minus_w) - poly(kMu, 4, ln_n)) / std::exp(poly(kSigma, 3, ln_n));
    p = boost::math::cdf(boost::math::complement(standard, z));
  }
  return {w, std::clamp(p, 0.0, 1.0), true};
}

Check durbin_watson_check(const VectorXd& e) {
  if (e.size() < 2) return {};
  const double den = e.squaredNorm();
  if (!(den > 0)) return {};
  double num = 0;
  for (Index i = 1; i < e.size(); ++i) num += (e(i) - e(i - 1)) * (e(i) - e(i - 1));
  return {num / den, 1.0, true};
}

// Koenker (1981): LM = n R^2 of e^2 on a constant and the regressors, chi-square(rank).
Check breusch_pagan_check(const VectorXd& e, const std::vector<std::vector<double>>& columns) {
  const Index n = e.size();
  VectorXd u = e.array().square().matrix();
  u.array() -= mean_of(u.data(), static_cast<std::size_t>(n));
  const double tss = u.squaredNorm();
  if (!(tss > 0)) return {};
  VectorXd mean, scale;
  const MatrixXd z = unit_columns(columns, /*centre=*/true, &mean, &scale);
  Eigen::ColPivHouseholderQR<MatrixXd> qr(z.rows(), z.cols());
  qr.setThreshold(kRankTolerance);
  qr.compute(z);
  const Index rank = qr.rank();
  if (rank == 0) return {};
  const VectorXd qtu = qr.householderQ().transpose() * u;
  const double r2 = std::clamp(qtu.head(rank).squaredNorm() / tss, 0.0, 1.0);
  const double lm = static_cast<double>(n) * r2;
  return {lm, chi_squared_upper_p(lm, static_cast<double>(rank)), true};
}

void require_sample(const std::vector<double>& x, std::size_t min_n, const char* what) {
  if (x.size() < min_n)
    throw UserError(fmt::format("{}: got {} values, need at least {}", what, x.size(), min_n));
  for (std::size_t i = 0; i < x.size(); ++i)
    if (!std::isfinite(x[i]))
      throw UserError(fmt::format("{}: value {} (counting from 0) is {}; expected a finite number",
                                  what, i, value_text(x[i])));
}

std::string g4(double v) { return std::isinf(v) ? value_text(v) : fmt::format("{:.4g}", v); }

std::string p_text(double p) { return p < 1e-4 ? "< 1e-4" : "= " + fmt::format("{:.2g}", p); }

}  // namespace

std::string validate(const OlsOptions& options) {
  std::vector<std::string> problems;
  if (!(options.alpha > 0 && options.alpha < 1))
    problems.push_back(
        fmt::format("alpha: got {}, expected a value in (0, 1)", value_text(options.alpha)));
  if (!(options.collinearity_vif > 1))
    problems.push_back(
        fmt::format("collinearity_vif: got {}, expected a value > 1 (+inf to "
                    "reject only exact collinearity)",
                    value_text(options.collinearity_vif)));
  std::string out;
  for (const auto& p : problems) out += (out.empty() ? "" : "; ") + p;
  return out;
}

double t_two_sided_p(double t, double df) {
  if (!(df > 0) || !std::isfinite(df))
    throw UserError(
        fmt::format("t_two_sided_p: df got {}, expected a finite value > 0", value_text(df)));
  if (std::isnan(t)) throw UserError("t_two_sided_p: t is NaN");
  if (std::isinf(t)) return 0.0;
  const boost::math::students_t dist(df);
  return std::min(1.0, 2.0 * boost::math::cdf(boost::math::complement(dist, std::abs(t))));
}

double f_upper_p(double f, double df1, double df2) {
  if (!(df1 > 0) || !(df2 > 0) || !std::isfinite(df1) || !std::isfinite(df2))
    throw UserError(
        fmt::format("f_upper_p: degrees of freedom got ({}, {}), expected finite "
                    "values > 0",
                    value_text(df1), value_text(df2)));
  if (!(f >= 0)) throw UserError(fmt::format("f_upper_p: F got {}, expected >= 0", value_text(f)));
  if (std::isinf(f)) return 0.0;
  return boost::math::cdf(boost::math::complement(boost::math::fisher_f(df1, df2), f));
}

double chi_squared_upper_p(double x, double df) {
  if (!(df > 0) || !std::isfinite(df))
    throw UserError(
        fmt::format("chi_squared_upper_p: df got {}, expected a finite value > 0", value_text(df)));
  if (!(x >= 0))
    throw UserError(
        fmt::format("chi_squared_upper_p: statistic got {}, expected >= 0", value_text(x)));
  if (std::isinf(x)) return 0.0;
  return boost::math::cdf(boost::math::complement(boost::math::chi_squared(df), x));
}

OneSampleTest shapiro_wilk(const std::vector<double>& x) {
  require_sample(x, kShapiroWilkMinN, "shapiro_wilk");
  if (x.size() > kShapiroWilkMaxN)
    throw UserError(
        fmt::format("shapiro_wilk: got {} values; the p approximation is validated for "
                    "3 to {} only",
                    x.size(), kShapiroWilkMaxN));
  const Check c = shapiro_wilk_check(x);
  if (!c.available) throw UserError("shapiro_wilk: all values are equal; W is undefined");
  return {c.statistic, c.p};
}

OneSampleTest jarque_bera(const std::vector<double>& x) {
  require_sample(x, 2, "jarque_bera");
  const Check c =
      jarque_bera_check(Eigen::Map<const VectorXd>(x.data(), static_cast<Index>(x.size())));
  if (!c.available) throw UserError("jarque_bera: all values are equal; skewness is undefined");
  return {c.statistic, c.p};
}

double durbin_watson(const std::vector<double>& residuals) {
  require_sample(residuals, 2, "durbin_watson");
  const Check c = durbin_watson_check(
      Eigen::Map<const VectorXd>(residuals.data(), static_cast<Index>(residuals.size())));
  if (!c.available)
    throw UserError("durbin_watson: all residuals are zero; the ratio is undefined");
  return c.statistic;
}

namespace {

// The residual checks of the fit (on the scale-free residuals: every check is invariant to the
// scale of y; all-zero residuals, a perfect fit, leave each one unavailable) and the warnings
// they and the design give.
void add_residual_checks(const VectorXd& e_s, const std::vector<std::vector<double>>& columns,
                         const std::vector<std::string>& names, const VectorXd& vif, Index worst,
                         double condition, bool perfect, const OlsOptions& options,
                         OlsResult* res) {
  const Index n = e_s.size(), k = vif.size();
  const double negligible_scaled = std::sqrt(kPerfectFitRss);
  OlsDiagnostics& d = res->diagnostics;
  d.max_vif = vif(worst);
  d.condition_number = condition;
  const Check jb = jarque_bera_check(e_s);
  d.jarque_bera = jb.statistic;
  d.jarque_bera_p = jb.p;
  d.jarque_bera_available = jb.available;
  const Check sw = shapiro_wilk_check(std::vector<double>(e_s.data(), e_s.data() + n));
  d.shapiro_wilk_w = sw.statistic;
  d.shapiro_wilk_p = sw.p;
  d.shapiro_wilk_available = sw.available;
  const Check bp = breusch_pagan_check(e_s, columns);
  d.breusch_pagan_lm = bp.statistic;
  d.breusch_pagan_p = bp.p;
  d.breusch_pagan_available = bp.available;
  const Check dw = durbin_watson_check(e_s);
  d.durbin_watson = dw.available ? dw.statistic : 2.0;
  d.durbin_watson_available = dw.available;

  auto& warn = res->warnings;
  const double alpha = options.alpha;
  if (perfect)
    warn.push_back(
        fmt::format("perfect fit (residuals within {:.0e} of the response's spread): "
                    "reported as exact, so sigma and the standard errors are 0, t and "
                    "F are infinite, and the residual checks are unavailable",
                    negligible_scaled));
  if (jb.available && jb.p < alpha)
    warn.push_back(fmt::format("residuals look non-normal: Jarque-Bera {} (p {} < alpha {})",
                               g4(jb.statistic), p_text(jb.p), alpha));
  if (sw.available && sw.p < alpha)
    warn.push_back(fmt::format("residuals look non-normal: Shapiro-Wilk W {} (p {} < alpha {})",
                               g4(sw.statistic), p_text(sw.p), alpha));
  if (res->n < kShapiroWilkMinN || res->n > kShapiroWilkMaxN)
    warn.push_back(fmt::format("Shapiro-Wilk not computed: n = {} is outside [{}, {}]", n,
                               kShapiroWilkMinN, kShapiroWilkMaxN));
  if (bp.available && bp.p < alpha)
    warn.push_back(fmt::format(
        "residuals look heteroscedastic: Breusch-Pagan (Koenker) LM {} (p {} < alpha {}); the "
        "estimates stay unbiased but the t and F p values are not exact",
        g4(bp.statistic), p_text(bp.p), alpha));
  // No exact DW bounds for arbitrary designs; far from 2 is a clear sign on its own.
  if (dw.available && (dw.statistic < 1.0 || dw.statistic > 3.0))
    warn.push_back(
        fmt::format("residuals look serially correlated: Durbin-Watson {} (outside "
                    "[1, 3]; 2 means uncorrelated)",
                    g4(dw.statistic)));
  for (Index j = 0; j < k; ++j)
    if (vif(j) > kVifWarning)
      warn.push_back(fmt::format("multicollinearity: VIF of '{}' is {} (> {})",
                                 names[static_cast<std::size_t>(j)], g4(vif(j)), kVifWarning));
}

// Data near the limits of double (|values| ~1e154 and up) can still overflow the unscaled
// sums of squares; say so rather than hand back infinities or NaN.
void require_finite(const OlsResult& res) {
  bool finite = std::isfinite(res.rss) && std::isfinite(res.tss) && std::isfinite(res.sigma) &&
                std::isfinite(res.r2) && std::isfinite(res.adj_r2) && !std::isnan(res.f);
  for (const auto& c : res.coefficients)
    finite = finite && std::isfinite(c.estimate) && std::isfinite(c.std_error) && !std::isnan(c.t);
  for (std::size_t i = 0; i < res.residuals.size(); ++i)
    finite = finite && std::isfinite(res.residuals[i]) && std::isfinite(res.fitted[i]);
  if (!finite)
    throw UserError(
        "ols: the data are too large in magnitude for double-precision sums of "
        "squares; rescale y or the columns (e.g. change units)");
}

// The problem ols() factorises: the columns centred (with an intercept) and scaled to unit norm,
// and y centred and scaled to unit norm.
struct ScaledProblem {
  MatrixXd z;            // unit-norm (centred) regressors
  VectorXd xbar, scale;  // the columns' means and norms after centring
  double ybar = 0;       // mean of y (0 without an intercept)
  VectorXd ys;           // (y - ybar) / sy
  double sy = 0;         // norm of y - ybar
};

// Centring removes the intercept from the factorisation (Frisch-Waugh) and, with unit-norm
// columns, leaves the QR the conditioning of the regressors' correlations rather than of their
// offsets and units: Longley's raw design has condition number 4.9e9, unit-norm columns 4.3e4,
// centred unit-norm columns 111.
ScaledProblem scale_problem(const std::vector<double>& y,
                            const std::vector<std::vector<double>>& columns, bool with_intercept) {
  const Index n = static_cast<Index>(y.size());
  ScaledProblem p;
  p.z = unit_columns(columns, with_intercept, &p.xbar, &p.scale);
  p.ybar = with_intercept ? mean_of(y) : 0.0;
  p.ys.resize(n);
  for (Index i = 0; i < n; ++i) p.ys(i) = y[static_cast<std::size_t>(i)] - p.ybar;
  p.sy = p.ys.stableNorm();
  p.ys /= p.sy;  // scale-free from here on; sums of squares cannot overflow
  return p;
}

// The pivoted QR of the unit-norm design and what its R tells of the conditioning.
struct Factorisation {
  Eigen::ColPivHouseholderQR<MatrixXd> qr;
  MatrixXd r;        // the k x k upper triangle of the QR
  double condition;  // largest over smallest singular value of the design
  VectorXd weakest;  // the design's weakest direction (smallest right singular vector)
};

// Throws UserError when the columns are exactly collinear.
Factorisation factorise(const MatrixXd& z, const std::vector<std::string>& names,
                        bool with_intercept) {
  const Index n = z.rows(), k = z.cols();
  Eigen::ColPivHouseholderQR<MatrixXd> qr(n, k);
  qr.setThreshold(kRankTolerance);
  qr.compute(z);
  const MatrixXd r = qr.matrixR().topLeftCorner(k, k).triangularView<Eigen::Upper>();
  // Singular values of the design are those of R; right singular vectors come back through P.
  // R is square, so the SVD needs no QR preconditioning of its own.
  const Eigen::JacobiSVD<MatrixXd, Eigen::NoQRPreconditioner> svd(r, Eigen::ComputeFullV);
  const VectorXd sv = svd.singularValues();
  const double condition = sv(k - 1) > 0 ? sv(0) / sv(k - 1) : kInf;
  const VectorXd weakest = qr.colsPermutation() * svd.matrixV().col(k - 1);

  if (qr.rank() < k)
    throw UserError(fmt::format(
        "ols: columns {} are exactly collinear{}: the {} regressors have rank {} (condition number "
        "{:.3g}); drop one of them",
        quoted_list(weakest_direction_columns(weakest, names)),
        with_intercept ? " (together with the intercept)" : "", k, qr.rank(), condition));
  return {qr, r, condition, weakest};
}

// M = P R^-1 and the regressors' variance inflation factors from it.
struct VarianceFactors {
  MatrixXd m;
  VectorXd vif;
  Index worst = 0;  // the regressor with the largest VIF
};

// Throws UserError when a VIF is above options.collinearity_vif.
VarianceFactors variance_factors(const Factorisation& f, const std::vector<std::string>& names,
                                 const OlsOptions& options) {
  const Index k = f.r.rows();
  // M = P R^-1: (Z'Z)^-1 = M M', so row j of M gives regressor j's variance factor (its VIF,
  // since Z'Z is the correlation matrix when centred) without ever forming Z'Z.
  const MatrixXd r_inv = f.r.triangularView<Eigen::Upper>().solve(MatrixXd::Identity(k, k));
  const MatrixXd m = f.qr.colsPermutation() * r_inv;
  VectorXd vif(k);
  for (Index j = 0; j < k; ++j) vif(j) = m.row(j).squaredNorm();
  Index worst = 0;
  vif.maxCoeff(&worst);
  if (vif(worst) > options.collinearity_vif)
    throw UserError(fmt::format(
        "ols: columns {} are nearly collinear: VIF of '{}' is {:.3g} (1 - R^2 = {:.2g} on the "
        "other regressors), above collinearity_vif = {:.3g}; condition number {:.3g}. Drop or "
        "combine one of them",
        quoted_list(weakest_direction_columns(f.weakest, names)),
        names[static_cast<std::size_t>(worst)], vif(worst), 1.0 / vif(worst),
        options.collinearity_vif, f.condition));
  return {m, vif, worst};
}

// The least-squares solution of the unit-norm problem and its sums of squares.
struct ScaledFit {
  VectorXd b;  // coefficients of the unit-norm problem
  double rss_s = 0, ess_s = 0, tss_s = 0;
  bool perfect = false;  // residuals are rounding noise of exact data
  double sigma_s = 0;
  VectorXd e_s;  // residuals (zero on a perfect fit)
};

ScaledFit fit_scaled(const Factorisation& f, const VarianceFactors& v, const VectorXd& ys,
                     Index df_resid) {
  const Index n = ys.size(), k = f.r.rows();
  ScaledFit fit;
  const VectorXd qty = f.qr.householderQ().transpose() * ys;
  fit.b = v.m * qty.head(k);  // coefficients of the unit-norm problem
  fit.rss_s = qty.tail(n - k).squaredNorm();
  fit.ess_s = qty.head(k).squaredNorm();
  fit.tss_s = ys.squaredNorm();
  // Residuals within 1e-12 of the response's spread are what rounding of exact data leaves
  // behind; the fit is then treated as exact (NIST certifies Wampler1's standard deviations
  // as 0) rather than reporting t ~ 1e16 that measures the arithmetic.
  fit.perfect = fit.rss_s <= kPerfectFitRss * fit.tss_s;
  fit.sigma_s = fit.perfect ? 0.0 : std::sqrt(fit.rss_s / static_cast<double>(df_resid));

  // Residuals as the projection onto the complement of the column space: consistent with rss
  // to rounding, unlike y - X beta, which cancels.
  fit.e_s = VectorXd::Zero(n);
  if (!fit.perfect) {
    fit.e_s.tail(n - k) = qty.tail(n - k);
    fit.e_s = f.qr.householderQ() * fit.e_s;
  }
  return fit;
}

// The coefficients in the units of the data: the intercept first (if any), then the columns.
std::vector<OlsCoefficient> coefficients(const ScaledProblem& p, const VarianceFactors& v,
                                         const ScaledFit& fit,
                                         const std::vector<std::string>& names,
                                         const OlsOptions& options, Index df_resid) {
  const bool with_intercept = options.intercept;
  const bool perfect = fit.perfect;
  const Index n = p.ys.size(), k = v.vif.size();
  const VectorXd& b = fit.b;
  const double sy = p.sy, sigma_s = fit.sigma_s;
  std::vector<OlsCoefficient> out;

  // On a perfect fit a coefficient is either exactly determined and nonzero (t = +-inf) or
  // zero up to the same rounding that was forgiven in the residuals (t = 0).
  auto add_coefficient = [&](std::string name, double estimate, double std_error, double t,
                             bool negligible, double vif_value) {
    OlsCoefficient c;
    c.name = std::move(name);
    c.estimate = estimate;
    c.std_error = std_error;
    c.vif = vif_value;
    if (perfect)
      c.t = negligible ? 0.0 : std::copysign(kInf, estimate);
    else
      c.t = t;
    c.p = t_two_sided_p(c.t, static_cast<double>(df_resid));
    c.significant = c.p < options.alpha;
    out.push_back(std::move(c));
  };
  const double negligible_scaled = std::sqrt(kPerfectFitRss);

  std::vector<double> beta(static_cast<std::size_t>(k));
  for (Index j = 0; j < k; ++j) beta[static_cast<std::size_t>(j)] = sy * b(j) / p.scale(j);
  if (with_intercept) {
    // Var(b0) = sigma^2 (1/n + xbar' (Xc'Xc)^-1 xbar), the quadratic form as a squared norm.
    const VectorXd w = p.xbar.cwiseQuotient(p.scale);
    const double factor =
        std::sqrt(1.0 / static_cast<double>(n) + (v.m.transpose() * w).squaredNorm());
    double b0 = p.ybar;
    double magnitude = std::abs(p.ybar) + sy / std::sqrt(static_cast<double>(n));
    for (Index j = 0; j < k; ++j) {
      b0 -= beta[static_cast<std::size_t>(j)] * p.xbar(j);
      magnitude += std::abs(beta[static_cast<std::size_t>(j)] * p.xbar(j));
    }
    const double se0 = sy * sigma_s * factor;
    add_coefficient(kInterceptName, b0, se0, perfect ? 0.0 : b0 / se0,
                    std::abs(b0) <= negligible_scaled * magnitude, 0.0);
  }
  for (Index j = 0; j < k; ++j) {
    const double factor = v.m.row(j).norm();
    add_coefficient(names[static_cast<std::size_t>(j)], beta[static_cast<std::size_t>(j)],
                    sy * sigma_s * factor / p.scale(j), perfect ? 0.0 : b(j) / (sigma_s * factor),
                    std::abs(b(j)) <= negligible_scaled, v.vif(j));
  }
  return out;
}

}  // namespace

OlsResult ols(const std::vector<double>& y, const std::vector<std::vector<double>>& columns,
              const std::vector<std::string>& names, const OlsOptions& options) {
  check_inputs(y, columns, names, options);
  const bool with_intercept = options.intercept;
  const Index n = static_cast<Index>(y.size());
  const Index k = static_cast<Index>(columns.size());
  const Index params = k + (with_intercept ? 1 : 0);
  const Index df_resid = n - params;

  const ScaledProblem p = scale_problem(y, columns, with_intercept);
  const Factorisation f = factorise(p.z, names, with_intercept);
  const VarianceFactors v = variance_factors(f, names, options);
  const ScaledFit fit = fit_scaled(f, v, p.ys, df_resid);
  const bool perfect = fit.perfect;
  const double sy = p.sy, rss_s = fit.rss_s, tss_s = fit.tss_s;

  OlsResult res;
  res.n = static_cast<std::size_t>(n);
  res.df_model = static_cast<std::size_t>(k);
  res.df_resid = static_cast<std::size_t>(df_resid);
  res.intercept = with_intercept;
  res.alpha = options.alpha;
  res.coefficients = coefficients(p, v, fit, names, options, df_resid);

  res.rss = perfect ? 0.0 : sy * sy * rss_s;
  res.tss = sy * sy * tss_s;
  res.sigma = sy * fit.sigma_s;
  res.r2 = perfect ? 1.0 : std::clamp(1.0 - rss_s / tss_s, 0.0, 1.0);
  res.adj_r2 = 1.0 - (1.0 - res.r2) * static_cast<double>(n - (with_intercept ? 1 : 0)) /
                         static_cast<double>(df_resid);
  res.f = perfect ? kInf
                  : (fit.ess_s / static_cast<double>(k)) / (rss_s / static_cast<double>(df_resid));
  res.f_p = f_upper_p(res.f, static_cast<double>(k), static_cast<double>(df_resid));

  res.residuals.resize(static_cast<std::size_t>(n));
  res.fitted.resize(static_cast<std::size_t>(n));
  for (Index i = 0; i < n; ++i) {
    const auto ui = static_cast<std::size_t>(i);
    res.residuals[ui] = sy * fit.e_s(i);
    res.fitted[ui] = y[ui] - res.residuals[ui];
  }

  add_residual_checks(fit.e_s, columns, names, v.vif, v.worst, f.condition, perfect, options, &res);
  require_finite(res);
  return res;
}

std::string OlsResult::brief() const {
  std::string s = fmt::format(
      "OLS: {} observations, {} regressors{}, df_resid {}; R^2 {:.4f} (adjusted {:.4f}); F({}, {}) "
      "{} "
      "(p {}{}); sigma {}.",
      n, df_model, intercept ? " + intercept" : " (no intercept)", df_resid, r2, adj_r2, df_model,
      df_resid, g4(f), p_text(f_p), f_p < alpha ? ", significant" : ", not significant", g4(sigma));
  s += fmt::format(" Coefficients (* significant at alpha {}):", alpha);
  for (std::size_t i = 0; i < coefficients.size(); ++i) {
    const auto& c = coefficients[i];
    s += fmt::format("{} {} {:.3e}{} (t {}, p {})", i == 0 ? "" : ";", c.name, c.estimate,
                     c.significant ? "*" : "",
                     std::isinf(c.t) ? value_text(c.t) : fmt::format("{:.2f}", c.t), p_text(c.p));
  }
  const auto& d = diagnostics;
  auto test = [](bool available, const std::string& text) {
    return available ? text : std::string("n/a");
  };
  s += fmt::format(
      ". Residual checks: Jarque-Bera {}, Shapiro-Wilk {}, Breusch-Pagan (Koenker) {}, "
      "Durbin-Watson {}; max VIF {}, condition number {}.",
      test(d.jarque_bera_available,
           fmt::format("{} (p {})", g4(d.jarque_bera), p_text(d.jarque_bera_p))),
      test(d.shapiro_wilk_available,
           fmt::format("W {} (p {})", g4(d.shapiro_wilk_w), p_text(d.shapiro_wilk_p))),
      test(d.breusch_pagan_available,
           fmt::format("{} (p {})", g4(d.breusch_pagan_lm), p_text(d.breusch_pagan_p))),
      test(d.durbin_watson_available, g4(d.durbin_watson)), g4(d.max_vif), g4(d.condition_number));
  if (!warnings.empty()) {
    s += " Warnings:";
    for (std::size_t i = 0; i < warnings.size(); ++i) s += (i == 0 ? " " : "; ") + warnings[i];
    s += ".";
  }
  return s;
}

}  // namespace driftlab::eval
