// Jamming of frictionless spheres by the quasistatic protocol (pressure target: staged enthalpy FIRE
// with the cell as a degree of freedom, 100 P → 10 P → P, then a fixed-cell polish) against
// O'Hern, Silbert, Liu & Nagel, PRE 68 (2003) 011306, and the frictional and adhesive packings
// of issue 3. The contact network is recounted here from positions and radii (all pairs), not
// taken from the library's contact table or rattler removal.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <set>
#include <tuple>
#include <vector>

#include "scenes.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/dem/simulation.hpp"
#include "tomodem/geometry/pack.hpp"

using namespace tomodem;
using namespace tomodem::geometry;

namespace {
constexpr double kPi = 3.14159265358979323846;

struct Recount {
  double phi = 0, z = 0, z_no_rattlers = 0, rattlers = 0;
};

/// Contacts (overlap > 0) of a periodic cubic packing by brute force over all pairs and the 27
/// nearest images; rattlers (fewer than `min_contacts`) removed recursively.
Recount recount(const Packing& pk, int min_contacts) {
  const auto& x = pk.particles.position;
  const auto& r = pk.particles.radius;
  const std::size_t n = r.size();
  const double L = pk.cell.h(0, 0);
  std::vector<std::vector<int>> adj(n);
  long contacts = 0;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j) {
      Vec3 d = x[j] - x[i];
      for (int k = 0; k < 3; ++k) d[k] -= L * std::round(d[k] / L);  // minimum image (L > 4 d here)
      if (norm(d) < r[i] + r[j]) adj[i].push_back(int(j)), adj[j].push_back(int(i)), ++contacts;
    }
  Recount c;
  double vs = 0;
  for (double ri : r) vs += 4 * kPi / 3 * ri * ri * ri;
  c.phi = vs / (L * L * L);
  c.z = 2.0 * double(contacts) / double(n);
  std::vector<int> z(n);
  std::vector<char> gone(n, 0);
  for (std::size_t i = 0; i < n; ++i) z[i] = int(adj[i].size());
  for (bool again = true; again;) {
    again = false;
    for (std::size_t i = 0; i < n; ++i)
      if (!gone[i] && z[i] < min_contacts) {
        gone[i] = 1;
        again = true;
        for (int j : adj[i]) --z[std::size_t(j)];
      }
  }
  long kept = 0, zsum = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (!gone[i]) ++kept, zsum += z[i];
  c.rattlers = double(long(n) - kept) / double(n);
  c.z_no_rattlers = kept ? double(zsum) / double(kept) : 0;
  return c;
}

/// Frictionless harmonic spheres (O'Hern's model, α = 2): d = 1 mm, k = 1000 N/m, packed to
/// p d/k = 1e-6, i.e. overlaps δ/d ~ 1e-6: φ(p) − φ_J and Z − Z_J ~ 7.7 (φ − φ_J)^½ (O'Hern)
/// are far below the tolerances.
PackSpec harmonic(std::size_t n, bool bidisperse, double friction) {
  PackSpec s;
  PhaseSpec p;
  p.name = "spheres";
  p.material.density = 1000;
  p.material.youngs_modulus = 1e6;
  p.psd.diameter = 1e-3;
  if (bidisperse) {  // 50:50 by number, diameter ratio 1.4 (O'Hern's bidisperse system)
    p.psd.kind = PsdKind::bimodal;
    p.psd.diameter2 = 1.4e-3;
    p.psd.fraction2 = 0.5;
    p.psd.basis = PsdBasis::number;
  }
  s.phases = {p};
  s.n_particles = n;
  s.initial_solid_fraction = 0.3;
  s.normal = dem::NormalLaw::linear;
  s.normal_stiffness = 1000;
  s.restitution = 1;  // no dashpot: FIRE alone removes the energy
  s.friction = friction;
  s.target = Target::pressure;
  s.target_pressure = 1e-6 * s.normal_stiffness / p.psd.diameter;
  s.tessellate = false;
  s.seed = 7;
  s.threads = 1;
  if (const char* t = std::getenv("TOMODEM_TEST_THREADS")) s.threads = std::atoi(t);
  return s;
}

