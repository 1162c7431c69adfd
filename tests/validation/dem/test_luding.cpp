// Luding's (2008) elasto-plastic adhesive normal law (docs/physics.md#luding-elasto-plastic-adhesive-law)
// in the engine, against its closed forms written out here:
//   loading f = k1 δ; unloading f = k2 (δ − δ0) with the plastic overlap δ0 = (1 − k1/k2) δ_max;
//   adhesive limit f = −kc δ below δ_min = (k2 − k1)/(k2 + kc) δ_max; reloading from there along
//   k2 through the current point; k2 = k1 + (kp − k1) δ_max/δ_max^p up to kp,
//   δ_max^p = kp/(kp − k1) φ_f 2R*;
//   head-on impact (no dashpot): δ_max = v0 sqrt(m*/k1),
//   e² = k1/k2 − (k2 − k1)² kc/(k1 k2 (k2 + kc)), sticking when e² ≤ 0.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "scenes.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/dem/law_registry.hpp"

using namespace tomodem;
using namespace tomodem::dem;
using namespace tomodem::dem::testing;

namespace {
constexpr double R = 1e-3, rho = 2500;
constexpr double k1 = 1e3, kp = 1e4;

ContactModel luding(double kc, double phi) {
  ContactModel m = model(NormalLaw{"luding"}, TangentialLaw::none, material(1e8, 0.25, rho), 1.0);
  m.set("loading_stiffness", k1);
  m.set("unloading_stiffness", kp);
  m.set("adhesion_stiffness", kc);
  m.set("plastic_depth", phi);
  m.finalize();
  return m;
}

/// The unloading stiffness after a maximum overlap dmax (equal spheres: R* = R/2).
double k2_of(double dmax, double phi) {
  const double dp = kp / (kp - k1) * phi * 2 * (0.5 * R);
  return phi > 0 && dmax < dp ? k1 + (kp - k1) * dmax / dp : kp;
}
/// Restitution of a head-on impact at v0 without dashpot; 0 when the spheres stick.
double restitution(double v0, double kc, double phi) {
  const double mstar = 0.5 * rho * 4.0 / 3.0 * M_PI * R * R * R;
  const double k2 = k2_of(v0 * std::sqrt(mstar / k1), phi);
  const double e2 = k1 / k2 - (k2 - k1) * (k2 - k1) * kc / (k1 * k2 * (k2 + kc));
  return e2 > 0 ? std::sqrt(e2) : 0;
}

/// Sphere 0 fixed, sphere 1 prescribed along x through the overlaps `path` (piecewise linear,
/// `per_leg` steps per leg); returns (overlap, normal force) after every step.
std::vector<std::pair<double, double>> drive(const ContactModel& m, const std::vector<double>& path, int per_leg) {
  Particles p;
  p.add({0, 0, 0}, R, rho, 0);
  p.add({2 * R - path[0], 0, 0}, R, rho, 0);
  p.set_motion(0, Motion::fixed);
  p.set_motion(1, Motion::prescribed);
  Simulation sim(std::move(p), Cell::box({-10 * R, -10 * R, -10 * R}, {10 * R, 10 * R, 10 * R}, false), m);
  const double dt = 1e-6;  // any step: both spheres move as prescribed (no free particle, no limit)
  sim.set_time_step(dt);
  std::vector<std::pair<double, double>> out;
  for (std::size_t leg = 1; leg < path.size(); ++leg) {
    sim.particles().v[1] = {-(path[leg] - path[leg - 1]) / (per_leg * dt), 0, 0};
    for (int k = 0; k < per_leg; ++k) {
      sim.step();
      const double delta = 2 * R - (sim.particles().x[1].x - sim.particles().x[0].x);
      out.push_back({delta, -sim.particles().f[0].x});  // f on 0 = −f_n n, n = +x
    }
  }
  return out;
}
}  // namespace

