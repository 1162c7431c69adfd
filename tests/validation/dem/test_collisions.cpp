// Binary collisions against closed forms (docs/physics.md#hertz, Johnson 1985).
#include <gtest/gtest.h>

#include <cmath>

#include "scenes.hpp"

using namespace tomodem;
using namespace tomodem::dem;
using namespace tomodem::dem::testing;

namespace {
constexpr double R = 1e-3, rho = 2500, E = 1e8, nu = 0.25;
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
    const double es = m.pair(0, 0).E_star;
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
      const double ms = 0.5 * mass, rs = 0.5 * R, es = m.pair(0, 0).E_star;
      const double tc = 2.868 * std::pow(ms * ms / (rs * es * es * v), 0.2);
      sim.set_time_step(tc / 2000);
      const Collision c = collide(sim, v);
      EXPECT_NEAR(c.restitution / e, 1.0, 0.01) << "e = " << e << ", v = " << v;
    }
  }
}