// Validation runs N = 1000 (about 4 s of CPU); the N = 4000 (about 70 s of CPU, 5–6 min
// at a load of 12 on two cores) is the same file built as the bench `pack_jamming_bench`
// (TOMODEM_JAMMING_N_DEFAULT=4000), or any N through the environment variable TOMODEM_JAMMING_N.
#ifndef TOMODEM_JAMMING_N_DEFAULT
#define TOMODEM_JAMMING_N_DEFAULT 1000
#endif
std::size_t particles() {
  const char* e = std::getenv("TOMODEM_JAMMING_N");
  return e ? std::size_t(std::atol(e)) : std::size_t(TOMODEM_JAMMING_N_DEFAULT);
}

void print(const char* what, const PackReport& r, const Recount& c) {
  std::printf("%s: N %zu, phi %.5f (recount %.5f), phi_J %.5f, p %.4g Pa, Z %.4f, Z_nr %.4f (recount %.4f), "
              "rattlers %.4f (recount %.4f), minimisations %d, steps %ld, unbalanced %.2e, %.1f s\n",
              what, r.n_particles, r.solid_fraction, c.phi, r.jamming_solid_fraction, r.pressure, r.coordination,
              r.coordination_no_rattlers, c.z_no_rattlers, r.rattler_fraction, c.rattlers, r.minimisations, r.steps,
              r.unbalanced_force_ratio, r.wall_time_s);
}
}  // namespace

// O'Hern et al. 2003: φ_J = 0.639 (monodisperse, 3D), isostatic Z = 2d = 6 without rattlers.
// Issue 3 asks 0.64 ± 0.01 and 6.0 ± 0.2 at N ≥ 4000. The spread of φ_J between configurations
// falls as N^(-1/2) (O'Hern: width ≈ 0.003–0.004 around N = 1000 in 3D, and the mean is within
// about 0.002 of its large-N value), so the same ± 0.01 holds at the validation's N = 1000 with a
// margin of 2–3 widths; Z at p d/k = 1e-6 exceeds Z_J by about 7.7 sqrt(φ − φ_J) < 0.01, and an
// isostatic network of N' particles has Z = 6 − O(1/N'). Pressure targets are reached by the
// enthalpy minimiser and its fixed-cell polish (docs/pack.md): the relaxed pressure ends within
// its 1 % tolerance of the target (1.05 % allowed: the reported pressure includes the kinetic
// part of a state whose velocities were just zeroed) and the unbalanced-force ratio below 1e-4.
TEST(Jamming, MonodisperseFrictionlessIsostaticAtRandomClosePacking) {
  const PackSpec s = harmonic(particles(), false, 0);
  const PackOutput out = make_packing(s);
  const PackReport& r = out.report;
  const Recount c = recount(out.packing, 4);
  print("monodisperse", r, c);
  EXPECT_TRUE(r.equilibrium);
  EXPECT_LT(std::abs(r.pressure / s.target_pressure - 1), 0.0105);
  EXPECT_LT(r.unbalanced_force_ratio, s.unbalanced_force_ratio);
  EXPECT_NEAR(c.phi, r.solid_fraction, 1e-12);
  EXPECT_NEAR(r.solid_fraction, 0.64, 0.01);           // issue 3
  EXPECT_NEAR(c.z_no_rattlers, 6.0, 0.2);              // issue 3 (isostatic)
  EXPECT_NEAR(r.coordination_no_rattlers, c.z_no_rattlers, 1e-12);
  EXPECT_LT(c.rattlers, 0.05);  // O'Hern: a few per cent rattlers at jamming
}

