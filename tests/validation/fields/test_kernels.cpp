// The kernels integrate to one, their 1-D marginals are their plane integrals, and the
// derivatives match finite differences. Expected values from the definitions, integrated here by
// composite Simpson rules (error ~ (h/c)^4 on a polynomial-smooth integrand: 1e-12 at 20000 panels).
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "tomodem/fields/kernel.hpp"

using namespace tomodem::fields;

namespace {
constexpr double kPi = 3.14159265358979323846;

double simpson(const std::function<double(double)>& f, double a, double b, int n = 20000) {
  const double h = (b - a) / n;
  double s = f(a) + f(b);
  for (int i = 1; i < n; ++i) s += (i % 2 ? 4 : 2) * f(a + i * h);
  return s * h / 3;
}

class Kernels : public ::testing::TestWithParam<std::pair<KernelType, double>> {};

TEST_P(Kernels, IntegrateToOneInThreeDimensionsAndAlongAProfile) {
  const auto [type, cutoff_widths] = GetParam();
  const Kernel k = Kernel::make(type, 2e-3, cutoff_widths);
  const double c = k.cutoff;
  const double volume = simpson([&](double r) { return 4 * kPi * r * r * k.value(r); }, 0, c * (1 - 1e-15));
  EXPECT_NEAR(volume, 1.0, 1e-11);
  const double line = simpson([&](double s) { return k.marginal(s); }, -c * (1 - 1e-15), c * (1 - 1e-15));
  EXPECT_NEAR(line, 1.0, 1e-11);
  EXPECT_EQ(k.value(c), 0.0);
  EXPECT_EQ(k.value(1.01 * c), 0.0);
  EXPECT_EQ(k.marginal(1.01 * c), 0.0);
}

TEST_P(Kernels, MarginalIsThePlaneIntegralAndDerivativesMatchDifferences) {
  const auto [type, cutoff_widths] = GetParam();
  const Kernel k = Kernel::make(type, 2e-3, cutoff_widths);
  const double c = k.cutoff;
  for (double f : {0.0, 0.1, 0.37, 0.8, 0.99}) {
    const double s = f * c, rho_max = std::sqrt(std::max(0.0, c * c - s * s));
    const double plane = simpson([&](double rho) { return 2 * kPi * rho * k.value(std::sqrt(rho * rho + s * s)); }, 0,
                                 rho_max * (1 - 1e-9));  // r stays below c after rounding
    EXPECT_NEAR(k.marginal(s), plane, 1e-9 * k.marginal(0)) << "s/c = " << f;
    const double h = 1e-6 * c;
    const double fd = (k.value(s + h) - k.value(s - h)) / (2 * h);
    if (f > 0) EXPECT_NEAR(k.derivative_over_r(s) * s, fd, 1e-6 * k.norm / c) << "s/c = " << f;
    const double fd1 = (k.marginal(s + h) - k.marginal(s - h)) / (2 * h);
    if (f > 0) EXPECT_NEAR(k.marginal_derivative(s), fd1, 1e-6 * k.marginal(0) / c) << "s/c = " << f;
  }
}

TEST(Kernels, WidthIsTheStandardDeviationOfLucy) {
  // Lucy's variance per direction is c²/12 (∫ x² φ dV = (1/3)∫ r² φ 4πr² dr).
  const Kernel k = Kernel::make(KernelType::lucy, 1.5e-3);
  const double var = simpson([&](double r) { return 4 * kPi * r * r * r * r * k.value(r) / 3; }, 0, k.cutoff);
  EXPECT_NEAR(std::sqrt(var), 1.5e-3, 1e-12);
}

INSTANTIATE_TEST_SUITE_P(Shapes, Kernels,
                         ::testing::Values(std::make_pair(KernelType::gaussian, 3.0),
                                           std::make_pair(KernelType::gaussian, 6.0),
                                           std::make_pair(KernelType::lucy, 3.0)));
}  // namespace
