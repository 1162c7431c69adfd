// Cross-path check (P9 of docs/architecture.md#code-conventions): the wall kernel and the pair kernel must give the same contact
// mechanics in the limit where they describe the same thing. A wall uses R* = R and m* = m; a
// fixed sphere of radius R_b = 1e5 R gives R* = R(1 − 1e-5) and m* = m exactly (fixed: infinite
// mass), and its surface departs from a plane by s²/(2R_b) over the contact patch.
#include <gtest/gtest.h>

#include <cmath>

#include "packings.hpp"

using namespace tomodem;
using namespace tomodem::dem;
using namespace tomodem::dem::testing;

namespace {
constexpr double R = 1e-3, rho = 2500, E = 1e8, nu = 0.25;
constexpr double Rb = 1e5 * R;

struct Impact {
  Vec3 v, omega;
  double max_force = 0;
};

/// An oblique impact with back-spin on a plane (wall) or on the top of the huge fixed sphere.
Impact impact(bool use_wall) {
  ContactModel m = model(NormalLaw::hertz, TangentialLaw::mindlin, material(E, nu, rho), 0.6, 0.3);
  Particles p;
  const double z0 = R + 0.05 * R;
  p.add({0, 0, z0}, R, rho, 0);
  p.enable_rotation();
  if (!use_wall) {
    p.add({0, 0, -Rb}, Rb, rho, 0);
    p.set_motion(1, Motion::fixed);
  }
  p.v[0] = {0.3, 0.1, -0.5};
  p.omega[0] = {50, -200, 30};
  Cell c = Cell::box({-3 * R, -3 * R, -2 * Rb - R}, {3 * R, 3 * R, 3 * R}, false);
  Simulation sim(std::move(p), c, m);
  if (use_wall) {
    Wall w;
    w.normal = {0, 0, 1};
    sim.add_wall(w);
  }
  sim.set_time_step(0.05 * sim.critical_time_step());
  Impact out;
  bool touched = false;
  for (long k = 0; k < 1000000; ++k) {
    sim.step();
    const Vec3 f = sim.particles().f[0];
    out.max_force = std::max(out.max_force, norm(f));
    const bool contact = norm(f) > 0;
    if (contact) touched = true;
    if (touched && !contact) break;
  }
  out.v = sim.particles().v[0];
  out.omega = sim.particles().omega[0];
  return out;
}
}  // namespace

// Differences of order R/R_b = 1e-5 are expected (R*, and the tilt of the sphere's normal over a
// contact patch of radius ~1e-2 R: s/R_b ~ 1e-7); positions ~R_b carry round-off 1e-16·R_b =
// 1e-11·R against overlaps ~1e-3 R (1e-8 relative). Tolerance 1e-4 relative to the incoming
// speed (and R × spin): a mismatch in law, damping mass or lever arm would be O(1e-1).
TEST(CrossPath, WallContactEqualsContactWithHugeFixedSphere) {
  const Impact w = impact(true), s = impact(false);
  const double vscale = 0.5, wscale = 0.5 / R;
  report("max force wall/sphere - 1", w.max_force / s.max_force - 1);
  report("max |dv| / v_in", norm(w.v - s.v) / vscale);
  report("max |d omega| R / v_in", norm(w.omega - s.omega) / wscale);
  EXPECT_NEAR(w.max_force / s.max_force, 1.0, 1e-4);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(w.v[k], s.v[k], 1e-4 * vscale) << "velocity component " << k;
    EXPECT_NEAR(w.omega[k], s.omega[k], 1e-4 * wscale) << "spin component " << k;
  }
  // The impact must exercise sliding and sticking: the rebound differs from the incidence.
  EXPECT_GT(w.v.z, 0.0);
  EXPECT_GT(std::abs(w.v.x - 0.3), 1e-3);
}