// Staged enthalpy minimisation (docs/pack.md, issue 19): jamming the packing at 100 P and
// decompressing it to P with the cell as a degree of freedom against one minimisation that stops
// when the packing first reaches P plus the fixed-cell polish (enthalpy_stages = 0), on the
// benchmark's system at N = 500: Hertz alumina, lognormal σ = 0.3 by volume, 1 MPa ≈ 2.6e-6 E
// (overlaps ~1e-4 d: close to jamming, where the polish probes unjammed states). Both runs must end
// in equilibrium at the target (the criteria of the monodisperse test above); the staged one in at
// most a third of the FIRE steps (an operation count, not a time). Measured: staged 14 480 steps
// (φ 0.6653), unstaged 138 200 (φ 0.6632: the overshoot to 100 P packs 0.002 denser).
TEST(Jamming, StagedEnthalpyReachesPressureTargetInFewerSteps) {
  long steps[2] = {0, 0};
  for (int stages : {2, 0}) {
    PackSpec s;
    PhaseSpec p;
    p.name = "alumina";
    p.material.density = 3950;
    p.material.youngs_modulus = 3.8e11;
    p.material.poisson_ratio = 0.22;
    p.psd.kind = PsdKind::lognormal;
    p.psd.diameter = 1e-6;
    p.psd.sigma = 0.3;
    p.psd.basis = PsdBasis::volume;
    s.phases = {p};
    s.n_particles = 500;
    s.initial_solid_fraction = 0.3;
    s.target = Target::pressure;
    s.target_pressure = 1e6;
    s.enthalpy_stages = stages;
    s.tessellate = false;
    s.seed = 5;
    const PackOutput out = make_packing(s);
    const PackReport& r = out.report;
    const Recount c = recount(out.packing, 4);
    std::printf("enthalpy stages %d: ", stages);
    print("hertz", r, c);
    EXPECT_TRUE(r.equilibrium) << stages << " stages";
    EXPECT_LT(std::abs(r.pressure / s.target_pressure - 1), 0.0105) << stages << " stages";
    EXPECT_LT(r.unbalanced_force_ratio, s.unbalanced_force_ratio) << stages << " stages";
    steps[stages ? 0 : 1] = r.steps;
  }
  EXPECT_LT(3 * steps[0], steps[1]) << "staged " << steps[0] << " steps, unstaged " << steps[1];
}

// A pressure target above what the contact law carries without overlaps beyond 10 % of a radius
// is refused before any work (exit 2 in the tool): harmonic k = 1000 N/m, d = 1 mm admits
// p = 6 · 0.64 · k · 0.05 d / (π d²) ≈ 61 kPa; 1 MPa is refused, 1 kPa is not; a negative
// target is refused as well.
TEST(Jamming, UnreachablePressureTargetRefused) {
  PackSpec s = harmonic(100, false, 0);
  const double pmax = 6 * 0.64 * 1000 * 0.05e-3 / (kPi * 1e-6);
  EXPECT_NEAR(max_admissible_pressure(s), pmax, 1e-9 * pmax);
  s.target_pressure = 1e6;
  EXPECT_THROW(validate(s), InputError);
  s.target_pressure = 1e3;
  EXPECT_NO_THROW(validate(s));
  s.target_pressure = -1;
  EXPECT_THROW(validate(s), InputError);
}

// O'Hern's 50:50 bidisperse mixture (diameter ratio 1.4): φ_J = 0.648 in 3D; same bounds.
TEST(Jamming, BidisperseFrictionlessIsostatic) {
  const PackSpec s = harmonic(particles(), true, 0);
  const PackOutput out = make_packing(s);
  const PackReport& r = out.report;
  const Recount c = recount(out.packing, 4);
  print("bidisperse", r, c);
  EXPECT_TRUE(r.equilibrium);
  EXPECT_LT(std::abs(r.pressure / s.target_pressure - 1), 0.0105);
  EXPECT_NEAR(r.solid_fraction, 0.648, 0.01);
  EXPECT_NEAR(c.z_no_rattlers, 6.0, 0.2);
}

