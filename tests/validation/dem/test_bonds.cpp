// Bonded-particle networks in the DEM core, against lattice closed forms.
#include <gtest/gtest.h>

#include <cmath>

#include "scenes.hpp"
#include "tomodem/dem/bonds.hpp"
#include "tomodem/dem/scene.hpp"

using namespace tomodem;
using namespace tomodem::dem;
using namespace tomodem::dem::testing;

namespace {

// A periodic simple cubic lattice of touching spheres (spacing 2R), every neighbour pair bonded
// (3 bonds per particle) with a neck of radius a. Contacts are frictionless Hertz (they never
// act while the bonds hold: bonded pairs are excluded from the contact list).
struct BondedLattice {
  double R = 0.5e-3, rho = 2500, E = 1e9, nu = 0.25, a_over_R = 0.05;
  int n = 10;
  Simulation make(BondFailure failure = BondFailure::none, double zeta = 0.3) const {
    const double s = 2 * R;
    Particles p;
    for (const Vec3& x : lattice_sites(dem::LatticeKind::simple_cubic, n, s)) p.add(x, R, rho, 0);
    ContactModel m;
    m.normal = NormalLaw::hertz;
    m.materials = {material(E, nu, rho)};
    m.finalize();
    Simulation sim(std::move(p), Cell::box({0, 0, 0}, {n * s, n * s, n * s}, true), m, Settings{});
    BondSet bonds;
    auto index = [this](int x, int y, int z) { return ((x % n) * n + (y % n)) * n + (z % n); };
    for (int x = 0; x < n; ++x)
      for (int y = 0; y < n; ++y)
        for (int z = 0; z < n; ++z)
          for (int axis = 0; axis < 3; ++axis) {
            const int q[3] = {x + (axis == 0), y + (axis == 1), z + (axis == 2)};
            Vec3 image{0, 0, 0};
            for (int k = 0; k < 3; ++k)
              if (q[k] == n) image[k] = 1;  // the neighbour across the periodic face
            bonds.add(index(x, y, z), index(q[0], q[1], q[2]), image, a_over_R * R, s);
          }
    BondLaw law;
    law.E_star = m.pair(0, 0).E_star;
    law.G_star = m.pair(0, 0).G_star;
    law.damping_ratio = zeta;
    sim.set_bonds(bonds, {law}, failure);
    return sim;
  }
  /// k_n = 2E* a g_n = E a g_n/(1 − ν²) for like phases, g_n = 1 + 4 (a/R̄)², R̄ = R for equal
  /// spheres (docs/physics.md#bond-stiffness), written out from E and ν: the bond law's E* comes
  /// from ContactModel::finalize, so a wrong mixing rule or stiffness formula fails the tests.
  double kn(const Simulation&) const {
    const double a = a_over_R * R;
    return E * a * (1 + 4 * a_over_R * a_over_R) / (1 - nu * nu);
  }
};

}  // namespace

TEST(Bonds, LatticeBondCountAndStiffTimeStep) {
  BondedLattice L;
  Simulation sim = L.make();
  EXPECT_EQ(sim.bonds().size(), std::size_t(3 * L.n * L.n * L.n));
  // The bond's normal stiffness enters the critical step: 2 sqrt(m*/k_n) at most.
  const double mstar = 0.5 * L.rho * 4.0 / 3.0 * M_PI * std::pow(L.R, 3);
  EXPECT_LE(sim.critical_time_step(), 2 * std::sqrt(mstar / L.kn(sim)) * (1 + 1e-12));
}

// Uniaxial stress along z (lateral stresses servo-held at zero), quasi-static: bond dashpots
// ζ = 0.3, strain rate chosen so the loading takes ~50 elastic-wave transits. E is the slope
// between two strain levels (the constant viscous stress cancels), ν the lateral strain ratio.
// The SC lattice with normal bonds: E = k_n/(2R), ν = 0 (docs/physics.md#elastic-constants). Tolerance 0.5% (issue 5):
// the dynamic error at ~50 transits is below 1e-3.
TEST(Bonds, SimpleCubicLatticeUnderUniaxialStressHasKnOver2R) {
  BondedLattice L;
  Simulation sim = L.make();
  sim.set_time_step(0.2 * sim.critical_time_step());
  const double kn = L.kn(sim);
  const double E_expected = kn / (2 * L.R);
  const double mass = L.rho * 4.0 / 3.0 * M_PI * std::pow(L.R, 3);
  const double c = 2 * L.R * std::sqrt(kn / mass);  // wave speed of the bonded chain
  const double transit = L.n * 2 * L.R / c;
  CellControl& cc = sim.cell_control();
  cc.stress_controlled[0][0] = cc.stress_controlled[1][1] = true;
  cc.max_strain_rate = 1.0 / transit;
  const double rate = 1e-4 / (50 * transit);  // 1e-4 strain over 50 transits
  cc.velocity_gradient(2, 2) = rate;
  const long steps = long(50 * transit / sim.time_step());
  sim.run(steps / 2);
  const Measurements m1 = sim.measure();
  const double hz1 = sim.cell().h(2, 2), hx1 = sim.cell().h(0, 0);
  sim.run(steps / 2);
  const Measurements m2 = sim.measure();
  const double hz2 = sim.cell().h(2, 2), hx2 = sim.cell().h(0, 0);
  const double dez = std::log(hz2 / hz1), dex = std::log(hx2 / hx1);
  const double E = (m2.stress(2, 2) - m1.stress(2, 2)) / dez;
  EXPECT_NEAR(E / E_expected, 1.0, 0.005);
  EXPECT_NEAR(-dex / dez, 0.0, 0.005);                        // ν = 0
  EXPECT_NEAR(m2.stress(0, 0) / m2.stress(2, 2), 0.0, 0.01);  // lateral stress held at zero
}

// Stress failure criterion: under slow tension every bond along z carries F = k_n u; the
// lattice breaks when σ_bond = F/(π a²) reaches the tensile strength, i.e. at a macroscopic
// stress σ = σ_t π a²/(2R)². Tolerance 2%: the breaking step resolves the stress to
// ε̇ Δt_load-limited precision and the dynamic overshoot is below 1%.
TEST(Bonds, StressCriterionBreaksAtTensileStrength) {
  BondedLattice L;
  Simulation sim = L.make(BondFailure::stress, 0.3);
  BondLaw law = sim.bond_laws()[0];
  law.tensile_strength = 50e6;
  law.shear_strength = 1e12;
  sim.set_bond_laws({law});
  sim.set_time_step(0.2 * sim.critical_time_step());
  const double kn = L.kn(sim);
  const double mass = L.rho * 4.0 / 3.0 * M_PI * std::pow(L.R, 3);
  const double transit = L.n * 2 * L.R / (2 * L.R * std::sqrt(kn / mass));
  const double a = L.a_over_R * L.R;
  const double sigma_break = law.tensile_strength * M_PI * a * a / (4 * L.R * L.R);
  const double eps_break = sigma_break / (kn / (2 * L.R));
  sim.cell_control().velocity_gradient(2, 2) = eps_break / (100 * transit);
  double peak = 0;
  for (int k = 0; k < 4000 && sim.bond_events().empty(); ++k) {
    sim.run(long(transit / sim.time_step()) / 2 + 1);
    peak = std::max(peak, sim.measure().stress(2, 2));
  }
  ASSERT_FALSE(sim.bond_events().empty());
  EXPECT_NEAR(peak / sigma_break, 1.0, 0.02);
  EXPECT_EQ(sim.bonds().mode[sim.bond_events().front().bond], BondSet::tension);
}