// The quasi-static cycle (prescribed motion, so every force is the law at a known overlap):
// load to δ_max, unload into tension, reload from the adhesive branch past the old maximum,
// pull off. Branch by branch the force is the closed form to round-off (1e-12 of k1 δ_max,
// measured 4e-16);
// the plastic overlap (zero crossing, interpolated between samples δ_max/2000 apart: the force
// is linear there, so exactly) and the tensile limit −kc δ_min are checked on their own.
TEST(Luding, LoadingCycleFollowsTheBranchesAndLeavesThePlasticOverlap) {
  const double kc = 2e3, dmax_path = 1e-5;
  const double dr_path = 0.5 * (kp - k1) / (kp + kc) * dmax_path;  // reload from the adhesive branch
  const auto samples = drive(luding(kc, 0), {-0.1 * dmax_path, dmax_path, dr_path, 1.5 * dmax_path, -0.1 * dmax_path}, 2000);
  // The turning points as reached (positions accumulate round-off along each leg).
  const double dmax = samples[1999].first, dr = samples[3999].first, dend = samples[5999].first;
  const double d0 = (1 - k1 / kp) * dmax, dmin = (kp - k1) / (kp + kc) * dmax;
  const double d0r = dr * (1 + kc / kp);        // the reload's k2 line: through (dr, −kc dr)
  const double dstar = kp * d0r / (kp - k1);    // where that line meets k1 δ again
  // Expected force along each leg, from the formulas above (leg 2: k2 = kp after δ_max, φ_f = 0).
  const double d0_end = (1 - k1 / kp) * dend;
  double worst = 0, f_min = 0, zero_crossing = -1;
  for (std::size_t s = 0; s < samples.size(); ++s) {
    const auto [d, f] = samples[s];
    const int leg = int(s / 2000);
    double expect = 0;
    if (d > 0) {
      if (leg == 0) expect = k1 * d;
      else if (leg == 1) expect = std::max(kp * (d - d0), -kc * d);
      else if (leg == 2) expect = d < dstar ? kp * (d - d0r) : k1 * d;
      else expect = std::max(kp * (d - d0_end), -kc * d);
    }
    worst = std::max(worst, std::abs(f - expect));
    if (leg == 1) {
      f_min = std::min(f_min, f);
      if (s > 2000 && samples[s - 1].second > 0 && f <= 0)  // interpolate the zero crossing
        zero_crossing = d + (samples[s - 1].first - d) * (0 - f) / (samples[s - 1].second - f);
    }
  }
  std::printf("measured: worst |F - F_formula| / (k1 dmax) = %.2e; plastic overlap %.6e (formula %.6e); "
              "tensile limit %.6e N (formula %.6e)\n",
              worst / (k1 * dmax), zero_crossing, d0, f_min, -kc * dmin);
  EXPECT_LT(worst, 1e-12 * k1 * dmax);
  EXPECT_NEAR(zero_crossing / d0, 1.0, 1e-9);
  // The most tensile sample is within one step (δ_max/2000) of δ_min on the branch −kc δ.
  EXPECT_NEAR(f_min / (-kc * dmin), 1.0, 2 * (dmax / 2000) / dmin);
  EXPECT_GT(dstar, dr);
  EXPECT_LT(dstar, dmax);  // the reload rejoins the loading line below the old maximum
  EXPECT_EQ(samples.back().second, 0.0);  // pulled apart: no force, contact gone
}

// Restitution as a function of the impact speed without adhesion: e = sqrt(k1/k2(δ_max(v0))),
// from nearly elastic slow impacts (k2 close to k1) to sqrt(k1/kp) once δ_max ≥ δ_max^p. The
// collision is integrated at Δt = 0.01 of the critical step (~700 steps per contact); the error
// of the measured rebound is at most O(Δt/t_c) ~ 1e-3 from the branch switches (measured
// 2e-5), so 1e-3 relative.
TEST(Luding, RestitutionFollowsTheUnloadingStiffnessOfEachImpactSpeed) {
  const double phi = 0.01;
  const ContactModel m = luding(0, phi);
  double prev = 2;
  for (double v0 : {0.02, 0.05, 0.1, 0.3}) {
    Simulation sim = head_on(m, R, rho, 1e-6, v0);
    sim.set_time_step(0.01 * sim.critical_time_step());
    const Collision c = collide(sim, v0);
    const double e = restitution(v0, 0, phi);
    std::printf("measured: v0 = %.2f m/s: e = %.5f (formula %.5f), max overlap %.4e (formula %.4e)\n", v0,
                c.restitution, e, c.max_overlap, v0 * std::sqrt(0.5 * sim.particles().m[0] / k1));
    EXPECT_NEAR(c.restitution / e, 1.0, 1e-3) << v0;
    EXPECT_LT(e, prev);  // the expected values really change with the speed
    prev = e;
  }
  EXPECT_NEAR(restitution(0.3, 0, phi), std::sqrt(k1 / kp), 1e-12);  // beyond δ_max^p: k2 = kp
}

