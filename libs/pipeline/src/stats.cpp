// Replica statistics (stats.hpp). Sources: Student (1908), Biometrika 6:1-25 (the t
// distribution); Welch (1947), Biometrika 34:28-35 (unequal variances, approximate dof);
// JCGM 100:2008 (GUM) G.4 (effective dof of a combined uncertainty, Welch-Satterthwaite).
#include "tomodem/pipeline/stats.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace tomodem::pipeline::stats {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Continued fraction of I_x(a, b) (Numerical Recipes 3rd ed., betacf), modified Lentz.
double beta_fraction(double a, double b, double x) {
  constexpr double tiny = 1e-300, eps = 1e-16;
  const double qab = a + b, qap = a + 1, qam = a - 1;
  double c = 1, d = 1 - qab * x / qap;
  if (std::fabs(d) < tiny) d = tiny;
  d = 1 / d;
  double h = d;
  for (int m = 1; m <= 100000; ++m) {
    const int m2 = 2 * m;
    double aa = m * (b - m) * x / ((qam + m2) * (a + m2));
    d = 1 + aa * d;
    if (std::fabs(d) < tiny) d = tiny;
    c = 1 + aa / c;
    if (std::fabs(c) < tiny) c = tiny;
    d = 1 / d;
    h *= d * c;
    aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
    d = 1 + aa * d;
    if (std::fabs(d) < tiny) d = tiny;
    c = 1 + aa / c;
    if (std::fabs(c) < tiny) c = tiny;
    d = 1 / d;
    const double del = d * c;
    h *= del;
    if (std::fabs(del - 1) < eps) break;
  }
  return h;
}

// P(|T| > t) for t >= 0: the two-sided tail, computed directly so small p keep their digits.
double two_sided_tail(double t, double dof) {
  if (std::isinf(dof) || dof > 1e10) return std::erfc(t / std::sqrt(2.0));
  return incomplete_beta(dof / 2, 0.5, dof / (dof + t * t));
}
}  // namespace

double incomplete_beta(double a, double b, double x) {
  if (x <= 0) return 0;
  if (x >= 1) return 1;
  const double front = std::exp(std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) + a * std::log(x) + b * std::log1p(-x));
  // The fraction converges fast on this side of the mean; use the symmetry on the other.
  if (x < (a + 1) / (a + b + 2)) return front * beta_fraction(a, b, x) / a;
  return 1 - front * beta_fraction(b, a, 1 - x) / b;
}

double t_cdf(double t, double dof) {
  if (std::isnan(t) || !(dof > 0)) return kNaN;
  if (std::isinf(t)) return t > 0 ? 1 : 0;
  const double tail = 0.5 * two_sided_tail(std::fabs(t), dof);
  return t > 0 ? 1 - tail : tail;
}

