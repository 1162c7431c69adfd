// Coarse-graining of a simple cubic spring lattice under a homogeneous affine strain in a
// periodic cell: the CG stress equals the Love stress at every node, written out by hand below
// (Weinhart et al. 2012: the exact CG of a homogeneous state is homogeneous). What is left is
// the lattice ripple of the kernel: its Fourier transform at the reciprocal lattice vectors G,
// exp(-2π² w²/a²) ~ 1e-19 for the untruncated Gaussian at w = 1.5a, but set by the jump at the
// cut-off k·w for the truncated one (∝ e^{-k²/2}/(w|G|)², docs/cg.md#accuracy): measured 1.5e-3 at
// k = 3 and 3e-9 at k = 6. Lucy (C² at its edge, FT ∝ |G|^-6) ripples at 7e-5.
#include <gtest/gtest.h>

#include <cmath>

#include "lattices.hpp"
#include "tomodem/fields/cg.hpp"
#include "tomodem/fields/tool.hpp"

using namespace tomodem;
using namespace tomodem::fields;
using tomodem::fields::test::relative_difference;
using tomodem::fields::test::spring_lattice;

namespace {
constexpr double kA = 1e-3, kK = 1e5, kRho = 2500;
constexpr double kPi = 3.14159265358979323846;

Accumulator::Fields coarse_grain(const Packing& p, const Kernel& k, GridSpec g, int threads = 2,
                                 const Packing* ref = nullptr) {
  Accumulator acc(k, g, p.cell, 0, threads);
  acc.add(make_snapshot(p, "lattice", SnapshotOptions{}, ref, "reference"));
  return acc.fields();
}

GridSpec full(int n) {
  GridSpec g;
  g.n = {n, n, n};
  return g;
}

struct Case {
  KernelType type;
  double cutoff_widths, width_over_a, tolerance;
};

class AffineLattice : public ::testing::TestWithParam<Case> {};

TEST_P(AffineLattice, StressIsTheLoveStressAtEveryNode) {
  const Case c = GetParam();
  const Vec3 eps{-1e-3, -2e-3, 5e-4};
  const Mat3 F = Mat3::diagonal({1 + eps.x, 1 + eps.y, 1 + eps.z});
  const Packing p = spring_lattice(8, kA, F, kK, kRho);
  // By hand: one contact per axis and particle, force -k a ε_a along the axis, branch a(1 + ε_a),
  // volume per particle a³ Π(1 + ε): σ_aa = k ε_a (1 + ε_a) / (a Π(1 + ε)).
  const double J = (1 + eps.x) * (1 + eps.y) * (1 + eps.z);
  const Mat3 love = Mat3::diagonal({kK * eps.x * (1 + eps.x) / (kA * J), kK * eps.y * (1 + eps.y) / (kA * J),
                                    kK * eps.z * (1 + eps.z) / (kA * J)});
  const Kernel k = Kernel::make(c.type, c.width_over_a * kA, c.cutoff_widths);
  const auto f = coarse_grain(p, k, full(20));
  double worst = 0;
  for (std::size_t n = 0; n < f.points.size(); ++n) worst = std::max(worst, relative_difference(&f.stress[9 * n], love));
  RecordProperty("max_relative_difference", std::to_string(worst));
  std::printf("kernel %d cutoff %.1f w/a %.2f: max relative difference %.3e\n", int(c.type), c.cutoff_widths,
              c.width_over_a, worst);
  EXPECT_LT(worst, c.tolerance);
}

INSTANTIATE_TEST_SUITE_P(Kernels, AffineLattice,
                         ::testing::Values(Case{KernelType::gaussian, 6, 1.5, 1e-6},
                                           Case{KernelType::gaussian, 3, 1.5, 3e-3},
                                           Case{KernelType::gaussian, 3, 3.0, 1e-3},
                                           Case{KernelType::lucy, 3, 1.5, 1e-3}));

TEST(AffineLattice, ShearedTriclinicCellGivesTheLoveShearStress) {
  // Simple shear x += γ y: the y contacts have branch a(γ, 1, 0), length L = a sqrt(1 + γ²), force
  // -k (L - a) d/L; volume per particle a³. σ = k (L - a)/(L a) [γ² γ; γ 1] in the xy block.
  const double g = 0.01;
  Mat3 F = Mat3::identity();
  F(0, 1) = g;
  const Packing p = spring_lattice(8, kA, F, kK, kRho);
  const double L = kA * std::sqrt(1 + g * g), s = kK * (L - kA) / (L * kA);
  Mat3 love;
  love(0, 0) = s * g * g, love(0, 1) = love(1, 0) = s * g, love(1, 1) = s;
  const auto f = coarse_grain(p, Kernel::make(KernelType::gaussian, 1.5 * kA, 6), full(16));
  double worst = 0;
  for (std::size_t n = 0; n < f.points.size(); ++n) worst = std::max(worst, relative_difference(&f.stress[9 * n], love));
  std::printf("triclinic: %.3e\n", worst);
  EXPECT_LT(worst, 1e-6);
}

TEST(AffineLattice, DensityIntegratesToTheTotalMass) {
  // Σ ρ ΔV over the periodic grid against N m: the grid quadrature of a smooth periodic function
  // (the untruncated Gaussian's error exp(-2π² w²/h²) is nil at h = w/4), so what is left is the
  // jump at the cut-off, e^{-k²/2}: round-off at k = 8, ~1e-10 at k = 6, ~1e-4 at k = 3.
  const Packing p = spring_lattice(6, kA, Mat3::identity(), kK, kRho);
  const double mass = 216 * kRho * 4.0 / 3.0 * kPi * std::pow(0.5 * kA, 3);
  for (double k : {8.0, 6.0, 3.0}) {
    const auto f = coarse_grain(p, Kernel::make(KernelType::gaussian, 1.5 * kA, k), full(17));
    double m = 0;
    for (double rho : f.density) m += rho * f.node_volume;
    std::printf("mass cutoff %.0f: %.3e\n", k, (m - mass) / mass);
    EXPECT_NEAR(m / mass, 1.0, k == 8 ? 2e-13 : k == 6 ? 1e-9 : 1e-3);
  }
}

TEST(AffineLattice, ProfilesAndSlicesGiveTheLoveStress) {
  const Vec3 eps{-1e-3, -2e-3, 5e-4};
  const Packing p = spring_lattice(8, kA, Mat3::diagonal({1 + eps.x, 1 + eps.y, 1 + eps.z}), kK, kRho);
  const double J = (1 + eps.x) * (1 + eps.y) * (1 + eps.z);
  const Mat3 love = Mat3::diagonal({kK * eps.x * (1 + eps.x) / (kA * J), kK * eps.y * (1 + eps.y) / (kA * J),
                                    kK * eps.z * (1 + eps.z) / (kA * J)});
  const Kernel k = Kernel::make(KernelType::gaussian, 1.5 * kA, 6);
  for (int axis = 0; axis < 3; ++axis) {
    GridSpec g;
    g.kind = GridSpec::Kind::profile;
    g.axis = axis;
    g.n = {37, 37, 37};
    const auto f = coarse_grain(p, k, g);
    double worst = 0;
    for (std::size_t n = 0; n < f.points.size(); ++n) worst = std::max(worst, relative_difference(&f.stress[9 * n], love));
    std::printf("profile %d: %.3e\n", axis, worst);
    EXPECT_LT(worst, 1e-6) << "profile along " << axis;
    g.kind = GridSpec::Kind::slice;
    g.fraction = 0.3;
    const auto s = coarse_grain(p, k, g);
    worst = 0;
    for (std::size_t n = 0; n < s.points.size(); ++n) worst = std::max(worst, relative_difference(&s.stress[9 * n], love));
    std::printf("slice %d: %.3e\n", axis, worst);
    EXPECT_LT(worst, 1e-6) << "slice normal to " << axis;
  }
}

TEST(AffineLattice, ResultsDoNotDependOnTheThreadCount) {
  const Packing p = spring_lattice(6, kA, Mat3::diagonal({0.999, 1.001, 1}), kK, kRho);
  const Kernel k = Kernel::make(KernelType::lucy, 1.2 * kA);
  const auto a = coarse_grain(p, k, full(13), 1), b = coarse_grain(p, k, full(13), 3);
  EXPECT_EQ(a.stress, b.stress);
  EXPECT_EQ(a.density, b.density);
}
}  // namespace

