// Replica statistics against values computed by hand or read from printed tables (Student t
// quantiles as in any statistics table; the Welch and fractional-dof values from a separate
// Simpson integration of the t density, not from the incomplete beta function under test).
#include <gtest/gtest.h>

#include <cmath>

#include "tomodem/pipeline/stats.hpp"

namespace st = tomodem::pipeline::stats;

TEST(Stats, IncompleteBetaMatchesClosedForms) {
  EXPECT_NEAR(st::incomplete_beta(1, 1, 0.3), 0.3, 1e-14);  // uniform
  // I_x(2, 3) = P(Binomial(4, x) >= 2) = 1 - (1-x)^4 - 4x(1-x)^3 = 0.5248 at x = 0.4
  EXPECT_NEAR(st::incomplete_beta(2, 3, 0.4), 0.5248, 1e-13);
  EXPECT_EQ(st::incomplete_beta(2, 3, 0), 0);
  EXPECT_EQ(st::incomplete_beta(2, 3, 1), 1);
}

TEST(Stats, TDistributionMatchesClosedForms) {
  EXPECT_NEAR(st::t_cdf(1, 1), 0.75, 1e-13);                                 // Cauchy: 1/2 + atan(1)/pi
  EXPECT_NEAR(st::t_cdf(2, 2), 0.5 + 2 / (2 * std::sqrt(6.0)), 1e-13);      // dof 2: 1/2 + t/(2 sqrt(2+t^2))
  EXPECT_NEAR(st::t_cdf(-2, 2), 0.5 - 2 / (2 * std::sqrt(6.0)), 1e-13);
  EXPECT_NEAR(st::t_cdf(1.959964, INFINITY), 0.975, 1e-6);
}

TEST(Stats, TQuantilesMatchTheTable) {
  // Two-sided 95 % (one-sided 0.975) column of the table, three decimals.
  const std::pair<double, double> table[] = {{1, 12.706}, {2, 4.303}, {3, 3.182}, {4, 2.776}, {5, 2.571},
                                             {10, 2.228}, {20, 2.086}, {30, 2.042}, {120, 1.980}};
  for (const auto& [dof, t] : table) EXPECT_NEAR(st::t_quantile(0.975, dof), t, 5e-4) << "dof " << dof;
  EXPECT_NEAR(st::t_quantile(0.95, 5), 2.015, 5e-4);
  EXPECT_NEAR(st::t_quantile(0.995, 20), 2.845, 5e-4);
  EXPECT_NEAR(st::t_quantile(0.025, 4), -2.776, 5e-4);
  EXPECT_NEAR(st::t_quantile(0.975, INFINITY), 1.960, 5e-4);
  EXPECT_TRUE(std::isnan(st::t_quantile(1.0, 3)));
}

TEST(Stats, EstimateOfThreeReplicasByHand) {
  // 10, 12, 14: mean 12, sd 2, sem 2/sqrt(3) = 1.1547, half-width t_{0.975,2} sem = 4.303 * 1.1547.
  const auto e = st::estimate({10, 12, 14});
  EXPECT_EQ(e.n, 3u);
  EXPECT_DOUBLE_EQ(e.mean, 12);
  EXPECT_NEAR(e.sd, 2, 1e-14);
  EXPECT_NEAR(e.sem, 1.1547005, 1e-7);
  EXPECT_NEAR(e.dof, 2, 1e-12);
  EXPECT_NEAR(e.half95, 4.303 * 1.1547005, 5e-4);
  EXPECT_NEAR(e.rel_half95(), 4.303 * 1.1547005 / 12, 5e-5);
  EXPECT_TRUE(std::isnan(st::estimate({5}).half95));  // one replica: no spread, no interval
}

