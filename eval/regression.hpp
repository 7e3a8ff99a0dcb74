// Ordinary least squares multiple linear regression with the inference and residual checks of
// river paper Section 2.4 (Kriechbaumer 2015): Eq. (13) fitted by OLS, t tests of the
// coefficients and an F test of the model at alpha = 0.05, R^2 (Table 3), and checks of the OLS
// assumptions: normal residuals (Jarque-Bera, Shapiro-Wilk), homoscedasticity (Breusch-Pagan),
// uncorrelated residuals (Durbin-Watson) and no multicollinearity (VIF).
//
// Numerics: the regressors are centred (when there is an intercept) and scaled to unit norm, then
// factored by a column-pivoted Householder QR; the normal equations are never formed. Every
// certified value of NIST StRD Longley is reproduced to 13.8 significant digits or more.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace driftlab::eval {

/// Options of ols(). Check with validate(); ols() throws UserError on invalid options.
struct OlsOptions {
  /// Fit beta_0 (river paper Eq. (13) has one). Without it, R^2 and F are uncentred (about
  /// zero, as R's lm does for models without an intercept) and VIFs are uncentred too.
  bool intercept = true;
  /// Significance level of the coefficient t tests, the F test and the residual-check warnings;
  /// in (0, 1). The river paper uses 0.05.
  double alpha = 0.05;
  /// Largest variance inflation factor accepted: a regressor with VIF above it (R_j^2 of that
  /// regressor on the others above 1 - 1/VIF) is rejected as collinear with UserError, naming the
  /// columns. At the default, 1e6, only a millionth of the regressor's variance is its own: its
  /// standard error is a thousand times what an uncorrelated design would give, and the solve
  /// loses about log10(sqrt(VIF)) = 3 digits to it; no covariate of Eq. (13) is worth keeping
  /// then. (The rule-of-thumb VIF > 10 only adds a warning.) A VIF threshold rather than a
  /// condition number, because it names one regressor and reads as that regressor's R^2.
  /// Must be > 1; +infinity rejects only exactly collinear regressors.
  double collinearity_vif = 1e6;
};

/// "" when usable, else one "field: got V, expected E" per bad field, joined by "; ".
std::string validate(const OlsOptions& options);

/// One row of river paper Table 3.
struct OlsCoefficient {
  std::string name;          ///< "Intercept" or the regressor's name
  double estimate = 0;       ///< beta_j
  double std_error = 0;      ///< sqrt of the diagonal of sigma^2 (X'X)^-1
  double t = 0;              ///< estimate / std_error (see OlsResult on a perfect fit)
  double p = 1;              ///< two-sided p of the t test, df_resid degrees of freedom
  double vif = 0;            ///< variance inflation factor 1 / (1 - R_j^2); 0 for the intercept
  bool significant = false;  ///< p < alpha
};

/// Checks of the OLS assumptions on the residuals, in the order the rows were given.
/// A test that cannot be computed (e.g. all residuals zero) has available = false, statistic 0
/// (Durbin-Watson: the neutral 2) and p 1.
struct OlsDiagnostics {
  /// n/6 (S^2 + (K-3)^2/4) from the residuals' population skewness S and kurtosis K;
  /// asymptotically chi-square with 2 degrees of freedom.
  double jarque_bera = 0, jarque_bera_p = 1;
  bool jarque_bera_available = false;
  /// Royston's (1992, 1995; AS R94) approximation, as R's shapiro.test. Available for
  /// 3 <= n <= 5000 only: outside, the p approximation is not validated.
  double shapiro_wilk_w = 0, shapiro_wilk_p = 1;
  bool shapiro_wilk_available = false;
  /// Koenker's studentised Breusch-Pagan test: LM = n R^2 of the regression of e^2 on the
  /// regressors and a constant (a constant is added even without an intercept in the model),
  /// chi-square with (rank of the centred regressors) degrees of freedom. Unlike the original
  /// Breusch-Pagan statistic it does not assume normal residuals, which the paper's errors are not
  /// guaranteed to be.
  double breusch_pagan_lm = 0, breusch_pagan_p = 1;
  bool breusch_pagan_available = false;
  /// sum (e_i - e_{i-1})^2 / sum e_i^2 in row order (sections along the track): about 2 for
  /// uncorrelated residuals, towards 0 for positive and 4 for negative lag-one correlation.
  double durbin_watson = 2;
  bool durbin_watson_available = false;
  /// Largest VIF of the regressors (the intercept excluded).
  double max_vif = 0;
  /// 2-norm condition number of the regressor matrix after centring (with an intercept) and
  /// scaling each column to unit norm: what limits the accuracy of the coefficients.
  double condition_number = 1;
};