// Friction μ = 0.5 (linear tangential spring, k_t = 2/7 k_n), same protocol and pressure:
// frictional spheres jam looser and with fewer contacts (Silbert, Soft Matter 6 (2010) 2918:
// μ = 0.5 gives φ_J ≈ 0.60–0.61 and Z_J ≈ 4.5–4.7, between the isostatic limits d + 1 = 4 at
// infinite friction and 2d = 6 without). Bounds: below the frictionless 0.64 − 0.01 and 6 − 0.5,
// at or above the frictional isostatic Z = 4 (less 0.2 for the finite-N spread).
TEST(Jamming, FrictionalLooserWithFewerContacts) {
  PackSpec s = harmonic(particles(), false, 0.5);
  const PackOutput out = make_packing(s);
  const PackReport& r = out.report;
  const Recount c = recount(out.packing, 2);
  print("friction 0.5", r, c);
  EXPECT_TRUE(r.equilibrium);
  EXPECT_LT(r.solid_fraction, 0.63);
  EXPECT_GT(r.solid_fraction, 0.55);  // random loose packing bound (Onoda & Liniger 1990: 0.555)
  EXPECT_LT(c.z_no_rattlers, 5.5);
  EXPECT_GT(c.z_no_rattlers, 3.8);
  EXPECT_NEAR(r.coordination_no_rattlers, c.z_no_rattlers, 1e-12);
}

// Fine cohesive powder (issue 3): 1 µm alumina spheres, Hertz + DMT with w = 0.1 and 1 J/m²,
// Coulomb μ = 0.5 and rolling friction μ_r = 0.1 (as the DEM studies cited, which need rolling
// resistance for the loose structures: without it, chains of adhesive spheres roll shut and the
// same run ends at φ ≈ 0.53, docs/pack.md), at 1 kPa — three orders below the cohesive stress
// 2π w R*/d² ≈ 0.16–1.6 MPa.
// Contacts that form stick, and the adhesive, frictional network carries the load long before
// the particles can rearrange into a dense packing: loose packings far below 0.6 (DEM and
// experiments: φ ≈ 0.35–0.45 at 1 µm, Yang, Zou & Yu, PRE 62 (2000) 3900; Parteli et al.,
// Sci. Rep. 4 (2014) 6227). Bounds: 0.30 < φ < 0.47, the cited 0.35–0.45 widened by the
// statistical spread of a 500-particle packing (~0.01) and the unstudied w = 1 end; measured
// φ = 0.432 (w = 0.1) and 0.380 (w = 1). Stronger adhesion packs looser (the cited studies: φ falls
// with the cohesive-to-weight ratio): φ(w = 1) < φ(w = 0.1). The contact network is held by
// adhesion, not friction: 1.5 < Z < 4, below the Z ≈ 4.5–4.7 of non-adhesive spheres at μ = 0.5
// (Silbert 2010, docs/physics.md#packing; Z → 4 only as μ → ∞) and near the chains of Z = 2
// less the rattlers counted in Z (measured Z = 2.07 and 2.11 with 41–44 % rattlers).
TEST(Jamming, AdhesiveMicronPowderPacksLoose) {
  double phi_prev = 1;
  for (double w : {0.1, 1.0}) {
    PackSpec s;
    PhaseSpec p;
    p.name = "alumina";
    p.material.density = 3950;
    p.material.youngs_modulus = 3.8e11;
    p.material.poisson_ratio = 0.22;
    p.psd.diameter = 1e-6;
    s.phases = {p};
    s.n_particles = 500;
    s.initial_solid_fraction = 0.2;
    s.normal = dem::NormalLaw::hertz_dmt;
    s.work_of_adhesion = w;
    s.friction = 0.5;
    s.rolling_friction = 0.1;
    s.target = Target::pressure;
    s.target_pressure = 1e3;
    s.tessellate = false;
    s.seed = 3;
    const PackOutput out = make_packing(s);
    const PackReport& r = out.report;
    const Recount c = recount(out.packing, 2);
    std::printf("adhesion w = %.1f J/m^2: ", w);
    print("", r, c);
    EXPECT_GT(r.solid_fraction, 0.30) << "w = " << w;
    EXPECT_LT(r.solid_fraction, 0.47) << "w = " << w;
    EXPECT_LT(r.solid_fraction, phi_prev) << "w = " << w << ": stronger adhesion must not pack denser";
    phi_prev = r.solid_fraction;
    EXPECT_GT(r.coordination, 1.5) << "w = " << w;
    EXPECT_LT(r.coordination, 4.0) << "w = " << w;
  }
}

