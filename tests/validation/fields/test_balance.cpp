// Momentum balance and the other fields on lattices with closed forms:
//  - a lattice whose x springs carry a tension that varies from line to line (y, z) but not along a
//    line is in equilibrium: ∇·σ = Σ_i f_i φ_i = 0 though σ is not uniform; the residual left is the
//    quadrature of the branch integrals. The same lattice with tensions that vary along the lines
//    is not in equilibrium, and its divergence must be the net force density Σ f_i φ(r - x_i);
//  - alternating velocities ±v give the kinetic stress -ρ v⊗v;
//  - an affine displacement gives the strain of the affine map at every node;
//  - bonds stretched affinely give the Love stress of springs k_n = E a g_n/(1 - ν²).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "lattices.hpp"
#include "tomodem/fields/cg.hpp"
#include "tomodem/fields/tool.hpp"

using namespace tomodem;
using namespace tomodem::fields;
using tomodem::fields::test::spring_lattice;

namespace {
constexpr double kA = 1e-3, kK = 1e5, kRho = 2500;
constexpr double kPi = 3.14159265358979323846;

GridSpec full(int n) {
  GridSpec g;
  g.n = {n, n, n};
  return g;
}

/// x springs with tension T(y, z) (uniform along each line) or T(x) (varying along the lines).
Snapshot line_tensions(bool balanced, std::vector<Vec3>* net_force) {
  const int n = 8;
  Packing p = spring_lattice(n, kA, Mat3::identity(), kK, kRho);
  std::mt19937 gen(20);
  std::uniform_real_distribution<double> u(0.5, 1.5);
  std::vector<double> line(n * n), column(n);
  for (double& t : line) t = u(gen);
  for (double& t : column) t = u(gen);
  net_force->assign(p.particles.size(), Vec3{});
  for (std::size_t c = 0; c < p.contacts.size(); ++c) {
    const int i = p.contacts.i[c], j = p.contacts.j[c];
    const Vec3 d = p.particles.position[j] - p.particles.position[i];
    const bool along_x = std::abs(d.x) > 0.5 * kA || std::abs(std::abs(d.x) - (n - 1) * kA) < 1e-9;
    double t = 0;
    if (along_x && c % 3 == 0) t = balanced ? line[i % (n * n)] : column[i / (n * n)];
    p.contacts.normal_force[c] = {-t, 0, 0};  // tension: pulls j (the +x neighbour) towards i
    (*net_force)[j] += p.contacts.normal_force[c];
    (*net_force)[i] -= p.contacts.normal_force[c];
  }
  return make_snapshot(p, "lines", SnapshotOptions{}, nullptr, "");
}

struct DivCase {
  KernelType type;
  double cutoff_widths;
  int quadrature;  // points per branch, 0: automatic (3 on these branches of 0.67 w)
  double balanced_tolerance, density_tolerance;
};
class Divergence : public ::testing::TestWithParam<DivCase> {};

// The divergence is taken from the kernel's gradient, which leaves out the surface term of the
// truncated Gaussian's jump (e^{-k²/2} relative): 1e-3 at k = 3, nil at k = 6 and for Lucy (C²).
// What is left is the Gauss-Legendre quadrature of the branch integrals: measured 2e-7 with the
// automatic 3 points, 1.5e-9 with 8.
TEST_P(Divergence, EquilibriumLatticeHasZeroDivergenceAndAnUnbalancedOneHasItsForceDensity) {
  const DivCase dc = GetParam();
  const Kernel k = Kernel::make(dc.type, 1.5 * kA, dc.cutoff_widths);
  double residuals[2] = {0, 0};
  for (bool balanced : {true, false}) {
    std::vector<Vec3> fnet;
    const Snapshot s = line_tensions(balanced, &fnet);
    Accumulator acc(k, full(16), s.cell, dc.quadrature, 2);
    acc.add(s);
    const auto f = acc.fields();
    double div2 = 0, sig2 = 0, err2 = 0, ref2 = 0;
    for (std::size_t n = 0; n < f.points.size(); ++n) {
      div2 += norm2(f.divergence[n]);
      for (int c = 0; c < 9; ++c) sig2 += f.stress_contact[9 * n + c] * f.stress_contact[9 * n + c];
      // Σ_i f_i φ(r - x_i) over the images, computed directly.
      Vec3 expect;
      for (std::size_t i = 0; i < s.x.size(); ++i)
        if (norm2(fnet[i]) > 0)
          for (int a = -1; a <= 1; ++a)
            for (int b = -1; b <= 1; ++b)
              for (int c = -1; c <= 1; ++c)  // the support (4.5 a) reaches past half the cell (4 a)
                expect += k.value(norm(f.points[n] - s.x[i] - s.cell.h * Vec3(a, b, c))) * fnet[i];
      err2 += norm2(f.divergence[n] - expect), ref2 += norm2(expect);
    }
    const double residual = std::sqrt(div2 / sig2) * k.width;
    std::printf("balanced %d: residual %.3e, against force density %.3e\n", balanced, residual,
                ref2 > 0 ? std::sqrt(err2 / ref2) : 0.0);
    residuals[balanced] = residual;
    if (balanced) EXPECT_LT(residual, dc.balanced_tolerance);
    else EXPECT_LT(std::sqrt(err2 / ref2), dc.density_tolerance);
  }
  EXPECT_GT(residuals[0], 10 * residuals[1]);  // an unbalanced state stands out
}

INSTANTIATE_TEST_SUITE_P(Kernels, Divergence,
                         ::testing::Values(DivCase{KernelType::gaussian, 6, 0, 1e-6, 1e-4},
                                           DivCase{KernelType::gaussian, 6, 8, 1e-8, 1e-6},
                                           // Lucy's r³ term is not smooth where a branch passes a node:
                                           // Gauss-Legendre converges slowly there (measured 5e-6, 3e-4).
                                           DivCase{KernelType::lucy, 3, 0, 5e-5, 2e-3},
                                           DivCase{KernelType::gaussian, 3, 0, 3e-3, 0.2}));

TEST(Balance, AlternatingVelocitiesGiveTheKineticStress) {
  Packing p = spring_lattice(8, kA, Mat3::identity(), 0, kRho);
  const Vec3 v{0.3, -0.2, 0.1};
  for (std::size_t i = 0; i < p.particles.size(); ++i) {
    const Vec3 x = p.particles.position[i];
    const int parity = (int(x.x / kA) + int(x.y / kA) + int(x.z / kA)) % 2;
    p.particles.velocity.push_back(parity ? v : -1.0 * v);
  }
  // ρ = m/a³ with m = ρ_s π a³/6; σ_k = -ρ v⊗v (the local mean velocity is zero up to the ripple).
  const double rho = kRho * kPi / 6;
  const Kernel k = Kernel::make(KernelType::gaussian, 1.5 * kA, 6);
  Accumulator acc(k, full(12), p.cell, 0, 2);
  acc.add(make_snapshot(p, "velocities", SnapshotOptions{}, nullptr, ""));
  const auto f = acc.fields();
  double worst = 0;
  for (std::size_t n = 0; n < f.points.size(); ++n) {
    EXPECT_NEAR(f.density[n], rho, 1e-7 * rho);  // lattice ripple at k = 6: 2e-8
    for (int c = 0; c < 9; ++c)
      worst = std::max(worst, std::abs(f.stress_kinetic[9 * n + c] + rho * v[c / 3] * v[c % 3]) / (rho * 0.09));
  }
  std::printf("kinetic: %.3e\n", worst);
  EXPECT_LT(worst, 1e-6);
}

TEST(Balance, AffineDisplacementGivesItsStrainAcrossThePeriodicFaces) {
  const Packing ref = spring_lattice(8, kA, Mat3::identity(), 0, kRho);
  Mat3 F = Mat3::identity();
  F(0, 0) = 1.002, F(1, 1) = 0.999, F(0, 2) = 0.003;  // stretch and shear: ε_xz = 0.0015
  Packing def = spring_lattice(8, kA, F, 0, kRho);
  // Move a few particles by a cell vector: the displacement must see through the wrap.
  for (std::size_t i = 0; i < def.particles.size(); i += 7) def.particles.position[i] += def.cell.h.col(i % 3);
  const Kernel k = Kernel::make(KernelType::gaussian, 1.5 * kA, 6);
  Accumulator acc(k, full(12), def.cell, 0, 2);
  acc.add(make_snapshot(def, "deformed", SnapshotOptions{}, &ref, "reference"));
  const auto f = acc.fields();
  // The grid lives in the deformed cell, so ∇U is taken with respect to the current positions:
  // u = (F - I) F^-1 x, ∇u = I - F^-1 (= F - I to first order), ε its symmetric part.
  const Mat3 Fi = F.inverse();
  double expect[9];
  for (int c = 0; c < 9; ++c) {
    const int r = c / 3, s = c % 3;
    expect[c] = 0.5 * ((r == s) * 2.0 - Fi(r, s) - Fi(s, r));
  }
  double worst = 0;
  for (std::size_t n = 0; n < f.points.size(); ++n)
    for (int c = 0; c < 9; ++c) worst = std::max(worst, std::abs(f.strain[9 * n + c] - expect[c]) / 0.002);
  std::printf("strain: %.3e\n", worst);
  EXPECT_LT(worst, 1e-6);
}

TEST(Balance, StretchedBondsGiveTheLoveStressOfTheirStiffness) {
  // Bonds of radius a_b = 0.2 R on the lattice, stretched by ε along x only. Like phases:
  // k_n = E a_b g_n/(1 - ν²), g_n = 1 + 4 (a_b/R)² (docs/physics.md#bond-stiffness).
  const double eps = 1e-3, R = 0.5 * kA, ab = 0.2 * R, E = 1e9, nu = 0.25;
  const Packing ref = spring_lattice(6, kA, Mat3::identity(), 0, kRho);
  Packing p = spring_lattice(6, kA, Mat3::diagonal({1 + eps, 1, 1}), 0, kRho);
  for (std::size_t c = 0; c < ref.contacts.size(); ++c) {
    p.bonds.i.push_back(ref.contacts.i[c]);
    p.bonds.j.push_back(ref.contacts.j[c]);
    p.bonds.radius.push_back(ab);
    p.bonds.rest_length.push_back(kA);
    p.bonds.state.push_back(0);
    p.bonds.broken_at.push_back(NAN);
  }
  p.contacts = ContactTable{};
  const double kn = E * ab * (1 + 4 * (ab / R) * (ab / R)) / (1 - nu * nu);
  const double sxx = kn * eps * (1 + eps) / (kA * (1 + eps));  // -(1/V_p)(-k_n a ε)(a(1 + ε))
  std::string source;
  const Snapshot s = make_snapshot(p, "bonded", SnapshotOptions{}, nullptr, "", &source);
  EXPECT_EQ(source, "stretch");
  Accumulator acc(Kernel::make(KernelType::gaussian, 1.5 * kA, 6), full(10), s.cell, 0, 2);
  acc.add(s);
  const auto f = acc.fields();
  for (std::size_t n = 0; n < f.points.size(); ++n) {
    EXPECT_NEAR(f.stress_bond[9 * n], sxx, 1e-6 * sxx);
    EXPECT_NEAR(f.stress[9 * n + 4], 0, 1e-6 * sxx);
  }
}
}  // namespace
