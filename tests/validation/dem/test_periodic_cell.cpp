// The deforming periodic cell and its stress servo, against a lattice with a closed form.
#include <gtest/gtest.h>

#include <cmath>

#include "scenes.hpp"
#include "tomodem/dem/scene.hpp"

using namespace tomodem;
using namespace tomodem::dem;
using namespace tomodem::dem::testing;

namespace {
// A simple cubic lattice (n³ spheres, radius R, spacing a = 2R - δ0) pre-compressed so every
// contact overlaps by δ0, linear frictionless contacts of stiffness k_n. Along a lattice axis
// each contact column carries F = k_n δ over a cross-section a², so σ = -k_n δ/a² and,
// straining the cell by ε along z, Δσ_zz = k_n a ε/a²: E = k_n/a (→ k_n/2R), ν = 0.
struct Lattice {
  double R = 0.5e-3, kn = 1e4, rho = 2500, delta0 = 1e-6;
  int n = 4;
  double a() const { return 2 * R - delta0; }
  double prestress() const { return -kn * delta0 / (a() * a()); }
  Simulation make(double zeta) const {
    const double a = 2 * R - delta0;
    Particles p;
    for (const Vec3& x : lattice_sites(dem::LatticeKind::simple_cubic, n, a)) p.add(x, R, rho, 0);
    ContactModel m;
    m.normal = NormalLaw::linear;
    m.materials = {material(1e8, 0.25, rho)};
    m.finalize();
    m.pair(0, 0).k_n = kn;
    m.pair(0, 0).damping_ratio = zeta;
    m.finalize();
    Settings s;
    s.skin = 0.1 * R;
    return Simulation(std::move(p), Cell::box({0, 0, 0}, {n * a, n * a, n * a}, true), m, s);
  }
};
}  // namespace

// Uniaxial strain at a constant rate with heavy contact damping (ζ = 0.7) so the lattice
// follows the affine field. The dashpots add a constant viscous stress (η ε̇ a / a², about 1%
// of Δσ here); E is the slope between two strain levels, where that offset cancels. The
// elastic-wave transit takes ~5e-5 s against a loading time of 1e-3 s, so inertia is below
// 1e-3: tolerance 0.5%.
TEST(PeriodicCell, UniaxialStrainOfSimpleCubicLatticeGivesKnOver2R) {
  Lattice L;
  Simulation sim = L.make(0.7);
  const double mstar = 0.5 * L.rho * 4.0 / 3.0 * M_PI * std::pow(L.R, 3);
  const double tc = M_PI * std::sqrt(mstar / L.kn);
  sim.set_time_step(tc / 50);
  const Measurements m0 = sim.measure();
  const double s0 = L.prestress();
  EXPECT_NEAR(m0.stress_contact(2, 2) / s0, 1.0, 1e-9);  // the pre-stress itself, exact
  sim.cell_control().velocity_gradient(2, 2) = -1.0;  // 1/s: compress along z
  const double h0 = sim.cell().h(2, 2);
  sim.run(1000);
  const Measurements m1 = sim.measure();
  const double h1 = sim.cell().h(2, 2);
  sim.run(1000);
  const Measurements m2 = sim.measure();
  const double h2 = sim.cell().h(2, 2);
  // Spacing change per contact a(h/h0 - 1): Δσ = -k_n Δa/a² (the lattice follows the cell).
  const double E = (m2.stress_contact(2, 2) - m1.stress_contact(2, 2)) / ((h2 - h1) / h0);
  EXPECT_NEAR(E / (L.kn / L.a()), 1.0, 0.005) << "strain " << (h2 - h0) / h0;
  // Lateral contacts keep their force (ν = 0); their cross-section a_y a_z shrinks with the cell.
  EXPECT_NEAR(m2.stress_contact(0, 0) / (s0 * h0 / h2), 1.0, 1e-6);
}

// Mixed control: lateral stresses servo-held at targets while z is strained. The servo must
// bring σ_xx and σ_yy to their targets (1% of the target) and keep them there.
TEST(PeriodicCell, StressServoHoldsLateralStressesAtTarget) {
  Lattice L;
  Simulation sim = L.make(0.7);
  const double mstar = 0.5 * L.rho * 4.0 / 3.0 * M_PI * std::pow(L.R, 3);
  sim.set_time_step(M_PI * std::sqrt(mstar / L.kn) / 50);
  const double s0 = L.prestress();
  CellControl& cc = sim.cell_control();
  const double target = 0.5 * s0;  // half the pre-stress: the servo must expand x and y
  cc.stress_controlled[0][0] = cc.stress_controlled[1][1] = true;
  cc.target_stress(0, 0) = cc.target_stress(1, 1) = target;
  cc.max_strain_rate = 5.0;
  cc.velocity_gradient(2, 2) = -0.5;
  sim.run(4000);
  const Measurements m = sim.measure();
  EXPECT_NEAR(m.stress_contact(0, 0) / target, 1.0, 0.01);
  EXPECT_NEAR(m.stress_contact(1, 1) / target, 1.0, 0.01);
  // Along x the overlap now follows the target: δ_x = -σ a_y a_z / k_n (a_y = a_x, a_z from the cell).
  const double ax = sim.cell().h(0, 0) / L.n, az = sim.cell().h(2, 2) / L.n;
  const double delta_x = 2 * L.R - ax;
  EXPECT_NEAR(delta_x / (-target * ax * az / L.kn), 1.0, 0.01);
}