// The neighbour list's rebuild test measures motion against the cell's affine map
// (neighbour_list.cpp, rebuild_due): a pair left out at a build cannot touch before the next.
// 400 spheres (d 0.8-1.2 mm, no overlap at phi 0.2) in a periodic cube of ~11 d, deformed in 120
// steps by F = diag(1 - e) + shear g (e = 0.0015, g = 0.002; the volume falls to 0.58) plus a
// random non-affine jitter of up to 0.003 d per step and axis, then expanded in 30 steps. After
// every step, every pair within r_i + r_j (all pairs, the 27 images) must be listed through
// its image. The old test, 2 max|x - x0| + sqrt(3) |H - H0| > skin (replayed here on the same
// motion), rebuilds every ~2 steps at this cell size (the far side of the cell moves by e L per
// step); the affine one every ~10-20 (r_list e + the jitter): a quarter of the builds is a
// margin of 2 or more on both counts.
TEST(Jamming, AffineRebuildTestMissesNoPair) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0, 1);
  const double d = 1e-3, side = 11 * d;
  dem::Particles p;
  std::vector<Vec3> x;
  std::vector<double> r;
  while (r.size() < 400) {  // random sequential insertion, periodic minimum image
    const Vec3 xi{u(rng) * side, u(rng) * side, u(rng) * side};
    const double ri = d * (0.4 + 0.2 * u(rng));
    bool free = true;
    for (std::size_t j = 0; j < x.size() && free; ++j) {
      Vec3 dx = x[j] - xi;
      for (int k = 0; k < 3; ++k) dx[k] -= side * std::round(dx[k] / side);
      free = norm(dx) > ri + r[j];
    }
    if (free) x.push_back(xi), r.push_back(ri), p.add(xi, ri, 2500, 0);
  }
  // Only the neighbour list is checked: the contact law does not matter.
  const dem::ContactModel m = dem::testing::model(dem::NormalLaw::hertz, dem::TangentialLaw::mindlin,
                                                  dem::testing::material(1e8, 0.25, 2500), 0.5);
  dem::Settings set;
  set.threads = 1;
  dem::Simulation sim(std::move(p), Cell::box({0, 0, 0}, {side, side, side}, true), m, set);
  double dsum = 0;
  for (double ri : r) dsum += 2 * ri;
  const double skin = 0.1 * dsum / double(r.size());  // the engine's default
  sim.measure();
  const long builds0 = sim.engine_state().builds;
  // The old test replayed on unwrapped copies of the positions (the engine wraps at its builds).
  std::vector<Vec3> y = sim.particles().x, y0 = y;
  Mat3 h0 = sim.cell().h;
  long old_builds = 0, missed = 0, checked = 0;
  std::uniform_real_distribution<double> jitter(-0.003 * d, 0.003 * d);
  for (int step = 0; step < 150; ++step) {
    const double e = step < 120 ? 0.0015 : -0.004, g = step < 120 ? 0.002 : 0;
    Mat3 f;
    for (int a = 0; a < 3; ++a) f(a, a) = 1 - e;
    f(0, 1) = g;
    const Vec3 o = sim.cell().origin;
    auto& xs = sim.particles().x;
    for (std::size_t i = 0; i < xs.size(); ++i) {
      const Vec3 w{jitter(rng), jitter(rng), jitter(rng)};
      xs[i] = o + f * (xs[i] - o) + w;
      y[i] = o + f * (y[i] - o) + w;
    }
    sim.cell().h = f * sim.cell().h;
    double dmax = 0, dh = 0;
    for (std::size_t i = 0; i < y.size(); ++i) dmax = std::max(dmax, norm(y[i] - y0[i]));
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) dh += std::pow(sim.cell().h(a, b) - h0(a, b), 2);
    if (2 * dmax + std::sqrt(3 * dh) > skin) ++old_builds, y0 = y, h0 = sim.cell().h;
    sim.measure();  // rebuilds when due
    const dem::Simulation::EngineState es = sim.engine_state();
    std::set<std::tuple<int, int, int>> listed;
    for (std::size_t i = 0; i + 1 < es.start.size(); ++i)
      for (int k = es.start[i]; k < es.start[i + 1]; ++k) listed.emplace(int(i), es.j[std::size_t(k)], es.image[std::size_t(k)]);
    const Mat3& h = sim.cell().h;
    for (std::size_t i = 0; i < xs.size(); ++i)
      for (std::size_t j = i + 1; j < xs.size(); ++j)
        for (int c = 0; c < 27; ++c) {
          const Vec3 n{double(c / 9 - 1), double(c / 3 % 3 - 1), double(c % 3 - 1)};
          if (norm(xs[j] + h * n - xs[i]) >= r[i] + r[j]) continue;
          ++checked;
          if (!listed.count({int(i), int(j), c})) ++missed;
        }
  }
  const long builds = sim.engine_state().builds - builds0;
  std::printf("affine rebuild test: %ld builds, old test %ld, %ld touching pairs checked, %ld missed\n", builds,
              old_builds, checked, missed);
  EXPECT_GT(checked, 1000);  // the test saw contacts
  EXPECT_EQ(missed, 0);
  EXPECT_GE(builds, 3);  // the list did have to follow the motion
  EXPECT_LT(4 * builds, old_builds);
}

