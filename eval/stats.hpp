// Descriptive statistics shared by every evaluation table.
//
// Conventions (documented in docs/evaluation.md): `std_population` divides by n (as
// evo's APE/RPE `std`, numpy ddof=0); `sd_sample` divides by n - 1 (as the
// river paper's Table 1 "SD" and any statistics package). `rmse` is
// sqrt(mean(x^2)), river paper Eq. (14).
#pragma once

#include <cstddef>
#include <vector>

namespace driftlab::eval {

struct Summary {
  std::size_t n = 0;
  double min = 0;
  double max = 0;
  double mean = 0;
  double median = 0;
  double rmse = 0;
  double std_population = 0;  // divides by n
  double sd_sample = 0;       // divides by n - 1 (0 when n < 2)
  double sse = 0;             // sum of squares
};

/// Summary of `values` (any order). An empty input gives n = 0 and zeros.
/// Uses a two-pass (mean first) computation so that large offsets do not
/// cancel; the median averages the two middle values for even n.
Summary summarize(const std::vector<double>& values);

}  // namespace driftlab::eval
