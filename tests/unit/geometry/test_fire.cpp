// FIRE minimisation (dem/fire.hpp) against closed-form minima: a compressed FCC crystal of
// harmonic spheres, randomly disturbed, relaxes back to the lattice, whose energy is
// 6 N · ½ k δ² (12 neighbours per sphere, each contact shared by two) with δ = d − a/√2.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "tomodem/dem/fire.hpp"
#include "tomodem/dem/scene.hpp"

using namespace tomodem;

namespace {
dem::Simulation fcc(int cells, double a, double d, double k, double jitter, uint64_t seed, double friction = 0,
                    double restitution = 1) {
  std::vector<Vec3> x = dem::lattice_sites(dem::LatticeKind::fcc, cells, a);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-jitter, jitter);
  dem::Particles p;
  for (auto& xi : x) p.add(xi + Vec3{u(rng), u(rng), u(rng)}, 0.5 * d, 1000, 0);
  dem::ContactModel m;
  m.normal = dem::NormalLaw::linear;
  m.tangential = friction > 0 ? dem::TangentialLaw::linear : dem::TangentialLaw::none;
  Material mat;
  mat.density = 1000;
  mat.youngs_modulus = 1e6;
  m.materials = {mat};
  m.finalize();
  m.pair(0, 0).k_n = k;
  m.pair(0, 0).friction = friction;
  m.pair(0, 0).restitution = restitution;
  m.finalize();
  dem::Simulation sim(std::move(p), Cell::box({0, 0, 0}, {cells * a, cells * a, cells * a}, true), m);
  sim.set_time_step(0.1 * sim.critical_time_step());
  return sim;
}
}  // namespace

TEST(Fire, DisturbedCompressedFccRelaxesToTheLatticeEnergy) {
  const double d = 1e-3, k = 1000, delta = 1e-3 * d;
  const double a = std::sqrt(2.0) * (d - delta);  // nearest-neighbour distance d − δ
  dem::Simulation sim = fcc(4, a, d, k, 0.02 * d, 3);
  dem::FireOptions o;
  o.unbalanced_force_ratio = 1e-9;
  const dem::FireResult r = dem::minimise_fire(sim, o);
  ASSERT_TRUE(r.converged) << r.steps << " steps, ratio " << r.last.unbalanced_force_ratio;
  const double n = double(sim.particles().size());
  const double expected = 6 * n * 0.5 * k * delta * delta;
  // The FCC minimum is unique up to a translation: force ratio 1e-9 leaves displacements of
  // order 1e-9 δ, so the energy agrees to far better than 1e-6.
  EXPECT_NEAR(r.last.elastic_energy / expected, 1, 1e-6);
  EXPECT_NEAR(r.last.coordination, 12, 1e-12);
  // Pressure of the lattice: p = (1/3V) Σ f l = 6N k δ (d − δ) / (3V).
  const double V = sim.cell().volume();
  EXPECT_NEAR(r.last.pressure / (6 * n * k * delta * (d - delta) / (3 * V)), 1, 1e-6);
  EXPECT_LT(r.steps, 20000);
  // Velocities are left at zero, the caller's time step restored.
  for (const auto& v : sim.particles().v) EXPECT_EQ(norm(v), 0);
}

