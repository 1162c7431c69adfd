// The neck conductance at large necks (issue 18 item 7): periodic SC, BCC and FCC arrays of equal
// overlapping spheres, the network against the converged voxel solution of the same array.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "tomodem/dem/scene.hpp"
#include "tomodem/network/conductivity.hpp"
#include "tomodem/network/voxel.hpp"
#include "tomodem/spatial/union_volume.hpp"

using namespace tomodem;
using namespace tomodem::network;

namespace {

/// One cubic cell (n = 1) or n³ cells of the lattice with nearest-neighbour necks of radius a
/// (R = 1, σ = 1): nearest distance L = 2√(1 − a²); cell constant c from L.
Packing neck_array(dem::LatticeKind kind, double a, int n) {
  const double L = 2 * std::sqrt(1 - a * a);
  const double c = kind == dem::LatticeKind::simple_cubic ? L : kind == dem::LatticeKind::bcc ? 2 * L / std::sqrt(3.0)
                                                                                              : L * std::sqrt(2.0);
  Packing p;
  for (const Vec3& x : dem::lattice_sites(kind, n, c)) {
    p.particles.position.push_back(x);
    p.particles.radius.push_back(1.0);
    p.particles.phase.push_back(0);
  }
  p.cell = Cell::box({0, 0, 0}, {n * c, n * c, n * c}, true);
  Material m;
  m.name = "solid";
  m.conductivity = 1.0;
  p.materials = {m};
  return p;
}

/// σ_xx of the periodic network with the law "isolated_necks", "face_capped" or "flux_tube".
double network_sigma(const Packing& p, const std::string& law) {
  NetworkOptions o;
  o.face_cap = law != "isolated_necks";
  o.flux_tube = law == "flux_tube";
  ConductOptions co;
  co.solver.tolerance = 1e-12;
  return solve_periodic(build_network(p, o), co).sigma[0][0];
}

}  // namespace

// The reference study (TOMODEM_NECK_STUDY=1): voxel solutions at 32, 64, 128 voxels per cubic
// cell edge and their Richardson extrapolation, next to the network.
TEST(NeckLaw, VoxelReferenceStudy) {
  if (!std::getenv("TOMODEM_NECK_STUDY")) GTEST_SKIP() << "set TOMODEM_NECK_STUDY=1";
  const dem::LatticeKind kinds[] = {dem::LatticeKind::simple_cubic, dem::LatticeKind::bcc, dem::LatticeKind::fcc};
  std::printf("| lattice | a/R | rho | HS | flux tube | face-capped | isolated | v32 | v64 | v128 | extrapolated | order | error |\n");
  const std::vector<double> overlaps[] = {{0.3, 0.4, 0.5, 0.6, 0.7, 0.8}, {0.3, 0.4, 0.5, 0.55}, {0.3, 0.35, 0.4, 0.45}};
  for (int l = 0; l < 3; ++l)
    for (double a : overlaps[l]) {
      const dem::LatticeKind kind = kinds[l];
      const Packing cell = neck_array(kind, a, 1);
      const Packing net = neck_array(kind, a, 2);
      const double rho = spatial::union_relative_density(net.particles.position, net.particles.radius, net.cell);
      double s[3];
      int k = 0;
      for (int res : {32, 64, 128}) {
        VoxelOptions o;
        o.resolution = res;
        o.solver.tolerance = 1e-10;
        s[k++] = voxel_conductivity(cell, o).sigma_eff;
      }
      double order = 0, err = 0;
      const double x = richardson(s[0], s[1], s[2], 2.0, &order, &err);
      std::printf("| %s | %.2f | %.4f | %.4f | %.5f | %.5f | %.5f | %.5f | %.5f | %.5f | %.5f | %.2f | %.1e |\n",
                  dem::to_string(kind), a, rho, 2 * rho / (3 - rho), network_sigma(net, "flux_tube"),
                  network_sigma(net, "face_capped"), network_sigma(net, "isolated_necks"),
                  s[0], s[1], s[2], x, order, err);
      std::fflush(stdout);
    }
}

