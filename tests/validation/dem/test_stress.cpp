// Love–Weber stress of a wall-confined packing against the wall forces. At static equilibrium
// Σ_i x_i ⊗ F_i = 0 for every particle, so the contact virial (pair branch vectors between
// centres, wall branch vectors from the centre to the wall plane) equals −Σ_walls F ⊗ p_wall:
// for frictionless walls σ_aa = −(force on the a-walls)/(area of the a-walls) exactly.
#include <gtest/gtest.h>

#include <cmath>

#include "packings.hpp"

using namespace tomodem;
using namespace tomodem::dem;
using namespace tomodem::dem::testing;

namespace {
constexpr double R = 1e-3, rho = 2500, E = 1e8, nu = 0.25;
}

// 64 polydisperse spheres (±20%) in a box of six walls: a packing with ~200 contacts, enough
// to involve every wall with several contacts and a disordered force network. The walls close
// in from a gas state until the packing is jammed, then stop; Cundall damping brings it to
// rest. The identity holds to the unbalanced force: with a mean residual force below 1e-5 of
// the mean contact force the error is ~1e-4; 2% is the tolerance.
TEST(LoveStress, WallConfinedPackingMatchesWallForcePerArea) {
  const ContactModel m = model(NormalLaw::hertz, TangentialLaw::none, material(E, nu, rho), 0.3);
  LatticeSpec s;
  s.n = 4;
  s.radius = R;
  s.polydispersity = 0.2;
  s.spacing = 2.6;
  s.jitter = 0.05;
  s.speed = 0.05;
  Particles p = lattice_particles(s);
  const double L = s.n * s.spacing * R;
  Simulation sim(std::move(p), Cell::box({0, 0, 0}, {L, L, L}, false), m);
  for (int k = 0; k < 3; ++k) {
    Wall lo, hi;
    lo.normal = {0, 0, 0};
    lo.normal[k] = 1;
    hi.normal = {0, 0, 0};
    hi.normal[k] = -1;
    hi.point[k] = L;
    sim.add_wall(lo);
    sim.add_wall(hi);
  }
  const double dt = 0.2 * sim.critical_time_step();
  sim.set_time_step(dt);
  // Close in at a wall speed that moves each wall by 1e-4 R per step, until the mean wall
  // pressure reaches the target (overlaps ~1e-3 R).
  const double v_wall = 1e-4 * R / dt;
  for (auto& w : sim.walls()) w.velocity = v_wall * w.normal;
  const double p_target = 2e4;  // Pa
  double p_walls = 0;
  for (int k = 0; k < 400 && p_walls < p_target; ++k) {
    sim.run(50);
    const Measurements me = sim.measure();
    double fsum = 0, area = 0;
    for (std::size_t w = 0; w < sim.walls().size(); ++w) fsum += -dot(me.wall_forces[w], sim.walls()[w].normal);
    const double side = sim.walls()[1].point.x - sim.walls()[0].point.x;
    area = 6 * side * side;
    p_walls = fsum / area;
  }
  ASSERT_GE(p_walls, p_target) << "the packing did not jam";
  for (auto& w : sim.walls()) w.velocity = {0, 0, 0};
  sim.body_forces().local_damping = 0.7;
  Measurements me;
  for (int k = 0; k < 400; ++k) {
    sim.run(100);
    me = sim.measure();
    if (me.unbalanced_force_ratio < 1e-5) break;
  }
  ASSERT_LT(me.unbalanced_force_ratio, 1e-5) << "no static equilibrium";
  report("unbalanced force ratio", me.unbalanced_force_ratio);
  report("contacts", double(me.contacts));
  report("wall contacts", double(me.wall_contacts));
  ASSERT_GT(me.wall_contacts, 12);
  const Vec3 lo{sim.walls()[0].point.x, sim.walls()[2].point.y, sim.walls()[4].point.z};
  const Vec3 hi{sim.walls()[1].point.x, sim.walls()[3].point.y, sim.walls()[5].point.z};
  const Vec3 ext = hi - lo;
  EXPECT_NEAR(me.volume / (ext.x * ext.y * ext.z), 1.0, 1e-12) << "volume of the box between the walls";
  for (int k = 0; k < 3; ++k) {
    const double area = ext.x * ext.y * ext.z / ext[k];
    // Force the particles exert on the two walls of axis k, compressive positive; averaged.
    const double f_lo = -dot(me.wall_forces[2 * k], sim.walls()[2 * k].normal);
    const double f_hi = -dot(me.wall_forces[2 * k + 1], sim.walls()[2 * k + 1].normal);
    const double wall_stress = 0.5 * (f_lo + f_hi) / area;
    report("axis " + std::to_string(k) + ": -sigma_kk / (F_wall/A) - 1", -me.stress(k, k) / wall_stress - 1);
    EXPECT_NEAR(-me.stress(k, k) / wall_stress, 1.0, 0.02) << "axis " << k;
    EXPECT_NEAR(f_lo / f_hi, 1.0, 0.02) << "opposite walls balance, axis " << k;
  }
}
