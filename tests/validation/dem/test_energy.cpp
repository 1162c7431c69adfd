// Energy: velocity Verlet on an undamped elastic packing conserves E_kin + E_el up to an error
// of order Δt² (it is a second-order symplectic scheme), and with track_energy the budget
// E_kin + E_el + E_dissipated − E_0 − W_ext closes for a damped frictional packing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "packings.hpp"

using namespace tomodem;
using namespace tomodem::dem;
using namespace tomodem::dem::testing;

namespace {
constexpr double R = 1e-3, rho = 2500, E = 1e8, nu = 0.25;

/// 64 spheres (±10%) in a periodic cube at solid fraction ≈ 0.45 with random velocities:
/// every particle has several collisions over the run. 64 is enough for a many-contact
/// chaotic gas in which contacts open and close all the time, which is the case at stake.
LatticeSpec gas_spec() {
  LatticeSpec s;
  s.n = 4;
  s.radius = R;
  s.polydispersity = 0.1;
  s.spacing = 2.1;
  s.jitter = 0.02;
  s.speed = 0.5;
  s.seed = 7;
  return s;
}
}  // namespace

// Max |E(t) − E_0|/E_0 over a fixed physical time, for Δt = f·Δt_crit with f = 0.2, 0.1, 0.05.
// The run lasts ~10 contact durations (short enough that the three trajectories still visit
// the same collisions: chaos would otherwise make the error a random sample per Δt).
// Expected order 2 (Verlet); the issue asks for 2 ± 0.3 (the Hertz force is only C¹ at δ = 0,
// which adds higher-order terms at contact onset).
TEST(EnergyConservation, UndampedHertzPackingDriftFallsAsDtSquared) {
  const ContactModel m = model(NormalLaw::hertz, TangentialLaw::none, material(E, nu, rho), 1.0);
  std::vector<double> dts, errs;
  double t_end = 0;
  for (double frac : {0.2, 0.1, 0.05}) {
    Simulation sim = lattice(m, gas_spec());
    const double dt = frac * sim.critical_time_step();
    if (t_end == 0) t_end = 800 * dt;
    sim.set_time_step(dt);
    const double e0 = mechanical_energy(sim);
    double err = 0;
    const long steps = std::lround(t_end / dt);
    const long every = steps / 100;
    long contacts = 0;
    for (long k = 0; k < steps; k += every) {
      sim.run(every);
      const Measurements me = sim.measure();
      contacts += me.contacts;
      err = std::max(err, std::abs(me.kinetic_energy + me.elastic_energy - e0) / e0);
    }
    ASSERT_GT(contacts, 100) << "the packing must collide";
    dts.push_back(dt);
    errs.push_back(err);
  }
  const double order = log_slope(dts, errs);
  for (std::size_t k = 0; k < errs.size(); ++k) report("max |E - E0|/E0 at dt = " + std::to_string(dts[k]), errs[k]);
  report("order", order);
  EXPECT_NEAR(order, 2.0, 0.3) << "errors " << errs[0] << " " << errs[1] << " " << errs[2];
  EXPECT_LT(errs[2], 1e-3);
}

// Damped linear normal law (e = 0.5) with a linear tangential spring and Coulomb friction
// (μ = 0.4), spinning particles: the tallies of dashpot, slip and released-spring dissipation
// must close the budget. The dashpot power is tallied once per step with the half-step velocity
// against the end-of-step force, a first-order quadrature: per step its relative error is at
// most ω Δt/2 (4% at Δt = 0.05 Δt_crit), with opposite signs on loading and unloading, so the
// budget closes to O(Δt). The test asks for that order (halving Δt halves the error:
// order 1 ± 0.3) and for an error below 2% of E_0 at Δt = 0.05 Δt_crit (measured 0.84%). A
// budget that misses a mechanism does not converge (before the fixes of 842853a and 51c521c
// the error grew as Δt fell: 1.0%, 2.1%, 2.6%).
TEST(EnergyBalance, DampedFrictionalPackingBudgetCloses) {
  ContactModel m;
  m.normal = NormalLaw::linear;
  m.tangential = TangentialLaw::linear;
  m.materials = {material(E, nu, rho)};
  m.finalize();
  m.pair(0, 0).k_n = 1e4;
  m.pair(0, 0).restitution = 0.5;
  m.pair(0, 0).friction = 0.4;
  m.finalize();
  LatticeSpec s = gas_spec();
  Settings set;
  set.track_energy = true;
  std::vector<double> errs;
  double e0 = 0, dissipated = 0;
  for (double frac : {0.1, 0.05}) {
    LatticeSpec spec = s;
    Particles p = lattice_particles(spec);
    // Spin the particles too, so that the sliding and rolling parts of the contact velocity matter.
    p.enable_rotation();
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (auto& w : p.omega) w = {200 * u(rng), 200 * u(rng), 200 * u(rng)};
    Simulation sim(std::move(p), lattice_cell(spec), m, set);
    const double dt = frac * sim.critical_time_step();
    sim.set_time_step(dt);
    e0 = mechanical_energy(sim);
    const long steps = std::lround(4000 * 0.05 / frac);
    double worst = 0;
    for (long k = 0; k < steps; k += steps / 50) {
      sim.run(steps / 50);
      const Measurements me = sim.measure();
      worst = std::max(worst, std::abs(me.energy_balance_error));
      dissipated = me.dissipated_energy;
    }
    errs.push_back(worst / e0);
  }
  ASSERT_GT(dissipated, 0.3 * e0) << "the run must dissipate a large part of the energy";
  report("balance error / E0 at 0.1 dt_crit", errs[0]);
  report("balance error / E0 at 0.05 dt_crit", errs[1]);
  report("dissipated / E0", dissipated / e0);
  EXPECT_LT(errs[1], 0.02);
  EXPECT_NEAR(std::log2(errs[0] / errs[1]), 1.0, 0.3) << "errors " << errs[0] << " " << errs[1];
}

