// Paired comparisons (docs/sweeps.md, "Paired comparisons"): runs are deterministic, so a baseline
// and a change can be compared pair by pair (the same job, or the same section of the same job)
// instead of mean against mean. Used by the gate (`driftlab regress`, a metric with pairs) and by
// `driftlab sweep merge` (VOs side by side on the same seeds).
//
// For pairs (a_i, b_i) and differences d_i = b_i - a_i:
//   - the mean difference with its 95 % confidence interval (Student's t, n - 1 degrees of
//     freedom), and the same relative to the mean of a (the change in per cent of the baseline);
//   - one-sided Wilcoxon signed-rank p-values (Wilcoxon 1945): zero differences dropped,
//     tied |d| given their mid-ranks; exact (the null distribution of W+ by counting) for up to
//     kExactWilcoxonPairs untied pairs, else the normal approximation with the tie-corrected
//     variance n(n+1)(2n+1)/24 - sum(t^3 - t)/48 and a continuity correction of 1/2.
#pragma once

#include <cstddef>
#include <utility>
#include <vector>

namespace driftlab::gate {

/// Up to this many pairs without ties, the signed-rank p-value is exact.
constexpr std::size_t kExactWilcoxonPairs = 30;

struct SignedRankTest {
  std::size_t n = 0;     ///< non-zero differences
  double w_plus = 0;     ///< sum of the ranks of the positive differences
  double p_greater = 1;  ///< P(W+ >= w_plus) under H0: the differences lean positive
  double p_less = 1;     ///< P(W+ <= w_plus) under H0: they lean negative
  bool exact = false;
};

/// The Wilcoxon signed-rank test of `d` (non-finite values are an error of the caller).
SignedRankTest wilcoxon_signed_rank(const std::vector<double>& d);

struct PairedChange {
  std::size_t n = 0;                          ///< pairs
  double mean_a = 0, mean_b = 0;              ///< means of the two sides over the pairs
  double diff = 0, diff_lo = 0, diff_hi = 0;  ///< mean of b - a and its 95 % interval
  double rel = 0, rel_lo = 0, rel_hi = 0;     ///< the same over |mean_a| (0 when mean_a is 0)
  SignedRankTest test;
};

/// Two-sided 95% confidence interval of a mean from n samples with sample
/// standard deviation sd (Student's t with n - 1 degrees of freedom);
/// {mean, mean} when n < 2. The gate's paired differences and the sweep
/// merge's replicate means both use it.
std::pair<double, double> confidence_interval_95(double mean, double sd, std::size_t n);

/// Compares b against a, pair by pair (a[i] with b[i]; equal sizes).
PairedChange paired_change(const std::vector<double>& a, const std::vector<double>& b);

}  // namespace driftlab::gate
