// Paired comparisons (gate/paired.hpp) against independent expectations: the exact signed-rank
// p-value against enumerating every sign pattern, the normal approximation with ties against
// the same enumeration, the t-interval against a hand computation; and the gate's paired
// verdicts (gate.hpp): a change beyond the smallest effect in most pairs regresses, one below
// it or without a direction passes, a lost pair fails, and a baseline with pairs reads back as
// written.
#include "gate/paired.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>

#include "core/atomic_file.hpp"
#include "gate/gate.hpp"

namespace driftlab::gate {
namespace {

// P(W+ >= w) by enumerating all 2^n sign patterns over the given ranks.
double enumerated_p_greater(const std::vector<double>& ranks, double w) {
  const std::size_t n = ranks.size();
  std::size_t hits = 0;
  for (std::uint64_t signs = 0; signs < (1ULL << n); ++signs) {
    double sum = 0;
    for (std::size_t i = 0; i < n; ++i)
      if (signs >> i & 1) sum += ranks[i];
    hits += sum >= w - 1e-9 ? 1 : 0;
  }
  return static_cast<double>(hits) / static_cast<double>(1ULL << n);
}

TEST(SignedRank, ExactPValuesAreThoseOfEverySignPattern) {
  std::mt19937 gen(5);
  std::normal_distribution<double> noise(0.3, 1.0);
  for (std::size_t n = 1; n <= 14; ++n) {
    std::vector<double> d(n);
    for (auto& x : d) x = noise(gen);
    const SignedRankTest t = wilcoxon_signed_rank(d);
    ASSERT_TRUE(t.exact);
    std::vector<double> ranks(n);
    for (std::size_t i = 0; i < n; ++i) ranks[i] = static_cast<double>(i + 1);
    EXPECT_NEAR(t.p_greater, enumerated_p_greater(ranks, t.w_plus), 1e-12) << n;
    // P(W+ <= w) = P(W+ >= n(n+1)/2 - w) by symmetry.
    const double total = static_cast<double>(n * (n + 1)) / 2;
    EXPECT_NEAR(t.p_less, enumerated_p_greater(ranks, total - t.w_plus), 1e-12) << n;
  }
  // The textbook value: n = 10, W+ = 45 (W- = 10) has P = 0.042 (one-sided).
  const std::vector<double> d = {-1, -2, -3, -4, 5, 6, 7, 8, 9, 10};  // W- = 1 + 2 + 3 + 4 = 10
  EXPECT_NEAR(wilcoxon_signed_rank(d).p_greater, 0.0420, 0.0005);
}

TEST(SignedRank, ZerosAreDroppedAndTiesUseTheNormalApproximation) {
  EXPECT_EQ(wilcoxon_signed_rank({0, 0, 0}).n, 0u);
  EXPECT_EQ(wilcoxon_signed_rank({0, 0, 0}).p_greater, 1.0);
  // Ties: mid-ranks, normal approximation; compared with the enumeration over the mid-ranks.
  const std::vector<double> d = {0.5, 0.5, -0.5, 1, 1, 2, 2, 2, -3, 4, 5, 0, 6, -6, 7, 8};
  const SignedRankTest t = wilcoxon_signed_rank(d);
  EXPECT_FALSE(t.exact);
  EXPECT_EQ(t.n, 15u);
  const std::vector<double> ranks = {2, 2, 2, 4.5, 4.5, 7, 7, 7, 9, 10, 11, 12.5, 12.5, 14, 15};
  EXPECT_NEAR(t.p_greater, enumerated_p_greater(ranks, t.w_plus), 0.01);
}

TEST(PairedChange, MeanDifferenceAndItsStudentInterval) {
  const PairedChange c = paired_change({10, 10, 10, 10}, {11, 12, 13, 14});
  EXPECT_EQ(c.n, 4u);
  EXPECT_DOUBLE_EQ(c.diff, 2.5);
  // sd of {1,2,3,4} = 1.2910; t(3, 0.975) = 3.182446; half-width 3.182446 * 1.2910 / 2.
  const double half = 3.182446305284263 * std::sqrt(5.0 / 3.0) / 2;
  EXPECT_NEAR(c.diff_lo, 2.5 - half, 1e-9);
  EXPECT_NEAR(c.diff_hi, 2.5 + half, 1e-9);
  EXPECT_NEAR(c.rel, 0.25, 1e-12);
  EXPECT_NEAR(c.test.p_greater, 1.0 / 16, 1e-12);  // all four up: the smallest exact p for n = 4
}

// A baseline metric of `n` pairs with values 1..n (lower is better).
Baseline paired_baseline(std::size_t n) {
  BaselineMetric m;
  m.key = "algorithms.sparse.pairs.p_m_per_m_sections";
  for (std::size_t i = 0; i < n; ++i)
    m.pairs.push_back({"p0000-r00/" + std::to_string(i), 1.0 + i});
  m.baseline = pairs_mean(m.pairs);
  Baseline b;
  b.metrics.push_back(m);
  return b;
}

nlohmann::json results_with(const Baseline& b,
                            const std::function<double(std::size_t, double)>& f) {
  nlohmann::json pairs = nlohmann::json::object();
  const auto& p = b.metrics[0].pairs;
  for (std::size_t i = 0; i < p.size(); ++i) pairs[p[i].id] = f(i, p[i].value);
  nlohmann::json r;
  r["algorithms"]["sparse"]["pairs"]["p_m_per_m_sections"] = pairs;
  return r;
}

Verdict verdict(const Baseline& b, const std::function<double(std::size_t, double)>& f) {
  return check_baseline(b, results_with(b, f), "results").checks.at(0).verdict;
}

TEST(PairedGate, DecidesByTheTestAndTheSmallestEffect) {
  const Baseline b = paired_baseline(40);
  EXPECT_EQ(verdict(b, [](std::size_t, double v) { return v; }), Verdict::kPass);
  EXPECT_EQ(verdict(b, [](std::size_t, double v) { return v * 1.2; }), Verdict::kRegressed);
  EXPECT_EQ(verdict(b, [](std::size_t, double v) { return v * 0.8; }), Verdict::kImproved);
  // Every pair worse, but by 3 %: below the smallest effect that counts.
  EXPECT_EQ(verdict(b, [](std::size_t, double v) { return v * 1.03; }), Verdict::kPass);
  // Changes of +-30 % without a direction (alternating): not significant.
  EXPECT_EQ(verdict(b, [](std::size_t i, double v) { return v * (i % 2 ? 1.3 : 0.7); }),
            Verdict::kPass);
  // A pair the results lack fails the metric, whatever the others do.
  const GateResult lost = check_baseline(
      b,
      [&] {
        nlohmann::json r = results_with(b, [](std::size_t, double v) { return v; });
        r["algorithms"]["sparse"]["pairs"]["p_m_per_m_sections"].erase("p0000-r00/7");
        return r;
      }(),
      "results");
  EXPECT_EQ(lost.checks[0].verdict, Verdict::kMissing);
  EXPECT_NE(lost.checks[0].note.find("1 of 40 pairs have no value"), std::string::npos)
      << lost.checks[0].note;
}

TEST(PairedGate, ABaselineWithPairsReadsBackAsWrittenAndUpdates) {
  Baseline b = paired_baseline(5);
  b.description = "paired";
  const auto file =
      std::filesystem::temp_directory_path() / ("driftlab_paired_" + std::to_string(::getpid()));
  write_file_atomic(file, baseline_json(b));
  const Baseline read = load_baseline(file);
  ASSERT_EQ(read.metrics.size(), 1u);
  ASSERT_EQ(read.metrics[0].pairs.size(), 5u);
  for (std::size_t i = 0; i < 5; ++i) {
    EXPECT_EQ(read.metrics[0].pairs[i].id, b.metrics[0].pairs[i].id);
    EXPECT_EQ(read.metrics[0].pairs[i].value, b.metrics[0].pairs[i].value);
  }
  EXPECT_EQ(read.metrics[0].min_effect, 0.05);
  EXPECT_EQ(read.metrics[0].alpha, 0.01);
  const GateResult r =
      check_baseline(read, results_with(read, [](std::size_t, double v) { return 2 * v; }), file);
  const Baseline up = updated_baseline(read, r);
  EXPECT_EQ(up.metrics[0].pairs[4].value, 10.0);
  EXPECT_EQ(*up.metrics[0].baseline, 6.0);
  std::filesystem::remove(file);
}

}  // namespace
TEST(Paired, ConfidenceIntervalUsesStudentsT) {
  // t quantiles 0.975 with 1 and 4 degrees of freedom: 12.706204736174698, 2.7764451051977934.
  auto [lo2, hi2] = confidence_interval_95(10.0, 1.0, 2);
  EXPECT_NEAR(hi2 - 10.0, 12.706204736174698 / std::sqrt(2.0), 1e-9);
  EXPECT_NEAR(10.0 - lo2, 12.706204736174698 / std::sqrt(2.0), 1e-9);
  auto [lo5, hi5] = confidence_interval_95(0.0, 2.0, 5);
  EXPECT_NEAR(hi5, 2.7764451051977934 * 2.0 / std::sqrt(5.0), 1e-9);
  EXPECT_NEAR(lo5, -hi5, 1e-12);
  auto [lo1, hi1] = confidence_interval_95(3.0, 0.0, 1);
  EXPECT_EQ(lo1, 3.0);
  EXPECT_EQ(hi1, 3.0);
}

}  // namespace driftlab::gate