TEST(Fire, ConvergedMeansBalancedAtRestUnderEitherCriterion) {
  // Strong contact damping (restitution 0.05): in motion the dashpots carry part of the force,
  // so a check in motion can pass while the particles, stopped, are not balanced. FIRE's stop
  // is checked at rest, for the ratio criterion and for the net-force tolerance (adhesive
  // packings) alike; the net forces are recomputed here from the contact table.
  const double d = 1e-3, k = 1000, delta = 1e-3 * d;
  const double a = std::sqrt(2.0) * (d - delta);
  for (const bool tolerance : {false, true}) {
    dem::Simulation sim = fcc(3, a, d, k, 0.02 * d, 7, 0, 0.05);
    dem::FireOptions o;
    o.unbalanced_force_ratio = 1e-6;
    if (tolerance) o.force_tolerance = 1e-6 * k * delta;  // 1e-6 of a lattice contact's force
    const dem::FireResult r = dem::minimise_fire(sim, o);
    ASSERT_TRUE(r.converged) << "tolerance " << tolerance << ": " << r.steps << " steps";
    const ContactTable t = sim.contacts();
    std::vector<Vec3> net(sim.particles().size());
    for (std::size_t c = 0; c < t.size(); ++c) {
      net[t.j[c]] += t.normal_force[c] + t.tangential_force[c];
      net[t.i[c]] -= t.normal_force[c] + t.tangential_force[c];
    }
    double f2 = 0;
    for (const Vec3& f : net) f2 += norm2(f);
    const double rms = std::sqrt(f2 / double(net.size()));
    const dem::Measurements m = sim.measure();
    // The measurement's rms against the contact table's, to round-off of a sum of 12 forces.
    EXPECT_NEAR(m.net_force_rms, rms, 1e-9 * k * delta);
    if (tolerance) EXPECT_LT(rms, o.force_tolerance);
    else EXPECT_LT(m.unbalanced_force_ratio, o.unbalanced_force_ratio);
    EXPECT_EQ(r.last.net_force_rms, m.net_force_rms);  // the result is the measurement at rest
  }
}

TEST(Fire, UnjammedGasStopsAtZeroEnergy) {
  // Below touching (a/√2 > d) the disturbed lattice separates: no contact carries force.
  const double d = 1e-3;
  dem::Simulation sim = fcc(3, std::sqrt(2.0) * 1.05 * d, d, 1000, 0.04 * d, 5);
  const dem::FireResult r = dem::minimise_fire(sim, {});
  EXPECT_TRUE(r.below_floor);
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.last.contacts, 0);
}

TEST(Fire, RefusesADeformingCell) {
  dem::Simulation sim = fcc(2, std::sqrt(2.0) * 1e-3, 1e-3, 1000, 0, 1);
  sim.cell_control().velocity_gradient(0, 0) = -1;
  EXPECT_ANY_THROW(dem::minimise_fire(sim, {}));
}

namespace {
/// Compressed FCC crystal of Hertz spheres, half of them (at random) `ratio` times lighter,
/// disturbed by up to `jitter` along each axis.
dem::Simulation light_and_heavy_fcc(double a, double d, double ratio, uint64_t seed, double jitter) {
  std::vector<Vec3> x = dem::lattice_sites(dem::LatticeKind::fcc, 4, a);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-jitter, jitter);
  std::bernoulli_distribution light(0.5);
  Material heavy;
  heavy.density = 4000;
  heavy.youngs_modulus = 4e11;
  heavy.poisson_ratio = 0.2;
  Material feather = heavy;
  feather.density = heavy.density / ratio;
  dem::Particles p;
  for (auto& xi : x) {
    const int ph = light(rng) ? 1 : 0;
    p.add(xi + Vec3{u(rng), u(rng), u(rng)}, 0.5 * d, ph ? feather.density : heavy.density, ph);
  }
  dem::ContactModel m;
  m.normal = dem::NormalLaw::hertz;
  m.materials = {heavy, feather};
  m.n_phases = 2;
  m.finalize();
  return dem::Simulation(std::move(p), Cell::box({0, 0, 0}, {4 * a, 4 * a, 4 * a}, true), m);
}
}  // namespace

