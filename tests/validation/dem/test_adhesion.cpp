// Adhesive normal laws measured in the engine: two spheres, one fixed and one moved by
// prescribed motion, are pressed together and then pulled apart slowly; the force on the fixed
// sphere is recorded along the way (docs/physics.md#adhesion; JKR 1971, DMT 1975).
//   JKR: pull-off under load control = minimum of the force curve = −1.5 π w R*;
//        the contact breaks at δ_c = −(3/4)(π² w² R*/E*²)^{1/3}; it forms at δ = 0 (hysteresis).
//   DMT: pull-off = 2 π w R*, reached at δ = 0⁺.
// The expected values are written out here from the formulas, not taken from the engine's helpers.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "packings.hpp"

using namespace tomodem;
using namespace tomodem::dem;
using namespace tomodem::dem::testing;

namespace {
constexpr double R = 10e-6, rho = 2500, E = 1e8, nu = 0.25, w = 0.1;

struct Curve {
  double min_force_approach = 0;   ///< most tensile force while approaching (δ < 0 part must be 0)
  double first_touch_overlap = 0;  ///< overlap at the first non-zero force on approach
  double min_force_retract = 0;    ///< most tensile force while retracting, N
  double last_overlap_retract = 0; ///< overlap of the last sample with force (retracting)
  double force_at_max = 0;         ///< force at the deepest overlap
  double max_overlap = 0;
  double step = 0;                 ///< overlap change per step
};

/// Sphere 0 fixed at the origin, sphere 1 prescribed along +x: from a gap of `gap0` in to the
/// overlap `dmax`, then back out to the gap `gap1`, moving `dstep` per time step.
Curve press_and_pull(NormalLaw law, double gap0, double dmax, double gap1, double dstep) {
  ContactModel m = model(law, TangentialLaw::none, material(E, nu, rho), 1.0);
  m.pair(0, 0).work_of_adhesion = w;
  m.finalize();
  Particles p;
  p.add({0, 0, 0}, R, rho, 0);
  p.add({2 * R + gap0, 0, 0}, R, rho, 0);
  p.set_motion(0, Motion::fixed);
  p.set_motion(1, Motion::prescribed);
  Simulation sim(std::move(p), Cell::box({-10 * R, -10 * R, -10 * R}, {10 * R, 10 * R, 10 * R}, false), m);
  const double dt = 0.5 * sim.critical_time_step();
  sim.set_time_step(dt);
  const double v = dstep / dt;
  Curve c;
  c.step = dstep;
  c.max_overlap = dmax;
  auto overlap = [&] { return 2 * R - (sim.particles().x[1].x - sim.particles().x[0].x); };
  auto force = [&] { return -sim.particles().f[0].x; };  // f on 0 = −fn n, n = +x
  bool touched = false;
  sim.particles().v[1] = {-v, 0, 0};
  while (overlap() < dmax) {
    sim.step();
    const double fn = force();
    if (!touched && fn != 0) {
      touched = true;
      c.first_touch_overlap = overlap();
    }
    if (overlap() < 0) c.min_force_approach = std::min(c.min_force_approach, fn);
  }
  c.force_at_max = force();
  c.max_overlap = overlap();
  sim.particles().v[1] = {v, 0, 0};
  while (overlap() > -gap1) {
    sim.step();
    const double fn = force();
    c.min_force_retract = std::min(c.min_force_retract, fn);
    if (fn != 0) c.last_overlap_retract = overlap();
  }
  return c;
}
}  // namespace

// The force is a function of the overlap alone here (no damping: e = 1), sampled every
// |δ_c|/5000: the minimum of a smooth curve is found to O(step²) ~ 1e-8 and the break point to
// one step (2e-4 relative). 1% is the tolerance; the closed forms are exact.
TEST(AdhesionJKR, PullOffForceAndBreakDistanceMatchJohnsonKendallRoberts) {
  const double e_star = E / (2 * (1 - nu * nu));
  const double r_star = R / 2;
  const double delta_c = -0.75 * std::cbrt(M_PI * M_PI * w * w * r_star / (e_star * e_star));
  const double f_pull = 1.5 * M_PI * w * r_star;
  const Curve c = press_and_pull(NormalLaw::hertz_jkr, 0.5 * std::abs(delta_c), 3 * std::abs(delta_c),
                                 1.5 * std::abs(delta_c), std::abs(delta_c) / 5000);
  report("JKR pull-off / (1.5 pi w R*) - 1", -c.min_force_retract / f_pull - 1);
  report("JKR break overlap / delta_c - 1", c.last_overlap_retract / delta_c - 1);
  EXPECT_NEAR(-c.min_force_retract / f_pull, 1.0, 0.01) << "JKR pull-off 1.5 pi w R*";
  EXPECT_NEAR(c.last_overlap_retract / delta_c, 1.0, 0.01) << "JKR break overlap";
  // Hysteresis: no force before contact on approach; contact forms at δ = 0 (within a step).
  EXPECT_EQ(c.min_force_approach, 0.0);
  EXPECT_GE(c.first_touch_overlap, 0.0);
  EXPECT_LT(c.first_touch_overlap, 2 * c.step);
  // Deep in the contact the force follows the JKR parametric curve (a from δ = a²/R − sqrt(2πwa/E),
  // solved here by bisection, independently of the engine's Newton solver).
  double lo = std::sqrt(r_star * c.max_overlap), hi = 10 * lo;
  for (int it = 0; it < 200; ++it) {
    const double a = 0.5 * (lo + hi);
    (a * a / r_star - std::sqrt(2 * M_PI * w * a / e_star) < c.max_overlap ? lo : hi) = a;
  }
  const double a = 0.5 * (lo + hi);
  const double f_jkr = 4 * e_star * a * a * a / (3 * r_star) - std::sqrt(8 * M_PI * w * e_star * a * a * a);
  EXPECT_NEAR(c.force_at_max / f_jkr, 1.0, 1e-9) << "JKR force at the deepest overlap";
}

// DMT: the attraction 2πwR* acts while the surfaces overlap, so the most tensile force is
// reached at δ → 0⁺ where the Hertz part (4/3)E*sqrt(R*)δ^{3/2} vanishes; one sampling step of
// |δ_c|/5000 leaves a Hertz part of ~1e-6 of the pull-off. 1% is the tolerance.
TEST(AdhesionDMT, PullOffForceIsTwoPiWR) {
  const double r_star = R / 2;
  const double f_pull = 2 * M_PI * w * r_star;
  const double scale = 0.75 * std::cbrt(M_PI * M_PI * w * w * r_star / std::pow(E / (2 * (1 - nu * nu)), 2));
  const Curve c = press_and_pull(NormalLaw::hertz_dmt, 0.5 * scale, 3 * scale, 0.5 * scale, scale / 5000);
  report("DMT pull-off / (2 pi w R*) - 1", -c.min_force_retract / f_pull - 1);
  EXPECT_NEAR(-c.min_force_retract / f_pull, 1.0, 0.01) << "DMT pull-off 2 pi w R*";
  // DMT contacts end at δ = 0: no force once the surfaces separate, on approach or retraction.
  EXPECT_EQ(c.min_force_approach, 0.0);
  EXPECT_LE(std::abs(c.last_overlap_retract), 2 * c.step);
  const double e_star = E / (2 * (1 - nu * nu));
  const double f_dmt = 4.0 / 3.0 * e_star * std::sqrt(r_star) * std::pow(c.max_overlap, 1.5) - f_pull;
  EXPECT_NEAR(c.force_at_max / f_dmt, 1.0, 1e-9) << "DMT force at the deepest overlap";
}