// With adhesion the tensile branch grows with the plastic deformation, so a slow impact
// rebounds and a fast one sticks. Rebounds: e from the energy closed form (1e-3 as above, 1e-2
// near the critical speed where e is small and the same absolute error weighs more; measured
// 1e-5 and 1e-4). Above
// the critical speed (k1²(k2 + kc) = (k2 − k1)² kc) the spheres stay in contact for 30
// contact durations.
TEST(Luding, AdhesiveContactsReboundBelowAndStickAboveTheCriticalSpeed) {
  const double kc = 1e3, phi = 0.01;
  const ContactModel m = luding(kc, phi);
  // Critical k2: k1²(k2 + kc) = (k2 − k1)² kc; with kc = k1 this is k2² − 3 k1 k2 = 0, k2* = 3 k1.
  const double k2c = 3 * k1;
  const double mstar = 0.5 * rho * 4.0 / 3.0 * M_PI * R * R * R;
  const double dp = kp / (kp - k1) * phi * R;
  const double vc = dp * (k2c - k1) / (kp - k1) * std::sqrt(k1 / mstar);
  EXPECT_NEAR(restitution(vc * 0.999, kc, phi), 0.0, 0.05);
  for (double f : {0.3, 0.6, 0.9}) {
    const double v0 = f * vc;
    Simulation sim = head_on(m, R, rho, 1e-6, v0);
    sim.set_time_step(0.01 * sim.critical_time_step());
    const Collision c = collide(sim, v0);
    const double e = restitution(v0, kc, phi);
    std::printf("measured: v0 = %.3f v_c: e = %.5f (formula %.5f)\n", f, c.restitution, e);
    ASSERT_GT(e, 0);
    EXPECT_NEAR(c.restitution / e, 1.0, f < 0.8 ? 1e-3 : 1e-2) << f;
  }
  for (double f : {1.2, 2.0}) {
    const double v0 = f * vc;
    EXPECT_EQ(restitution(v0, kc, phi), 0.0);
    Simulation sim = head_on(m, R, rho, 1e-6, v0);
    sim.set_time_step(0.01 * sim.critical_time_step());
    const double tc = M_PI * std::sqrt(mstar / k1);
    bool apart = false, touched = false;
    auto& p = sim.particles();
    while (sim.time() < 30 * tc) {
      sim.step();
      const double delta = 2 * R - (p.x[1].x - p.x[0].x);
      touched = touched || delta > 0;
      apart = apart || (touched && delta <= 0);
    }
    std::printf("measured: v0 = %.1f v_c: %s after 30 contact durations\n", f, apart ? "apart" : "stuck");
    EXPECT_TRUE(touched && !apart) << f;
  }
}

// Bad values are refused naming the parameter: the unloading branch must be the stiffer one.
TEST(Luding, UnloadingStiffnessBelowLoadingIsRefused) {
  ContactModel m = model(NormalLaw{"luding"}, TangentialLaw::none, material(1e8, 0.25, rho), 1.0);
  m.set("loading_stiffness", 2e3);
  m.set("unloading_stiffness", 1e3);
  const LawProblem bad = law_info(m.normal).check(m.pair(0, 0));
  EXPECT_EQ(bad.key, "unloading_stiffness");
  EXPECT_THROW(m.set("normal_stiffness", 1e3), InputError);  // the linear law's, not luding's
}
