// Size distributions: stratified samples follow the requested CDF (Kolmogorov–Smirnov distance
// of a few 1/N), number/volume conversion, CSV tables and their errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>

#include "tomodem/core/error.hpp"
#include "tomodem/geometry/psd.hpp"

using namespace tomodem;
using namespace tomodem::geometry;

namespace {
SizeDistribution make(PsdKind k, PsdBasis b, double d, double sigma = 0) {
  SizeDistribution s;
  s.kind = k;
  s.basis = b;
  s.diameter = d;
  s.sigma = sigma;
  s.prepare();
  return s;
}
std::string write(const std::string& name, const std::string& text) {
  const std::string p = ::testing::TempDir() + name;
  std::ofstream(p) << text;
  return p;
}

// Independent of the code under test (max_cdf_deviation, SizeDistribution::cdf): the
// Kolmogorov–Smirnov distance sup|F_N − F| between the empirical CDF of `d`, weighted by d^p
// (p = 0: by number, p = 3: by volume), and a CDF F written out in the test. F must be continuous.
double ks_distance(std::vector<double> d, int p, const std::function<double(double)>& F) {
  std::sort(d.begin(), d.end());
  double total = 0;
  for (double x : d) total += std::pow(x, p);
  double below = 0, dist = 0;
  for (std::size_t i = 0; i < d.size();) {
    std::size_t j = i;
    double w = 0;
    for (; j < d.size() && d[j] == d[i]; ++j) w += std::pow(d[j], p);
    const double f = F(d[i]);
    dist = std::max({dist, std::abs(f - below / total), std::abs((below + w) / total - f)});
    below += w;
    i = j;
  }
  return dist;
}
// Φ(z), the standard normal CDF.
double Phi(double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); }
// Normal CDF in z cut at ±3 (SizeDistribution::truncation, default 3 σ) and renormalised.
double truncated(double z) {
  if (z <= -3) return 0;
  if (z >= 3) return 1;
  return (Phi(z) - Phi(-3)) / (Phi(3) - Phi(-3));
}
}  // namespace

TEST(Psd, LognormalByNumberSampleWithinOnePercent) {
  const auto s = make(PsdKind::lognormal, PsdBasis::number, 1e-6, 0.3);
  const auto d = s.sample(5000, 1);
  // Against the lognormal cut at ±3σ written out here: ln(d/1 µm)/0.3 is standard normal.
  const double ks = ks_distance(d, 0, [](double x) { return truncated(std::log(x / 1e-6) / 0.3); });
  std::printf("lognormal by number: KS %.3e\n", ks);
  // Stratified quantiles: KS distance 1/(2N) = 1e-4 plus the 4096-point grid interpolation
  // (second order in a log step of 6σ/4096: < 1e-6). Measured 1.0e-4; limit 1e-3.
  EXPECT_LT(ks, 1e-3);
  // Median of a lognormal is its parameter.
  auto sorted = d;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_NEAR(sorted[2500] / 1e-6, 1.0, 1e-3);
}

TEST(Psd, LognormalByVolumeSampleMatchesVolumeCdf) {
  const auto s = make(PsdKind::lognormal, PsdBasis::volume, 1e-6, 0.3);
  const auto d = s.sample(5000, 2);
  // By volume the weighted sample follows the requested lognormal (median 1 µm, σ 0.3, cut at ±3σ).
  const double ks = ks_distance(d, 3, [](double x) { return truncated(std::log(x / 1e-6) / 0.3); });
  std::printf("lognormal by volume: KS %.3e\n", ks);
  // Weighting a number-stratified sample by d³ puts up to d_max³/Σd³ ≈ 1e-3 on one particle:
  // measured 1.9e-3 (seed 2); limit 5e-3, inside the 2 % criterion of issue 3.
  EXPECT_LT(ks, 5e-3);
  // Volume-weighted median (d50 by volume) equals the parameter; number median is smaller by
  // exp(-3σ²) for a lognormal (Hatch–Choate).
  auto sorted = d;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_NEAR(sorted[2500] / (1e-6 * std::exp(-3 * 0.09)), 1.0, 0.01);
}