/// Summary of one fit (Ceres-style summary object; brief() prints it).
///
/// Perfect fit: when the residuals are within 1e-12 of the response's spread (1 - R^2 <= 1e-24,
/// what rounding leaves of an exact linear relation), the fit is reported as exact: rss, sigma,
/// every standard error and every residual are 0, R^2 is 1, F is +infinity with f_p = 0, t is
/// +-infinity (p = 0, significant) for each coefficient whose contribution exceeds that same
/// 1e-12 and 0 (p = 1) for the rest, the residual checks are unavailable, and a warning says so.
/// Nothing in the result is ever NaN.
struct OlsResult {
  std::vector<OlsCoefficient> coefficients;  ///< intercept first (if any), then columns in order
  std::size_t n = 0;                         ///< observations (sections, or runs)
  std::size_t df_model = 0;                  ///< regressors, intercept excluded
  std::size_t df_resid = 0;                  ///< n - parameters
  bool intercept = true;                     ///< as in the options
  double alpha = 0.05;                       ///< significance level the flags and warnings used
  double r2 = 0;                             ///< 1 - rss / tss
  double adj_r2 = 0;                         ///< 1 - (1 - r2) (n - intercept) / df_resid
  double f = 0;                              ///< (ess / df_model) / (rss / df_resid)
  double f_p = 1;                            ///< upper tail of F(df_model, df_resid)
  double sigma = 0;                          ///< residual standard deviation sqrt(rss / df_resid)
  double rss = 0;                            ///< residual sum of squares
  double tss = 0;  ///< total sum of squares (about the mean with an intercept, else zero)
  OlsDiagnostics diagnostics;
  std::vector<double> residuals;  ///< y - fitted, in row order
  std::vector<double> fitted;
  /// Assumption checks that failed at alpha, VIF > 10, a perfect fit, unavailable tests.
  std::vector<std::string> warnings;

  /// One paragraph: fit size, R^2, F test, every coefficient with t and p (significant ones
  /// starred, as in Table 3), the residual checks, and the warnings.
  std::string brief() const;
};

/// Fits y = beta_0 + sum_j beta_j columns[j] + u by least squares (river paper Eq. (13)).
/// `columns[j]` holds regressor j for every row; `names[j]` names it in results and messages.
/// Throws UserError, naming the column and row, on: invalid options; no regressors; names that
/// are empty, duplicated or "Intercept" (with an intercept); columns whose length differs from
/// y's; NaN or infinite values; fewer rows than parameters + 1; a constant column with an
/// intercept (or an all-zero column); a constant response (all zeros without an intercept);
/// exactly or nearly collinear regressors (VIF above options.collinearity_vif), naming the
/// columns involved, the VIF and the condition number.
OlsResult ols(const std::vector<double>& y, const std::vector<std::vector<double>>& columns,
              const std::vector<std::string>& names, const OlsOptions& options = {});

/// Statistic and p value of a one-sample test.
struct OneSampleTest {
  double statistic = 0;
  double p = 1;
};

/// Royston's Shapiro-Wilk W and its p value (AS R94, as R's shapiro.test). Throws UserError
/// unless 3 <= x.size() <= 5000, and when all values are equal or any is not finite.
OneSampleTest shapiro_wilk(const std::vector<double>& x);
/// Jarque-Bera statistic and its chi-square(2) p value. Throws UserError for fewer than 2
/// values, all values equal, or a non-finite value.
OneSampleTest jarque_bera(const std::vector<double>& x);
/// Durbin-Watson statistic of residuals in the given order. Throws UserError for fewer than 2
/// values, all zero, or a non-finite value.
double durbin_watson(const std::vector<double>& residuals);

/// Two-sided p of a t statistic with df > 0 degrees of freedom; t = +-infinity gives 0.
double t_two_sided_p(double t, double df);
/// Upper-tail p of an F statistic >= 0 with (df1, df2) degrees of freedom; +infinity gives 0.
double f_upper_p(double f, double df1, double df2);
/// Upper-tail p of a chi-square statistic >= 0 with df degrees of freedom.
double chi_squared_upper_p(double x, double df);

}  // namespace driftlab::eval
