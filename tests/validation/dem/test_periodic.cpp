// A contact across a periodic boundary must act exactly like the same contact inside the cell:
// the image of j is x_j + H n with velocity u_j + L H n (affine field of a deforming cell).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "packings.hpp"

using namespace tomodem;
using namespace tomodem::dem;
using namespace tomodem::dem::testing;

namespace {
constexpr double R = 1e-3, rho = 2500, E = 1e8, nu = 0.25;

struct Trace {
  std::vector<Vec3> force, torque;
};

/// Two spheres whose separation vector is d (so that they touch), particle 0 at x0, in the
/// cell `c` with velocity gradient L; relative tangential velocity makes friction history.
Trace run_pair(const Cell& c, const Mat3& L, const Vec3& x0, const Vec3& d, const Vec3& drift, long steps) {
  const ContactModel m = model(NormalLaw::hertz, TangentialLaw::mindlin, material(E, nu, rho), 0.5, 0.4);
  Particles p;
  p.add(x0, R, rho, 0);
  p.add(x0 + d, R, rho, 0);
  p.v[0] = drift + Vec3{0.001, -0.002, 0.0005};
  p.v[1] = drift + Vec3{-0.001, 0.0015, -0.0005};
  Simulation sim(std::move(p), c, m);
  sim.cell_control().velocity_gradient = L;
  sim.set_time_step(0.02 * sim.critical_time_step());
  Trace t;
  for (long k = 0; k < steps; ++k) {
    sim.step();
    t.force.push_back(sim.particles().f[0]);
    t.torque.push_back(sim.particles().torque[0]);
  }
  return t;
}

/// Largest difference of the two traces relative to the largest force (torque) in them.
double worst(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  double scale = 0, diff = 0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    scale = std::max(scale, norm(a[k]));
    diff = std::max(diff, norm(a[k] - b[k]));
  }
  return scale > 0 ? diff / scale : 1.0;
}

/// Same pair: once in the middle of the cell, once near the upper x and z faces (an edge, so
/// the tilt of a sheared cell enters the image shift), both drifting at the same velocity.
/// The drift carries the second pair across the faces while in contact, through several
/// neighbour-list rebuilds (every ~20 steps with the default skin): the particles are wrapped
/// and the pair's image changes, and its friction history must follow it.
void compare(const Cell& c, const Mat3& L) {
  const Vec3 d{0.6 * R, 0.4 * R, 1.85 * R};  // |d| = 1.986 R: overlap 0.014 R
  const Vec3 centre = c.origin + 0.5 * (c.h.col(0) + c.h.col(1) + c.h.col(2));
  const Vec3 corner = c.origin + c.h * Vec3{0.93, 0.5, 0.88};
  const Vec3 drift{8.0, 0.0, 9.0};  // m/s: ~0.4 R in x and z over the run
  const long steps = 100;
  const Trace inside = run_pair(c, L, centre - 0.5 * d, d, drift, steps);
  const Trace across = run_pair(c, L, corner - 0.5 * d, d, drift, steps);
  ASSERT_GT(norm(inside.force.back()), 0) << "the pair must stay in contact";
  // Round-off: positions of magnitude L = 10 R enter an overlap of 0.014 R, so the relative
  // difference in force is ~1e-16 · L/δ ≈ 1e-13 per step; 100 steps of accumulated history stay
  // far below 1e-9. A lost history (reset spring) would differ by O(1).
  report("max |dF|/|F| across vs inside", worst(inside.force, across.force));
  report("max |dT|/|T| across vs inside", worst(inside.torque, across.torque));
  EXPECT_LT(worst(inside.force, across.force), 1e-9);
  EXPECT_LT(worst(inside.torque, across.torque), 1e-9);
}
}  // namespace

TEST(PeriodicBoundary, PairAcrossFacesActsAsInside) {
  const Cell c = Cell::box({0, 0, 0}, {10 * R, 10 * R, 10 * R}, true);
  compare(c, Mat3{});
}