// The converged references (TOMODEM_NECK_STUDY=1, 32/64/128 voxels per cubic cell edge,
// Richardson; measured once): σ/σ_s of the array with nearest-neighbour necks a/R, and the
// extrapolation's error estimate.
struct Reference {
  dem::LatticeKind kind;
  double a, sigma, error;
};
constexpr Reference kReferences[] = {
    {dem::LatticeKind::simple_cubic, 0.30, 0.28657, 1.3e-2}, {dem::LatticeKind::simple_cubic, 0.40, 0.40812, 5.2e-3},
    {dem::LatticeKind::simple_cubic, 0.50, 0.55681, 1.2e-3}, {dem::LatticeKind::simple_cubic, 0.60, 0.74105, 7.2e-5},
    {dem::LatticeKind::simple_cubic, 0.70, 0.93166, 2.4e-5}, {dem::LatticeKind::simple_cubic, 0.80, 0.99960, 1.3e-4},
    {dem::LatticeKind::bcc, 0.30, 0.51451, 1.5e-2},          {dem::LatticeKind::bcc, 0.40, 0.65536, 6.2e-3},
    {dem::LatticeKind::bcc, 0.50, 0.82335, 3.7e-2},          {dem::LatticeKind::bcc, 0.55, 0.95243, 1.1e-2},
    {dem::LatticeKind::fcc, 0.30, 0.66146, 2.0e-2},          {dem::LatticeKind::fcc, 0.35, 0.74021, 9.4e-3},
    {dem::LatticeKind::fcc, 0.40, 0.81252, 6.3e-3},          {dem::LatticeKind::fcc, 0.45, 0.88068, 3.8e-3}};

// The flux-tube law against the references: within −19 % … +3 % everywhere (measured −16.7 % …
// +1.8 %, the largest on BCC below its full density; SC and FCC within −5.2 % … +1.8 %), and never above the Hashin–Shtrikman bound 2ρ/(3 − ρ) of the array (cubic symmetry
// makes σ isotropic, so the bound holds for it; ρ the union density); 1e-3 of slack for the
// union-density estimate where the array is solid (SC at a/R 0.8: ρ = 0.9998, σ = σ_s). The old
// face cap exceeds the bound on 6 of the 14 arrays (SC at 0.7, BCC at 0.55, every FCC), so the
// check can fail.
// A live voxel solve on the coarsest grid reproduces the stored study (FCC at a/R 0.4, 32 voxels:
// 0.83596; 1e-4 covers the CG tolerance).
TEST(NeckLaw, FluxTubeFollowsTheVoxelReferenceUnderTheBound) {
  int old_over = 0;
  for (const Reference& r : kReferences) {
    const Packing net = neck_array(r.kind, r.a, 2);
    const double rho = spatial::union_relative_density(net.particles.position, net.particles.radius, net.cell);
    const double hs = 2 * rho / (3 - rho), law = network_sigma(net, "flux_tube");
    old_over += network_sigma(net, "face_capped") > hs + 1e-3;
    std::printf("%s a/R %.2f: flux tube %.4f, voxel %.4f (%+.1f %%), HS %.4f\n", dem::to_string(r.kind), r.a, law, r.sigma,
                100 * (law / r.sigma - 1), hs);
    EXPECT_GT(law / r.sigma, 0.81) << dem::to_string(r.kind) << " " << r.a;
    EXPECT_LT(law / r.sigma, 1.03) << dem::to_string(r.kind) << " " << r.a;
    EXPECT_LE(law, hs + 1e-3) << dem::to_string(r.kind) << " " << r.a;
  }
  EXPECT_EQ(old_over, 6);
  VoxelOptions o;
  o.resolution = 32;
  o.solver.tolerance = 1e-10;
  EXPECT_NEAR(voxel_conductivity(neck_array(dem::LatticeKind::fcc, 0.4, 1), o).sigma_eff, 0.83596, 1e-4);
}

// Small necks: the flux tube tends to Holm (a/R = 0.02 on SC, faces 10⁴ times the neck disc).
TEST(NeckLaw, SmallNecksKeepHolm) {
  const Packing p = neck_array(dem::LatticeKind::simple_cubic, 0.02, 2);
  const double holm = network_sigma(p, "isolated_necks"), law = network_sigma(p, "flux_tube");
  EXPECT_NEAR(law / holm, 1.0, 0.02);  // corrections of order a/R
}
