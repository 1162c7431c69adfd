// Image cross-check: the voxel finite-volume solution of the same structure.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "lattice.hpp"
#include "tomodem/network/conductivity.hpp"
#include "tomodem/network/voxel.hpp"

using namespace tomodem;
using namespace tomodem::network;

namespace {
// A random packing made from a jittered simple cubic lattice (spacing 2, 4×4×4 sites): centres
// moved by up to ±0.1 per axis, radii uniform in [1.10, 1.20], so every lattice neighbour overlaps
// (neck radius a/R ≈ 0.3–0.5) and no diagonal pair touches. Phase A, σ = 1 S/m.
Packing jittered(unsigned seed) {
  Packing p = test::sc_lattice(4, 4, 4, 1.0, 0.1, false);
  p.bonds = BondTable{};
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> j(-0.1, 0.1), r(1.10, 1.20);
  for (std::size_t k = 0; k < p.particles.size(); ++k) {
    p.particles.position[k] += Vec3(j(rng), j(rng), j(rng));
    p.particles.radius[k] = r(rng);
  }
  return p;
}
}  // namespace

// A box filled with one phase: the two-point flux scheme is exact for a uniform medium.
TEST(Voxel, UniformMediumIsExact) {
  Packing p = test::sc_lattice(2, 2, 2, 1.0, 0.1, false);
  for (auto& r : p.particles.radius) r = 2.0;  // spheres cover the whole box
  p.materials[0].conductivity = 3.5;
  VoxelOptions o;
  o.resolution = 12;
  o.solver.tolerance = 1e-12;
  const VoxelResult v = voxel_conductivity(p, o);
  EXPECT_DOUBLE_EQ(v.solid_fraction, 1.0);
  EXPECT_NEAR(v.sigma_eff, 3.5, 1e-9 * 3.5);
}

// Network and voxel answers for the same random packing. The voxel answer converges with the
// grid (differences shrink), and the network (Holm constrictions, geometric neck radius) agrees
// with the extrapolated voxel answer within the model error stated in docs/conduct.md: Holm's
// 1/(2σa) ignores the resistance of the particle bodies and the finite size of the necks, which
// for necks of a/R ≈ 0.3–0.5 is a 10–30 % effect. This sample gives +10 % (network 0.567,
// voxel 0.647 / 0.537 / 0.518 at 16 / 32 / 64 voxels, extrapolated 0.514 S/m); we assert 25 %.
TEST(Voxel, NetworkAndVoxelAgreeWithinModelErrorAndConverge) {
  const Packing p = jittered(42);
  const Network net = build_network(p, NetworkOptions{});
  ConductOptions co;
  co.solver.tolerance = 1e-10;
  const AxisResult a = solve_electrodes(net, 0, co);
  ASSERT_TRUE(a.percolates);
  std::vector<double> s;
  for (int res : {16, 32, 64}) {
    VoxelOptions o;
    o.resolution = res;
    o.solver.tolerance = 1e-10;
    const VoxelResult v = voxel_conductivity(p, o);
    ASSERT_TRUE(v.percolates);
    EXPECT_LT(v.conservation_error, 1e-6);
    s.push_back(v.sigma_eff);
  }
  EXPECT_LT(std::abs(s[2] - s[1]), std::abs(s[1] - s[0])) << s[0] << " " << s[1] << " " << s[2];
  double order = 0, err = 0;
  const double ext = richardson(s[0], s[1], s[2], 2.0, &order, &err);
  RecordProperty("network", std::to_string(a.sigma_eff));
  RecordProperty("voxel_extrapolated", std::to_string(ext));
  std::printf("network %.5g voxel %.5g %.5g %.5g extrapolated %.5g (order %.2f)\n", a.sigma_eff, s[0], s[1], s[2],
              ext, order);
  EXPECT_NEAR(a.sigma_eff, ext, 0.25 * ext);
}