// The rebuild test bounds a pair's relative motion by the two largest displacements since the
// build (|u_j − u_i| ≤ |u_i| + |u_j| ≤ u₁ + u₂), not twice the largest: one particle running
// ahead of the rest no longer rebuilds the list twice as often. 27 spheres (d = 1 mm, 1.5 mm
// apart, skin 0.1 d) in a periodic cube; A moves 0.02 mm a step straight at its neighbour B,
// C 0.002 mm a step, the rest stay: u₁ + u₂ = 0.022 k mm passes the skin at k = 5 (6 builds in
// 30 steps), 2 u₁ = 0.04 k at k = 3 (10). A reaches B at step 25 and must be listed from then on.
TEST(Jamming, RebuildTestBoundsPairsByTheTwoFastestParticles) {
  const double d = 1e-3, a = 1.5e-3;
  dem::Particles p;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) p.add(Vec3{(i + 0.5) * a, (j + 0.5) * a, (k + 0.5) * a}, d / 2, 2500, 0);
  const dem::ContactModel m = dem::testing::model(dem::NormalLaw::hertz, dem::TangentialLaw::mindlin,
                                                  dem::testing::material(1e8, 0.25, 2500), 0.5);
  dem::Settings set;
  set.threads = 1;
  dem::Simulation sim(std::move(p), Cell::box({0, 0, 0}, {3 * a, 3 * a, 3 * a}, true), m, set);
  sim.measure();
  const long builds0 = sim.engine_state().builds;
  const std::size_t A = 0, B = 9, C = 13;  // B: one lattice step from A along x; C: the centre
  ASSERT_NEAR(sim.particles().x[B].x - sim.particles().x[A].x, a, 1e-12);
  long touching_steps = 0;
  for (int step = 1; step <= 30; ++step) {
    sim.particles().x[A].x += 0.02 * d;
    sim.particles().x[C].y += 0.002 * d;
    sim.measure();
    const auto& x = sim.particles().x;
    if (norm(x[B] - x[A]) >= d) continue;
    ++touching_steps;
    const dem::Simulation::EngineState es = sim.engine_state();
    bool listed = false;
    for (int q = es.start[A]; q < es.start[A + 1]; ++q) listed = listed || (es.j[std::size_t(q)] == int(B) && es.image[std::size_t(q)] == 13);  // 13: the centre image
    EXPECT_TRUE(listed) << "step " << step << ": A and B touch but are not listed";
  }
  EXPECT_GE(touching_steps, 5);  // steps 26-30, and 25 where the sum of the steps rounds below d
  EXPECT_EQ(sim.engine_state().builds - builds0, 6);  // twice the largest: 10
}
