#pragma once
// Statistics of replicas for `tomodem run report` and adaptive replicas (docs/pipelines.md,
// "Statistics"): Student t quantiles from the regularized incomplete beta function, the mean's
// 95 % confidence interval with the tools' own errors added, and Welch's two-sample t-test.
#include <cstddef>
#include <string>
#include <vector>

namespace tomodem::pipeline::stats {

/// Regularized incomplete beta function I_x(a, b), a, b > 0, 0 <= x <= 1 (continued fraction,
/// modified Lentz; Numerical Recipes 3rd ed., section 6.4).
double incomplete_beta(double a, double b, double x);

/// P(T <= t) for Student's t with `dof` > 0 degrees of freedom (dof may be fractional, as
/// Welch-Satterthwaite gives; infinite dof is the normal distribution).
double t_cdf(double t, double dof);

/// The t with t_cdf(t, dof) = p, 0 < p < 1 (bisection on t_cdf to 1e-12 relative).
double t_quantile(double p, double dof);

/// The mean of replicas and its uncertainty.
struct Estimate {
  std::size_t n = 0;
  double mean = 0, sd = 0, sem = 0;  // sample sd (n-1), sd / sqrt(n); NaN when n < 2
  double tool = 0;                   // the tools' own 1-sigma error of the mean (absolute)
  double u = 0;                      // combined standard uncertainty sqrt(sem^2 + tool^2)
  double dof = 0;                    // effective degrees of freedom (Welch-Satterthwaite)
  double half95 = 0;                 // 95 % half-width t_{0.975,dof} * u; NaN when n < 2
  double rel_half95() const;         // half95 / |mean| (infinite when the mean is 0 and half95 > 0)
};

/// `values`: one per replica; `tool_errors`: the absolute 1-sigma error each replica's tool
/// reported (empty, or one per value; NaN where a replica has none). The tools' error is taken
/// as systematic (it does not average out over replicas): tool = mean of the errors, added in
/// quadrature to the sem; dof = u^4 / (sem^4 / (n-1)) (the tool part has infinite dof).
Estimate estimate(const std::vector<double>& values, const std::vector<double>& tool_errors = {});

/// Welch's unequal-variance t-test of two samples (each n >= 2).
struct Welch {
  double t = 0, dof = 0, p = 1;  // p: two-sided
};
Welch welch(const std::vector<double>& a, const std::vector<double>& b);

/// Benjamini-Hochberg adjusted p-values (q-values) of m tests, in the order given: with p
/// sorted ascending, q_(k) = min over j >= k of min(1, m p_(j) / j) (Benjamini & Hochberg
/// 1995). Calling the tests with q < 0.05 resolved keeps the expected share of false ones among
/// them below 5 %, however many are made (proved for independent or positively dependent
/// tests). NaN p-values stay NaN and do not count in m.
std::vector<double> benjamini_hochberg(const std::vector<double>& p);

/// The adaptive stop rule for one cell after `n` replicas: "" (add one more) while n < min;
/// then "target met" when every named property meets its relative 95 % half-width target,
/// else "max reached" when n >= max, else "" again.
std::string stop_decision(std::size_t n, std::size_t min, std::size_t max, bool all_targets_met);

/// The fewest replicas, more than e.n and at most `cap`, whose 95 % half-width relative to the
/// mean would be at most `target` if the replicas' sd and the tools' error stayed as they are
/// (the same Student t and Welch-Satterthwaite dof as estimate()); `cap` when none would be,
/// e.n + 1 while there is no spread yet (n < 2). The half-width falls with n, so this bisects.
std::size_t projected_replicas(const Estimate& e, double target, std::size_t cap);

/// "0.002", "0.04", "< 0.0001": a p-value with two significant digits.
std::string p_text(double p);
/// "p = 0.045", "p < 0.0001": p_text with its relation, for sentences.
std::string p_phrase(double p);

}  // namespace tomodem::pipeline::stats