TEST(Stats, ToolErrorAddsInQuadratureWithWelchSatterthwaiteDof) {
  // sem^2 = 4/3, tool 0.5: u^2 = 4/3 + 1/4 = 1.58333; dof = u^4 / (sem^4 / 2) = 2.8203125;
  // t_{0.975, 2.8203} = 3.30028 (Simpson integration of the t density), half-width 4.15277.
  const auto e = st::estimate({10, 12, 14}, {0.5, 0.5, 0.5});
  EXPECT_NEAR(e.tool, 0.5, 1e-15);
  EXPECT_NEAR(e.u, std::sqrt(4.0 / 3 + 0.25), 1e-12);
  EXPECT_NEAR(e.dof, 2.8203125, 1e-10);
  EXPECT_NEAR(e.half95, 4.152767, 2e-5);
  // No scatter at all: only the tool's error, normal quantile.
  const auto f = st::estimate({3, 3, 3}, {0.1, 0.1, NAN});
  EXPECT_NEAR(f.half95, 1.959964 * 0.1, 1e-6);
}

TEST(Stats, WelchTestByHand) {
  // a = 1..5: mean 3, var 2.5; b = 3,5,..,11: mean 7, var 10. Squared standard errors 0.5, 2:
  // t = -4 / sqrt(2.5) = -2.529822; dof = 2.5^2 / (0.5^2/4 + 2^2/4) = 5.882353;
  // two-sided p = 0.045465 (Simpson integration of the t density).
  const auto w = st::welch({1, 2, 3, 4, 5}, {3, 5, 7, 9, 11});
  EXPECT_NEAR(w.t, -2.5298221, 1e-7);
  EXPECT_NEAR(w.dof, 5.8823529, 1e-7);
  EXPECT_NEAR(w.p, 0.0454646, 2e-6);
  EXPECT_EQ(st::welch({1, 1}, {1, 1}).p, 1);
  EXPECT_EQ(st::welch({1, 1}, {2, 2}).p, 0);
  EXPECT_EQ(st::p_text(0.0454646), "0.045");
  EXPECT_EQ(st::p_text(0.002), "0.002");
  EXPECT_EQ(st::p_text(1e-6), "< 0.0001");
  EXPECT_EQ(st::p_phrase(1e-6), "p < 0.0001");
  EXPECT_EQ(st::p_phrase(0.002), "p = 0.002");
}

namespace {
// Replays the runner's rule on a fixed sequence: the replica count at which it stops, and why.
std::pair<std::size_t, std::string> stop_on(const std::vector<double>& seq, double target, std::size_t min,
                                            std::size_t max) {
  for (std::size_t n = 1; n <= seq.size(); ++n) {
    const auto e = st::estimate(std::vector<double>(seq.begin(), seq.begin() + static_cast<long>(n)));
    const std::string why = st::stop_decision(n, min, max, n >= 2 && e.rel_half95() <= target);
    if (!why.empty()) return {n, why};
  }
  return {0, ""};
}
}  // namespace

TEST(Stats, AdaptiveStopOnFixedSequences) {
  // Relative half-widths t_{0.975,n-1} sd / sqrt(n) / mean by hand (table t):
  // n=3 0.0754, n=4 0.0395, n=5 0.0285, n=6 0.0225, n=7 0.0183, n=8 0.0160.
  const std::vector<double> seq = {10.0, 10.4, 9.8, 10.1, 9.9, 10.2, 10.0, 9.9};
  EXPECT_EQ(stop_on(seq, 0.02, 3, 20), std::make_pair(std::size_t{7}, std::string("target met")));
  EXPECT_EQ(stop_on(seq, 0.05, 3, 20), std::make_pair(std::size_t{4}, std::string("target met")));
  EXPECT_EQ(stop_on(seq, 0.05, 5, 20), std::make_pair(std::size_t{5}, std::string("target met")));  // min first
  EXPECT_EQ(stop_on(seq, 0.02, 3, 5), std::make_pair(std::size_t{5}, std::string("max reached")));
  EXPECT_EQ(stop_on(seq, 0.25, 2, 20), std::make_pair(std::size_t{2}, std::string("target met")));  // 0.2491
  EXPECT_EQ(st::stop_decision(2, 3, 20, true), "");  // below min: never stop
}