TEST(Psd, NormalByNumberMean) {
  const auto s = make(PsdKind::normal, PsdBasis::number, 2e-6, 0.2e-6);
  const auto d = s.sample(4000, 3);
  double m = 0;
  for (double x : d) m += x;
  EXPECT_NEAR(m / 4000 / 2e-6, 1.0, 1e-3);  // symmetric truncation keeps the mean
  const double ks = ks_distance(d, 0, [](double x) { return truncated((x - 2e-6) / 0.2e-6); });
  std::printf("normal by number: KS %.3e\n", ks);
  EXPECT_LT(ks, 1e-3);  // 1/(2N) = 1.25e-4 for stratified quantiles (measured 1.25e-4)
}

TEST(Psd, BimodalByVolumeCountsFollowDiameterCubed) {
  SizeDistribution s;
  s.kind = PsdKind::bimodal;
  s.basis = PsdBasis::volume;
  s.diameter = 1e-6;
  s.diameter2 = 10e-6;
  s.fraction2 = 0.5;
  s.prepare();
  // Equal volumes: 1000 small particles per large one.
  EXPECT_NEAR(s.number_cdf(1e-6), 1000.0 / 1001.0, 1e-12);
  const auto d = s.sample(100100, 4);
  // Counted directly: 1000 of every 1001 particles are the small ones (100100 = 1001·100).
  const auto small = std::count(d.begin(), d.end(), 1e-6), large = std::count(d.begin(), d.end(), 10e-6);
  std::printf("bimodal: %ld small, %ld large\n", long(small), long(large));
  EXPECT_EQ(small + large, 100100);
  EXPECT_NEAR(double(small), 100000.0, 1.0);  // stratified quantiles: exact up to one particle
}

TEST(Psd, TabulatedCsvVolumeBasis) {
  const auto p = write("psd_ok.csv", "diameter_m,cumulative_volume_fraction\n1e-6,0\n2e-6,0.3\n4e-6,0.9\n8e-6,1\n");
  auto s = read_psd_csv(p, PsdBasis::volume);
  s.prepare();
  EXPECT_NEAR(s.cdf(3e-6), 0.6, 1e-12);
  const auto d = s.sample(20000, 5);
  // The table's volume CDF, linear in d between its rows, written out here.
  const auto F = [](double x) {
    const double t[4][2] = {{1e-6, 0}, {2e-6, 0.3}, {4e-6, 0.9}, {8e-6, 1}};
    if (x <= t[0][0]) return 0.0;
    for (int k = 1; k < 4; ++k)
      if (x <= t[k][0]) return t[k - 1][1] + (x - t[k - 1][0]) / (t[k][0] - t[k - 1][0]) * (t[k][1] - t[k - 1][1]);
    return 1.0;
  };
  const double ks = ks_distance(d, 3, F);
  std::printf("tabulated by volume: KS %.3e\n", ks);
  EXPECT_LT(ks, 5e-3);  // measured 1.8e-3 (d³-weighted, as by volume above); issue 3: 2 %
}

TEST(Psd, CsvErrorsNameFileRowAndValue) {
  const auto expect_error = [](const std::string& text, const std::string& needle) {
    const auto p = write("psd_bad.csv", text);
    try {
      read_psd_csv(p, PsdBasis::volume);
      ADD_FAILURE() << "accepted: " << text;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
      EXPECT_EQ(e.file(), p);
    }
  };
  expect_error("1e-6,0\n-2e-6,1\n", "-2e-6");
  expect_error("1e-6,0\n2e-6,0.5\n", "must be 1");
  expect_error("1e-6,0\n2e-6,abc\n", "row 2");
  expect_error("1e-6,0.5\n2e-6,0.4\n3e-6,1\n", "must not decrease");
  EXPECT_THROW(read_psd_csv("/nonexistent/psd.csv", PsdBasis::volume), InputError);
}

TEST(Psd, NonPositiveSizesRefused) {
  auto s = make(PsdKind::monodisperse, PsdBasis::number, 0.0);
  EXPECT_THROW(s.validate("c.yaml", "phases[0].size_distribution"), InputError);
  auto n = make(PsdKind::normal, PsdBasis::number, 1e-6, 0.5e-6);  // mean − 3σ < 0
  EXPECT_THROW(n.validate("c.yaml", "x"), InputError);
}