// A sheared (tilted) cell that keeps deforming under a velocity gradient with shear and
// compression: the image shift H n and the image velocity L H n both change every step.
TEST(PeriodicBoundary, PairAcrossFacesOfShearedDeformingCellActsAsInside) {
  Cell c = Cell::box({0, 0, 0}, {10 * R, 10 * R, 10 * R}, true);
  c.h(0, 2) = 3 * R;  // z cell vector tilted along x
  c.h(1, 2) = -1 * R;
  Mat3 L;
  L(0, 2) = 2.0;    // 1/s: shear rate (relative velocity ~2 · 2R = 0.004 m/s across a pair)
  L(1, 1) = -0.5;   // lateral compression
  compare(c, L);
}

namespace {
/// JKR pair pulled apart by prescribed motion while drifting at 8–9 m/s: it is in tension
/// (δ_c < δ < 0) while one of the particles is wrapped across a face at a neighbour-list
/// rebuild. Returns the normal force on particle 0 per step.
std::vector<double> jkr_pull(const Vec3& x0, const Vec3& drift) {
  ContactModel m = model(NormalLaw::hertz_jkr, TangentialLaw::none, material(E, nu, rho), 1.0);
  m.pair(0, 0).work_of_adhesion = 0.1;
  m.finalize();
  const double es = m.pair(0, 0).E_star, rs = 0.5 * R;
  const double delta_c = -0.75 * std::cbrt(M_PI * M_PI * 0.01 * rs / (es * es));
  const Vec3 n{0.6, 0.0, 0.8};
  Particles p;
  p.add(x0, R, rho, 0);
  p.add(x0 + (2 * R + 0.5 * delta_c) * n, R, rho, 0);  // overlap +0.5|δ_c|: the contact forms
  p.set_motion(0, Motion::prescribed);
  p.set_motion(1, Motion::prescribed);
  Simulation sim(std::move(p), Cell::box({0, 0, 0}, {10 * R, 10 * R, 10 * R}, true), m);
  const double dt = 0.02 * sim.critical_time_step();
  sim.set_time_step(dt);
  const long steps = 100;
  // Open the gap from +0.5|δ_c| to −0.8|δ_c| (still above δ_c: in tension) over the run.
  const double v_sep = 1.3 * std::abs(delta_c) / (steps * dt);
  sim.particles().v[0] = drift - 0.5 * v_sep * n;
  sim.particles().v[1] = drift + 0.5 * v_sep * n;
  std::vector<double> fn;
  for (long k = 0; k < steps; ++k) {
    sim.step();
    fn.push_back(-dot(sim.particles().f[0], n));  // f on 0 = −fn n
  }
  return fn;
}
}  // namespace

// JKR hysteresis across a periodic face: the contact flag of a pair in tension must follow the
// pair when a rebuild wraps one of its particles (a lost flag drops the force to zero).
TEST(PeriodicBoundary, JKRPairInTensionKeepsItsContactAcrossFaces) {
  const Vec3 drift{8.0, 0.0, 9.0};
  const std::vector<double> inside = jkr_pull({4 * R, 5 * R, 4 * R}, drift);
  const std::vector<double> across = jkr_pull({8.5 * R, 5 * R, 7.8 * R}, drift);
  ASSERT_LT(inside.back(), 0) << "the pair must end in tension";
  double worst = 0, scale = 0;
  for (std::size_t k = 0; k < inside.size(); ++k) {
    scale = std::max(scale, std::abs(inside[k]));
    worst = std::max(worst, std::abs(inside[k] - across[k]));
  }
  report("JKR: max |dF_n| / max |F_n| across vs inside", worst / scale);
  // Same round-off argument as above (positions ~10 R against overlaps ~1e-4 R: ~1e-12).
  EXPECT_LT(worst / scale, 1e-9);
}