namespace {
/// Worst |budget error|/E0 at Δt = 0.1 and 0.05 Δt_crit for the spinning gas of the tests below,
/// and the energy dissipated at the finer step (so a test can require that much happened).
struct Budget {
  std::vector<double> errs;
  double dissipated_fraction = 0;
};
Budget budget_errors(const ContactModel& m) {
  LatticeSpec s = gas_spec();
  Settings set;
  set.track_energy = true;
  Budget b;
  for (double frac : {0.1, 0.05}) {
    Particles p = lattice_particles(s);
    p.enable_rotation();
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (auto& w : p.omega) w = {200 * u(rng), 200 * u(rng), 200 * u(rng)};
    Simulation sim(std::move(p), lattice_cell(s), m, set);
    sim.set_time_step(frac * sim.critical_time_step());
    const double e0 = mechanical_energy(sim);
    const long steps = std::lround(4000 * 0.05 / frac);
    double worst = 0, dissipated = 0;
    for (long k = 0; k < steps; k += steps / 50) {
      sim.run(steps / 50);
      const Measurements me = sim.measure();
      worst = std::max(worst, std::abs(me.energy_balance_error));
      dissipated = me.dissipated_energy;
    }
    b.errs.push_back(worst / e0);
    b.dissipated_fraction = dissipated / e0;
  }
  return b;
}
}  // namespace

// The same budget with Hertz + Mindlin (e = 0.5, μ = 0.4): Mindlin's k_t = 8G*a changes with
// the contact radius, and the energy its spring gains or loses at constant force is booked
// (signed) in the dissipation tally (laws.hpp), as is the spring energy left when a contact
// opens (k_t of its last step). Without them the balance was off by 6–9 % of E0 and grew as
// Δt fell; now 0.60 % and 0.28 %. Tolerance as for the linear laws: < 2 % and first order.
TEST(EnergyBalance, DampedHertzMindlinPackingBudgetCloses) {
  const Budget b = budget_errors(model(NormalLaw::hertz, TangentialLaw::mindlin, material(E, nu, rho), 0.5, 0.4));
  ASSERT_GT(b.dissipated_fraction, 0.3) << "the run must dissipate a large part of the energy";
  report("Hertz-Mindlin balance error / E0 at 0.1 dt_crit", b.errs[0]);
  report("Hertz-Mindlin balance error / E0 at 0.05 dt_crit", b.errs[1]);
  EXPECT_LT(b.errs[1], 0.02);
  EXPECT_NEAR(std::log2(b.errs[0] / b.errs[1]), 1.0, 0.3) << "errors " << b.errs[0] << " " << b.errs[1];
}

// With rolling resistance (elastic–plastic spring, μ_r = 0.1) on top: its k_r = 2.25 S_n μ_r² R*²
// follows the contact radius like Mindlin's k_t, so the same two terms (stiffness change at
// constant moment, spring energy left at opening) must be booked; same tolerance and order. The
// spinning gas keeps many contacts rolling, and the rolling spring dissipates a visible share.
TEST(EnergyBalance, HertzMindlinWithRollingResistanceBudgetCloses) {
  ContactModel m = model(NormalLaw::hertz, TangentialLaw::mindlin, material(E, nu, rho), 0.5, 0.4);
  m.rolling = RollingLaw::elastic_plastic;
  m.pair(0, 0).rolling_friction = 0.1;
  m.finalize();
  const Budget b = budget_errors(m);
  ASSERT_GT(b.dissipated_fraction, 0.3) << "the run must dissipate a large part of the energy";
  report("with rolling: balance error / E0 at 0.1 dt_crit", b.errs[0]);
  report("with rolling: balance error / E0 at 0.05 dt_crit", b.errs[1]);
  EXPECT_LT(b.errs[1], 0.02);
  EXPECT_NEAR(std::log2(b.errs[0] / b.errs[1]), 1.0, 0.3) << "errors " << b.errs[0] << " " << b.errs[1];
}
