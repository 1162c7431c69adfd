// Size distributions: stratified samples follow the requested CDF (Kolmogorov–Smirnov distance
// of a few 1/N), number/volume conversion, CSV tables and their errors.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

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
}  // namespace

TEST(Psd, LognormalByNumberSampleWithinOnePercent) {
  const auto s = make(PsdKind::lognormal, PsdBasis::number, 1e-6, 0.3);
  const auto d = s.sample(5000, 1);
  // Stratified quantiles: KS distance 1/(2N) plus the 4096-point grid interpolation.
  EXPECT_LT(max_cdf_deviation(s, d), 0.01);
  // Median of a lognormal is its parameter.
  auto sorted = d;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_NEAR(sorted[2500] / 1e-6, 1.0, 1e-3);
}

TEST(Psd, LognormalByVolumeSampleMatchesVolumeCdf) {
  const auto s = make(PsdKind::lognormal, PsdBasis::volume, 1e-6, 0.3);
  const auto d = s.sample(5000, 2);
  EXPECT_LT(max_cdf_deviation(s, d), 0.02);  // the 2 % criterion of issue 3
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
  EXPECT_LT(max_cdf_deviation(s, d), 0.01);
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
  EXPECT_LT(max_cdf_deviation(s, d), 0.01);
}

TEST(Psd, TabulatedCsvVolumeBasis) {
  const auto p = write("psd_ok.csv", "diameter_m,cumulative_volume_fraction\n1e-6,0\n2e-6,0.3\n4e-6,0.9\n8e-6,1\n");
  auto s = read_psd_csv(p, PsdBasis::volume);
  s.prepare();
  EXPECT_NEAR(s.cdf(3e-6), 0.6, 1e-12);
  const auto d = s.sample(20000, 5);
  EXPECT_LT(max_cdf_deviation(s, d), 0.02);
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