double t_quantile(double p, double dof) {
  if (!(p > 0 && p < 1) || !(dof > 0)) return kNaN;
  if (p == 0.5) return 0;
  if (p < 0.5) return -t_quantile(1 - p, dof);
  double lo = 0, hi = 1;
  while (t_cdf(hi, dof) < p && hi < 1e300) lo = hi, hi *= 2;
  for (int k = 0; k < 400 && hi - lo > 1e-12 * hi; ++k) {
    const double mid = 0.5 * (lo + hi);
    (t_cdf(mid, dof) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double Estimate::rel_half95() const {
  if (std::isnan(half95)) return kNaN;
  if (mean == 0) return half95 > 0 ? kInf : 0;
  return half95 / std::fabs(mean);
}

namespace {
// sem, u, dof and half95 of `e` from its n, sd and tool error.
void uncertainty_of_mean(Estimate& e) {
  const double n = static_cast<double>(e.n);
  e.sem = e.sd / std::sqrt(n);
  e.u = std::sqrt(e.sem * e.sem + e.tool * e.tool);
  // GUM G.4.2 with the tool part's dof infinite: only the replica scatter reduces the dof.
  e.dof = e.sem > 0 ? std::pow(e.u, 4) / (std::pow(e.sem, 4) / (n - 1)) : kInf;
  e.half95 = e.u > 0 ? t_quantile(0.975, e.dof) * e.u : 0;
}
}  // namespace

Estimate estimate(const std::vector<double>& values, const std::vector<double>& tool_errors) {
  Estimate e;
  e.n = values.size();
  if (e.n == 0) {
    e.mean = e.sd = e.sem = e.u = e.half95 = kNaN;
    return e;
  }
  double sum = 0;
  for (const double x : values) sum += x;
  e.mean = sum / static_cast<double>(e.n);
  double tool_sum = 0;
  int tools = 0;
  for (const double t : tool_errors)
    if (std::isfinite(t)) tool_sum += std::fabs(t), ++tools;
  e.tool = tools ? tool_sum / tools : 0;
  if (e.n < 2) {
    e.sd = e.sem = e.u = e.half95 = kNaN;
    return e;
  }
  double ss = 0;
  for (const double x : values) ss += (x - e.mean) * (x - e.mean);
  const double n = static_cast<double>(e.n);
  e.sd = std::sqrt(ss / (n - 1));
  uncertainty_of_mean(e);
  return e;
}

Welch welch(const std::vector<double>& a, const std::vector<double>& b) {
  const Estimate ea = estimate(a), eb = estimate(b);
  Welch w;
  const double va = ea.sem * ea.sem, vb = eb.sem * eb.sem;
  if (!(ea.n >= 2 && eb.n >= 2)) {
    w.t = w.dof = w.p = kNaN;
    return w;
  }
  if (va + vb == 0) {  // no scatter at all: equal means are not different, unequal ones surely are
    w.dof = static_cast<double>(ea.n + eb.n - 2);
    w.t = ea.mean == eb.mean ? 0 : (ea.mean > eb.mean ? kInf : -kInf);
    w.p = ea.mean == eb.mean ? 1 : 0;
    return w;
  }
  w.t = (ea.mean - eb.mean) / std::sqrt(va + vb);
  w.dof = (va + vb) * (va + vb) / (va * va / static_cast<double>(ea.n - 1) + vb * vb / static_cast<double>(eb.n - 1));
  w.p = two_sided_tail(std::fabs(w.t), w.dof);
  return w;
}

std::string stop_decision(std::size_t n, std::size_t min, std::size_t max, bool all_targets_met) {
  if (n < min) return "";
  if (all_targets_met) return "target met";
  if (n >= max) return "max reached";
  return "";
}

std::size_t projected_replicas(const Estimate& e, double target, std::size_t cap) {
  if (e.n < 2 || !std::isfinite(e.sd) || e.mean == 0) return std::min(e.n + 1, cap);
  const auto rel_half = [&](std::size_t n) {
    Estimate more = e;
    more.n = n;
    uncertainty_of_mean(more);
    return more.rel_half95();
  };
  std::size_t lo = e.n, hi = cap;  // rel_half(lo) > target (or lo = e.n); find the first n with <=
  if (hi <= lo || rel_half(hi) > target) return std::max(cap, e.n);
  while (hi - lo > 1) {
    const std::size_t mid = lo + (hi - lo) / 2;
    (rel_half(mid) <= target ? hi : lo) = mid;
  }
  return hi;
}

std::vector<double> benjamini_hochberg(const std::vector<double>& p) {
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (!std::isnan(p[i])) order.push_back(i);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return p[a] < p[b]; });
  std::vector<double> q(p.size(), NAN);
  const double m = double(order.size());
  double running = 1;  // the minimum over the larger p-values, taken from the largest down
  for (std::size_t k = order.size(); k-- > 0;) {
    running = std::min(running, m * p[order[k]] / double(k + 1));
    q[order[k]] = running;
  }
  return q;
}

std::string p_text(double p) {
  if (std::isnan(p)) return "n/a";
  if (p < 1e-4) return "< 0.0001";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2g", p);
  return buf;
}

std::string p_phrase(double p) { return p < 1e-4 ? "p " + p_text(p) : "p = " + p_text(p); }

}  // namespace tomodem::pipeline::stats