namespace {
TEST(AffineLattice, BoxWithoutPeriodicityLosesTheMassBeyondItsFaces) {
  // Walls instead of images: a particle keeps the part of its kernel inside the box. With the
  // cut-off at 8 widths the kernel is the untruncated Gaussian to 1e-14, which factorises, so the
  // kept fraction is Π_a [Φ((L - x_a)/w) - Φ(-x_a/w)] (Φ the normal distribution). The grid sum is
  // a midpoint rule on [0, L] whose error is (h²/24)·[f'] at the faces: ~2e-3 of the mass at
  // h = w/4 and w = 1.5a, hence the tolerance.
  Packing p = spring_lattice(6, kA, Mat3::identity(), kK, kRho);
  p.cell.periodic[0] = p.cell.periodic[1] = p.cell.periodic[2] = false;
  p.contacts = ContactTable{};
  const double w = 1.5 * kA, L = 6 * kA, m = kRho * 4.0 / 3.0 * kPi * std::pow(0.5 * kA, 3);
  auto Phi = [](double t) { return 0.5 * std::erfc(-t / std::sqrt(2.0)); };
  double kept = 0;
  for (const Vec3& x : p.particles.position) {
    double f = 1;
    for (int a = 0; a < 3; ++a) f *= Phi((L - x[a]) / w) - Phi(-x[a] / w);
    kept += m * f;
  }
  const auto f = coarse_grain(p, Kernel::make(KernelType::gaussian, w, 8), full(24));
  double grid = 0;
  std::size_t interior = 0;
  for (std::size_t n = 0; n < f.density.size(); ++n) grid += f.density[n] * f.node_volume, interior += f.interior[n];
  std::printf("box: kept %.6e, grid %.6e, relative %.3e\n", kept, grid, grid / kept - 1);
  EXPECT_NEAR(grid / kept, 1.0, 5e-3);
  EXPECT_LT(kept, 0.9 * 216 * m);  // the loss is real: a quarter of the mass sits within w of a face
  EXPECT_EQ(interior, 0u);         // a cut-off of 12 mm reaches a face of a 6 mm box from every node
}
}  // namespace