// Validation of the converged cross-check on a structure with an independent answer: the simple
// cubic lattice of spheres (spacing 2, radius Rs = sqrt(1 + a²), so neighbours overlap in necks of
// radius a). By symmetry one period is a single sphere clipped by the cube [0, 2]³ (the faces
// normal to the axis are the neck planes, equipotential by symmetry; the others carry no flux),
// so the voxel cross-check solves that cube; the network is a two-sphere chain with one neck
// (Holm: G = 2σa, L = 2, A = 4, σ_net = σa). Grids of 16, 32, 64, 128 voxels per cube edge
// (18–143 voxels per diameter; the neck radius a = 0.5 spans 4–32 voxels).
// Measured: 0.48955, 0.47802, 0.47272, 0.47378; Richardson of 16/32/64: 0.46822, order 1.12.
// Centre sampling puts the narrowest voxel layer h/2 off the neck plane, so the imaged neck is
// a² + O(R h): first order, with a staircase oscillation once the error is ~1 % (the 128 grid
// lies above 64). Asserted: observed order > 0.5 on 16/32/64, the extrapolation agrees with the
// 128 grid within its own error estimate + 1 %, and the network lies within the Holm model
// error of the extrapolation: Holm's 1/(2σa) is the small-neck limit and ignores the sphere
// bodies, so for a/R = 0.45 the network is above the voxel answer (measured +7 %); we assert
// above, by at most 35 % (the bound stated in docs/conduct.md for a/R <= 0.5 is 25 %).
// A smaller neck (a = 0.25) does not converge on these grids (order 0 on 16/32/64): h must be
// well below a²/R, not just below a.
TEST(Voxel, SimpleCubicNeckLatticeConvergesAndHolmIsWithinModelError) {
  const double a = 0.5, Rs = std::sqrt(1.0 + a * a);
  Packing chain = test::sc_lattice(2, 1, 1, 1.0, a, false);
  const Network net = build_network(chain, NetworkOptions{});
  ConductOptions co;
  co.solver.tolerance = 1e-12;
  const AxisResult an = solve_electrodes(net, 0, co);
  ASSERT_TRUE(an.percolates);
  EXPECT_NEAR(an.sigma_eff, a, 1e-9);  // σa: Holm, one neck, L = 2, A = 4
  Packing cell = test::sc_lattice(1, 1, 1, 1.0, a, false);
  cell.bonds = BondTable{};
  cell.particles.radius[0] = Rs;
  std::vector<double> s;
  for (int res : {16, 32, 64, 128}) {
    VoxelOptions o;
    o.resolution = res;
    o.solver.tolerance = 1e-10;
    o.neck_radii = {a};
    const VoxelResult v = voxel_conductivity(cell, o);
    ASSERT_TRUE(v.percolates);
    EXPECT_LT(v.conservation_error, 1e-6);
    EXPECT_NEAR(v.neck_min_voxels, a * res / 2.0, 1e-12);
    EXPECT_EQ(v.necks_resolved, a * res / 2.0 >= kNeckVoxels);
    s.push_back(v.sigma_eff);
  }
  double p1 = 0, e1 = 0, p2 = 0, e2 = 0;
  const double x1 = richardson(s[0], s[1], s[2], 2.0, &p1, &e1);
  const double x2 = richardson(s[1], s[2], s[3], 2.0, &p2, &e2);
  std::printf("network %.5g voxel %.5g %.5g %.5g %.5g; extrapolated %.5g (order %.2f) %.5g (order %.2f)\n", an.sigma_eff,
              s[0], s[1], s[2], s[3], x1, p1, x2, p2);
  EXPECT_GT(p1, 0.5);
  EXPECT_NEAR(x1, s[3], e1 + 0.01 * s[3]);
  EXPECT_NEAR(an.sigma_eff, x1, 0.35 * x1);
  EXPECT_GT(an.sigma_eff, x1);
}