TEST(Fire, StiffnessScaledMassesReachTheSameMinimumWhateverTheDensities) {
  // Masses change the path, not the minimum. Scaled by their contacts' stiffness, the masses no
  // longer depend on the densities at all (only the time unit does), so the minimisation takes
  // the same steps for densities 1:1 and 100:1; with physical masses the step is the Rayleigh
  // time of the light spheres (10× shorter, T_R ∝ √ρ) and the heavy ones lag.
  // Hertz lattice energy: 6N contacts of (8/15) E* √R* δ^{5/2}, E* = E / (2(1 − ν²)), R* = d/4.
  const double d = 1e-6, delta = 2e-3 * d, a = std::sqrt(2.0) * (d - delta);
  const double E_star = 4e11 / (2 * (1 - 0.2 * 0.2));
  const auto relax = [&](double ratio, bool scaled) {
    dem::Simulation sim = light_and_heavy_fcc(a, d, ratio, 11, 0.02 * d);
    const std::vector<double> m0 = sim.particles().m;
    dem::FireOptions o;
    o.unbalanced_force_ratio = 1e-9;
    o.scale_masses = scaled;
    const dem::FireResult r = dem::minimise_fire(sim, o);
    EXPECT_TRUE(r.converged) << "ratio " << ratio << ", scaled " << scaled << ": " << r.steps << " steps";
    const double n = double(sim.particles().size());
    const double expected = 6 * n * (8.0 / 15.0) * E_star * std::sqrt(0.25 * d) * std::pow(delta, 2.5);
    // Force ratio 1e-9 at the unique lattice minimum: energy far better than 1e-6.
    EXPECT_NEAR(r.last.elastic_energy / expected, 1, 1e-6) << "ratio " << ratio << ", scaled " << scaled;
    EXPECT_EQ(sim.particles().m, m0);  // physical masses restored
    return r.steps;
  };
  const long scaled_even = relax(1, true), scaled_mixed = relax(100, true), physical_mixed = relax(100, false);
  EXPECT_EQ(scaled_even, scaled_mixed);
  EXPECT_LT(scaled_mixed, physical_mixed);
}

TEST(Fire, EnthalpyMinimumOfAHertzLatticeWithTheStepCapFollowingTheMotion) {
  // A disturbed FCC crystal of Hertz spheres relaxed with the cell free at a pressure P a few
  // 1e-6 E (overlaps of 1e-4 d, as a ceramic powder at 1 MPa) must end on the lattice whose
  // pressure is P: p = (1/3V) Σ f l = 8 f (d − δ) / a³ with f = (4/3) E* √R* δ^{3/2}, R* = d/4,
  // a = √2 (d − δ). Near the minimum the particles move slowly; with the speed cap and the mass
  // floor following the motion (FireOptions::adaptive_step_cap) their masses come from their
  // own twelve contacts instead of the floor of a full-speed collision (2.7× stiffer here), so the
  // same minimum is reached in fewer FIRE steps (an operation count; the run is deterministic).
  const double d = 1e-6, delta = 1e-4 * d, E_star = 4e11 / (2 * (1 - 0.2 * 0.2));
  const double a = std::sqrt(2.0) * (d - delta);
  const double f = 4.0 / 3.0 * E_star * std::sqrt(0.25 * d) * std::pow(delta, 1.5);
  const double P = 8 * f * (d - delta) / (a * a * a);
  long steps[2];
  for (const bool adaptive : {true, false}) {
    // Start 5× more compressed, disturbed by 1e-3 d (ten overlaps).
    const double a0 = std::sqrt(2.0) * (d - 5 * delta);
    dem::Simulation sim = light_and_heavy_fcc(a0, d, 1, 11, 1e-3 * d);
    dem::FireOptions o;
    o.unbalanced_force_ratio = 1e-8;
    dem::EnthalpyOptions e;
    e.pressure = P;
    e.pressure_tolerance = 1e-7;
    o.adaptive_step_cap = adaptive;
    const dem::FireResult r = dem::minimise_enthalpy(sim, o, e);
    ASSERT_TRUE(r.converged) << "adaptive " << adaptive << ": " << r.steps << " steps, ratio "
                             << r.last.unbalanced_force_ratio;
    const double n = double(sim.particles().size());
    const double a_end = std::cbrt(4 * sim.cell().volume() / n), delta_end = d - a_end / std::sqrt(2.0);
    // p within 1e-7 of P puts δ within (2/3)·1e-7 of the lattice's (p ∝ δ^{3/2} to 1e-4); the
    // forces left (1e-8 of the mean contact force) move the particles by ~1e-8 δ. 1e-6 is loose.
    EXPECT_NEAR(delta_end / delta, 1, 1e-6) << "adaptive " << adaptive;
    EXPECT_NEAR(r.last.coordination, 12, 1e-12) << "adaptive " << adaptive;
    steps[adaptive ? 0 : 1] = r.steps;
  }
  std::printf("FIRE steps to the lattice at P: step cap following the motion %ld, fixed %ld\n", steps[0], steps[1]);
  EXPECT_LT(steps[0], steps[1]);
}
