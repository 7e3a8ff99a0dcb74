#include "gate/paired.hpp"

#include <boost/math/distributions/normal.hpp>
#include <boost/math/distributions/students_t.hpp>
#include <tuple>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/error.hpp"

namespace driftlab::gate {
namespace {

// Mid-ranks of |d| (1-based; ties share the mean of their ranks) and the tie term sum(t^3 - t).
std::vector<double> mid_ranks(const std::vector<double>& abs_d, double* tie_term) {
  std::vector<std::size_t> order(abs_d.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](auto i, auto j) { return abs_d[i] < abs_d[j]; });
  std::vector<double> rank(abs_d.size());
  *tie_term = 0;
  for (std::size_t i = 0; i < order.size();) {
    std::size_t j = i;
    while (j + 1 < order.size() && abs_d[order[j + 1]] == abs_d[order[i]]) ++j;
    const double t = static_cast<double>(j - i + 1);
    for (std::size_t k = i; k <= j; ++k) rank[order[k]] = (static_cast<double>(i + j) + 2) / 2;
    *tie_term += t * t * t - t;
    i = j + 1;
  }
  return rank;
}

// The null distribution of W+ for n untied ranks: counts[w] of the 2^n sign assignments.
std::vector<double> signed_rank_counts(std::size_t n) {
  const std::size_t max_w = n * (n + 1) / 2;
  std::vector<double> counts(max_w + 1, 0.0);
  counts[0] = 1;
  for (std::size_t r = 1; r <= n; ++r)
    for (std::size_t w = max_w; w >= r; --w) counts[w] += counts[w - r];
  return counts;
}

}  // namespace

SignedRankTest wilcoxon_signed_rank(const std::vector<double>& d) {
  std::vector<double> abs_d;
  std::vector<bool> positive;
  for (const double x : d) {
    DRIFTLAB_DEMAND_MSG(std::isfinite(x), "wilcoxon_signed_rank: a non-finite difference");
    if (x == 0) continue;
    abs_d.push_back(std::abs(x));
    positive.push_back(x > 0);
  }
  SignedRankTest t;
  t.n = abs_d.size();
  if (t.n == 0) return t;
  double tie_term = 0;
  const std::vector<double> rank = mid_ranks(abs_d, &tie_term);
  for (std::size_t i = 0; i < t.n; ++i)
    if (positive[i]) t.w_plus += rank[i];
  const double n = static_cast<double>(t.n);
  if (tie_term == 0 && t.n <= kExactWilcoxonPairs) {
    const std::vector<double> counts = signed_rank_counts(t.n);
    const double total = std::ldexp(1.0, static_cast<int>(t.n));
    const auto w = static_cast<std::size_t>(std::lround(t.w_plus));
    double at_least = 0, at_most = 0;
    for (std::size_t k = 0; k < counts.size(); ++k) (k >= w ? at_least : at_most) += counts[k];
    at_most += counts[w];
    t.p_greater = at_least / total;
    t.p_less = at_most / total;
    t.exact = true;
    return t;
  }
  const double mean = n * (n + 1) / 4;
  const double var = n * (n + 1) * (2 * n + 1) / 24 - tie_term / 48;
  if (var <= 0) return t;
  const boost::math::normal z;
  const double sd = std::sqrt(var);
  t.p_greater = boost::math::cdf(boost::math::complement(z, (t.w_plus - mean - 0.5) / sd));
  t.p_less = boost::math::cdf(z, (t.w_plus - mean + 0.5) / sd);
  return t;
}

std::pair<double, double> confidence_interval_95(double mean, double sd, std::size_t n) {
  if (n < 2) return {mean, mean};
  const boost::math::students_t t(static_cast<double>(n - 1));
  const double half = boost::math::quantile(t, 0.975) * sd / std::sqrt(static_cast<double>(n));
  return {mean - half, mean + half};
}

PairedChange paired_change(const std::vector<double>& a, const std::vector<double>& b) {
  DRIFTLAB_DEMAND_MSG(a.size() == b.size(), "paired_change: sides of different sizes");
  PairedChange c;
  c.n = a.size();
  if (c.n == 0) return c;
  std::vector<double> d(c.n);
  for (std::size_t i = 0; i < c.n; ++i) {
    d[i] = b[i] - a[i];
    c.mean_a += a[i];
    c.mean_b += b[i];
  }
  const double n = static_cast<double>(c.n);
  c.mean_a /= n;
  c.mean_b /= n;
  c.diff = c.mean_b - c.mean_a;
  c.diff_lo = c.diff_hi = c.diff;
  if (c.n >= 2) {
    double ss = 0;
    for (const double x : d) ss += (x - c.diff) * (x - c.diff);
    std::tie(c.diff_lo, c.diff_hi) = confidence_interval_95(c.diff, std::sqrt(ss / (n - 1)), c.n);
  }
  if (c.mean_a != 0) {
    const double s = std::abs(c.mean_a);
    c.rel = c.diff / s;
    c.rel_lo = c.diff_lo / s;
    c.rel_hi = c.diff_hi / s;
  }
  c.test = wilcoxon_signed_rank(d);
  return c;
}

}  // namespace driftlab::gate
