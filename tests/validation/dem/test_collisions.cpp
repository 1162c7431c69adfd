// Binary collisions against closed forms (docs/physics.md#hertz, Johnson 1985).
#include <gtest/gtest.h>

#include <cmath>

#include "scenes.hpp"

using namespace tomodem;
using namespace tomodem::dem;
using namespace tomodem::dem::testing;

namespace {
constexpr double R = 1e-3, rho = 2500, E = 1e8, nu = 0.25;
// E* of two spheres of one material, E/(2(1 − ν²)) (docs/physics.md#notation), written out here
// rather than read from ContactModel::finalize so that a wrong mixing rule fails these tests.
constexpr double kEstar = E / (2 * (1 - nu * nu));
}

// The mixing rules of ContactModel::finalize against hand arithmetic (docs/physics.md#notation):
// steel E = 210 GPa, ν = 0.3 (G = E/2.6) on glass E = 70 GPa, ν = 0.2 (G = E/2.4):
//   1/E* = 0.91/210e9 + 0.96/70e9 = 3.79/210e9,  E* = 210e9/3.79 Pa,
//   1/G* = 1.7·2.6/210e9 + 1.8·2.4/70e9 = 17.38/210e9,  G* = 210e9/17.38 Pa,
// like phases E* = E/(2(1 − ν²)), G* = G/(2(2 − ν)); w = 2 sqrt(γ_a γ_b) = 2 sqrt(1·0.25) = 1 J/m².
// Only round-off separates the two evaluations: tolerance 1e-12 relative.
TEST(ContactModelMixing, EffectiveModuliAndWorkOfAdhesionMatchHandValues) {
  ContactModel m;
  m.normal = NormalLaw::hertz;
  m.materials = {material(210e9, 0.3, 7800, 1.0), material(70e9, 0.2, 2500, 0.25)};
  m.n_phases = 2;
  m.finalize();
  const double tol = 1e-12;
  EXPECT_NEAR(m.pair(0, 1).E_star / (210e9 / 3.79), 1.0, tol);
  EXPECT_NEAR(m.pair(1, 0).E_star / (210e9 / 3.79), 1.0, tol);
  EXPECT_NEAR(m.pair(0, 1).G_star / (210e9 / 17.38), 1.0, tol);
  EXPECT_NEAR(m.pair(0, 0).E_star / (210e9 / (2 * 0.91)), 1.0, tol);
  EXPECT_NEAR(m.pair(0, 0).G_star / (210e9 / 2.6 / (2 * 1.7)), 1.0, tol);
  EXPECT_NEAR(m.pair(1, 1).E_star / (70e9 / (2 * 0.96)), 1.0, tol);
  EXPECT_NEAR(m.pair(1, 1).G_star / (70e9 / 2.4 / (2 * 1.8)), 1.0, tol);
  EXPECT_NEAR(m.pair(0, 1).work_of_adhesion, 1.0, tol);
  EXPECT_NEAR(m.pair(0, 0).work_of_adhesion, 2.0, tol);
}

// Undamped Hertz: duration 2.868 (m*²/(R* E*² v))^{1/5} and δ_max = (15 m* v²/(16 E* sqrt(R*)))^{2/5}.
// Δt = t_c/2000: Verlet's error in δ_max and in the interpolated contact times is O(Δt²) and
// well below 1e-4; 1% is the tolerance and leaves room for the constant 2.868 (4 digits).
TEST(NormalHertz, HeadOnDurationAndMaxOverlapMatchJohnson) {
  const Material mat = material(E, nu, rho);
  const ContactModel m = model(NormalLaw::hertz, TangentialLaw::none, mat, 1.0);
  for (double v : {0.01, 0.1, 1.0}) {
    Simulation sim = head_on(m, R, rho, 1e-7, v);
    const double mass = rho * 4.0 / 3.0 * M_PI * R * R * R;
    const double ms = 0.5 * mass, rs = 0.5 * R;
    const double es = kEstar;
    const double tc = 2.868 * std::pow(ms * ms / (rs * es * es * v), 0.2);
    const double dmax = std::pow(15 * ms * v * v / (16 * es * std::sqrt(rs)), 0.4);
    sim.set_time_step(tc / 2000);
    const Collision c = collide(sim, v);
    EXPECT_NEAR(c.duration / tc, 1.0, 0.01) << "v = " << v;
    EXPECT_NEAR(c.max_overlap / dmax, 1.0, 0.01) << "v = " << v;
    EXPECT_NEAR(c.restitution, 1.0, 1e-3) << "v = " << v;
  }
}

// Linear spring–dashpot: e = exp(-πζ/sqrt(1-ζ²)) exactly for the unclamped law. The damping
// force uses the half-step velocity, an O(Δt) error in the rebound speed of order ζ ω Δt v_in;
// at ζ = 0.7 the rebound is only 0.046 v_in, so 0.5% of it needs Δt ≈ t_c/10000.
TEST(NormalLinear, RestitutionMatchesDampingRatio) {
  for (double zeta : {0.05, 0.3, 0.7}) {
    ContactModel m;
    m.normal = NormalLaw::linear;
    m.materials = {material(E, nu, rho)};
    m.finalize();
    m.pair(0, 0).k_n = 1e4;
    m.pair(0, 0).damping_ratio = zeta;
    m.finalize();
    Simulation sim = head_on(m, R, rho, 1e-7, 0.1);
    const double mass = rho * 4.0 / 3.0 * M_PI * R * R * R;
    const double ms = 0.5 * mass;
    const double tc = M_PI / std::sqrt(1e4 / ms * (1 - zeta * zeta));
    sim.set_time_step(tc / 10000);
    const Collision c = collide(sim, 0.1);
    const double e = std::exp(-M_PI * zeta / std::sqrt(1 - zeta * zeta));
    EXPECT_NEAR(c.restitution / e, 1.0, 0.005) << "zeta = " << zeta;
  }
}

// Hertz with a requested restitution rebounds at it for every impact speed: the damping
// constant is calibrated once on the dimensionless collision (model.cpp); this test runs the
// full engine at speeds over two orders of magnitude. Δt = t_c/2000 (O(Δt²) error ~1e-5).
TEST(NormalHertz, ReboundsAtRequestedRestitutionForEverySpeed) {
  for (double e : {0.1, 0.5, 0.9}) {
    const ContactModel m = model(NormalLaw::hertz, TangentialLaw::none, material(E, nu, rho), e);
    for (double v : {0.01, 0.1, 1.0}) {
      Simulation sim = head_on(m, R, rho, 1e-7, v);
      const double mass = rho * 4.0 / 3.0 * M_PI * R * R * R;
      const double ms = 0.5 * mass, rs = 0.5 * R, es = kEstar;
      const double tc = 2.868 * std::pow(ms * ms / (rs * es * es * v), 0.2);
      sim.set_time_step(tc / 2000);
      const Collision c = collide(sim, v);
      EXPECT_NEAR(c.restitution / e, 1.0, 0.01) << "e = " << e << ", v = " << v;
    }
  }
}
