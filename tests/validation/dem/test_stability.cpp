// Time step and stability: a step above the stable limit is refused (InputError) or, where
// the two-particle estimate is not enough, caught while running (NumericalError); stiff and
// strongly polydisperse scenes run on the automatic step without blowing up.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "packings.hpp"
#include "tomodem/core/error.hpp"

using namespace tomodem;
using namespace tomodem::dem;
using namespace tomodem::dem::testing;

namespace {
constexpr double rho = 2500, nu = 0.25;
constexpr double kSafety = 0.2;  // the automatic step: critical_time_step() × 0.2

ContactModel linear_model(double kn, double e) {
  ContactModel m;
  m.normal = NormalLaw::linear;
  m.materials = {material(1e8, nu, rho)};
  m.finalize();
  m.pair(0, 0).k_n = kn;
  m.pair(0, 0).restitution = e;
  m.finalize();
  return m;
}
}  // namespace

TEST(TimeStep, OneAndAHalfTimesStableStepIsRefused) {
  const double R = 1e-3;
  LatticeSpec s;
  s.n = 3;
  s.radius = R;
  s.polydispersity = 0.2;
  for (const ContactModel& m : {model(NormalLaw::hertz, TangentialLaw::mindlin, material(1e8, nu, rho), 0.5, 0.3),
                                model(NormalLaw::hertz_jkr, TangentialLaw::none, material(1e8, nu, rho, 0.05), 1.0),
                                linear_model(1e4, 0.5), linear_model(1e4, 1.0)}) {
    Simulation sim = lattice(m, s);
    const double crit = sim.critical_time_step();
    ASSERT_TRUE(std::isfinite(crit) && crit > 0) << m.describe();
    EXPECT_THROW(sim.set_time_step(1.5 * crit), InputError) << m.describe();
    EXPECT_NO_THROW(sim.set_time_step(crit)) << m.describe();
  }
}

// "Caught": the linear law's limit 2 sqrt(m*/k) is exact for two particles, but a network is
// stiffer. A compressed periodic simple-cubic lattice (every particle pressed by its six
// neighbours) vibrates along each axis as a chain, ω_max = 2 sqrt(k/m), whose Verlet limit
// sqrt(m/k) is 0.707 × critical_time_step(). At 0.99 × critical_time_step() the set-up is
// accepted, the run is unstable, and it must stop with NumericalError (not produce garbage).
TEST(TimeStep, NetworkInstabilityAboveTheChainLimitIsCaught) {
  const double R = 1e-3;
  LatticeSpec s;
  s.n = 4;
  s.radius = R;
  s.spacing = 1.98;  // every particle overlaps its 6 neighbours by 0.02 R
  s.speed = 1e-3;    // seeds every mode
  Simulation sim = lattice(linear_model(1e4, 1.0), s);
  sim.set_time_step(0.99 * sim.critical_time_step());
  EXPECT_THROW(sim.run(20000), NumericalError);
}

// E = 400 GPa, R = 0.1 µm (t_Rayleigh ≈ 5e-11 s): a compressed periodic packing of 64 spheres
// (±20%, initial overlaps up to ~5% R) with random velocities and Hertz–Mindlin friction, run
// 3000 steps on the automatic step. No NumericalError, and the mechanical energy never
// exceeds its initial value (damped, frictional: it can only fall; 1e-3 for the O(Δt²)
// fluctuation of the measured energy).
TEST(TimeStep, StiffNanoscalePackingRunsStablyOnAutomaticStep) {
  const double R = 0.1e-6;
  const ContactModel m = model(NormalLaw::hertz, TangentialLaw::mindlin, material(400e9, nu, 4000), 0.7, 0.5);
  LatticeSpec s;
  s.n = 4;
  s.radius = R;
  s.polydispersity = 0.2;
  s.spacing = 2.0;
  s.jitter = 0.05;
  s.speed = 1.0;
  s.density = 4000;
  Simulation sim = lattice(m, s);
  sim.set_time_step(kSafety * sim.critical_time_step());
  const double e0 = mechanical_energy(sim);
  double emax = e0;
  EXPECT_NO_THROW({
    for (int k = 0; k < 30; ++k) {
      sim.run(100);
      emax = std::max(emax, mechanical_energy(sim));
    }
  });
  report("stiff: max E / E0", emax / e0);
  EXPECT_LE(emax / e0, 1.0 + 1e-3);
  EXPECT_LT(sim.measure().max_overlap_ratio, 0.1);
}

// Size ratio 1:20: a heavy sphere (R = 20 r, 8000× the mass of a small one) dropped onto a
// layer of 400 small spheres on a wall (periodic in x and y). The small spheres are squeezed
// between a huge mass and the wall, the stiffest, fastest modes of the scene. The automatic
// step comes from the smallest particle. The run covers the impact and rebound of the big
// sphere; no NumericalError, and E_kin + E_el − W_gravity never exceeds its initial value by
// more than 1e-3 (the scene is damped: e = 0.5, μ = 0.3).
TEST(TimeStep, SizeRatioOneToTwentyRunsStablyOnAutomaticStep) {
  const double r = 1e-4, big = 20 * r;
  const ContactModel m = model(NormalLaw::hertz, TangentialLaw::mindlin, material(1e9, nu, rho), 0.5, 0.3);
  Particles p;
  const int n = 20;
  const double a = 2.1 * r, L = n * a;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) p.add({(i + 0.5) * a, (j + 0.5) * a, r}, r, rho, 0);
  const std::size_t b = p.add({0.5 * L, 0.5 * L, 2 * r + big + 0.1 * r}, big, rho, 0);
  p.v[b] = {0, 0, -0.5};
  Cell c = Cell::box({0, 0, -5 * r}, {L, L, 2 * big + 10 * r}, true);
  c.periodic[2] = false;
  Simulation sim(std::move(p), c, m);
  Wall floor;
  floor.normal = {0, 0, 1};
  sim.add_wall(floor);
  const Vec3 g{0, 0, -9.81};
  sim.body_forces().gravity = g;
  sim.set_time_step(kSafety * sim.critical_time_step());
  auto energy = [&] {
    const Measurements me = sim.measure();
    double pot = 0;
    const Particles& q = sim.particles();
    for (std::size_t i = 0; i < q.size(); ++i) pot -= q.m[i] * dot(g, q.x[i]);
    return me.kinetic_energy + me.elastic_energy + pot;
  };
  const double e0 = energy();
  const double ek0 = 0.5 * sim.particles().m[b] * 0.25;
  double emax = e0;
  double zmin = sim.particles().x[b].z;
  EXPECT_NO_THROW({
    for (int k = 0; k < 40; ++k) {
      sim.run(100);
      emax = std::max(emax, energy());
      zmin = std::min(zmin, sim.particles().x[b].z);
    }
  });
  report("1:20: max (E - E0) / E_kin,big", (emax - e0) / ek0);
  report("1:20: deepest big-sphere centre below first touch / r", (2 * r + big - zmin) / r);
  EXPECT_LT(zmin, 2 * r + big) << "the big sphere must hit the layer";
  EXPECT_LE((emax - e0) / ek0, 1e-3);
}