TEST(Stats, ProjectedReplicasAgainstAnIndependentComputation) {
  // Expected counts from scipy.stats.t.ppf(0.975, dof) scanned over n (an independent code):
  // the first n whose t sd / sqrt(n) / mean (with the tool error in quadrature, Welch-
  // Satterthwaite dof) is at most the target. (n=3, mean 2, sd 0.1, 5 %) also by the printed
  // table: n=6 2.571 * 0.1 / sqrt(6) / 2 = 0.0525, n=7 2.447 * 0.1 / sqrt(7) / 2 = 0.0462.
  const auto est = [](std::size_t n, double mean, double sd, double tool) {
    st::Estimate e;
    e.n = n, e.mean = mean, e.sd = sd, e.tool = tool;
    return e;
  };
  EXPECT_EQ(st::projected_replicas(est(3, 2.0, 0.1, 0), 0.05, 100), 7u);
  EXPECT_EQ(st::projected_replicas(est(5, 1.0, 0.1, 0), 0.02, 1000), 99u);   // rel. half-width 0.019945
  EXPECT_EQ(st::projected_replicas(est(5, 1.0, 0.1, 0), 0.02, 50), 50u);     // not within the cap
  EXPECT_EQ(st::projected_replicas(est(5, 10.0, 0.5, 0.05), 0.02, 1000), 34u);  // tool error 0.5 %
  // A tool error of 1.2 % alone gives 1.96 * 1.2 % = 2.35 % > 2 %: no number of replicas helps.
  EXPECT_EQ(st::projected_replicas(est(5, 10.0, 0.5, 0.12), 0.02, 1000), 1000u);
  EXPECT_EQ(st::projected_replicas(est(1, 10.0, std::nan(""), 0), 0.02, 1000), 2u);  // no spread yet
}

// Benjamini-Hochberg by hand (Benjamini & Hochberg 1995; the same numbers as R's
// p.adjust(p, "BH")). p = 0.01, 0.04, 0.03, 0.005: sorted 0.005, 0.01, 0.03, 0.04, m p/k = 0.02,
// 0.02, 0.04, 0.04, the running minimum from the top keeps them: q = 0.02, 0.04, 0.04, 0.02 in
// the order given. p = 0.04, 0.041: m p/k = 0.08, 0.041, so the smaller p gets q = 0.041 (a
// step-up: a larger p that passes carries the smaller ones). A NaN stays out of m.
TEST(Stats, BenjaminiHochbergByHand) {
  const auto q = st::benjamini_hochberg({0.01, 0.04, 0.03, 0.005});
  ASSERT_EQ(q.size(), 4u);
  EXPECT_NEAR(q[0], 0.02, 1e-15);
  EXPECT_NEAR(q[1], 0.04, 1e-15);
  EXPECT_NEAR(q[2], 0.04, 1e-15);
  EXPECT_NEAR(q[3], 0.02, 1e-15);
  const auto step_up = st::benjamini_hochberg({0.04, 0.041});
  EXPECT_NEAR(step_up[0], 0.041, 1e-15);
  EXPECT_NEAR(step_up[1], 0.041, 1e-15);
  const auto with_nan = st::benjamini_hochberg({0.02, NAN, 0.5});
  EXPECT_NEAR(with_nan[0], 0.04, 1e-15);
  EXPECT_TRUE(std::isnan(with_nan[1]));
  EXPECT_NEAR(with_nan[2], 0.5, 1e-15);
  EXPECT_NEAR(st::benjamini_hochberg({0.3})[0], 0.3, 1e-15);  // one test: q = p
  EXPECT_NEAR(st::benjamini_hochberg({0.9, 0.8})[0], 0.9, 1e-15);  // never above 1, never below p
  EXPECT_TRUE(st::benjamini_hochberg({}).empty());
}
