// The energy budget (Settings::track_energy) across ranks against the serial engine, on 1, 2, 3
// and 4 ranks (docs/dem.md, "Running on several ranks"): kinetic and elastic energy, the
// dissipated energy (contact damping and friction, Cundall's local damping, Stokes drag) and the
// external work (gravity, a moving wall, a force-controlled wall, a deforming cell), each a
// global reduction over the owned particles and the owned rows.
//
// Two scenes: the falling column of the wall tests (falling_column.hpp) with local damping, and
// a periodic cell under simple shear with Stokes drag (the cell's work through the virial).
// Tracking the budget changes nothing in the trajectory, so the particles stay bitwise the
// serial ones. The budget terms add the ranks' parts in rank order (and the accounts add one
// such sum per step), so they agree with the serial run to round-off: each is compared to a
// relative 1e-12 of the budget's scale (|E_0| + |W| + |E_diss| + E_kin + E_el), the reordering
// bound n·ε of sums of n ~ 10^3 terms (ε = 2.2e-16) with margin; the balance error, a
// difference of those terms, is held to the same absolute bound.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <random>

#include "falling_column.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/dem/decomposition.hpp"
#include "tomodem/dem/scene.hpp"
#include "tomodem/dem/simulation.hpp"
#include "mpi_test.hpp"

using namespace tomodem;
using namespace tomodem::dem;
using namespace tomodem::test;  // world_rank, all_ranks, rank0_verdict, same
using namespace tomodem::dem::mpi_test;

namespace {

/// 10³ jittered spheres (±10 % radius) with random velocities in a periodic cell sheared at
/// γ̇ = 200 /s, Stokes drag η = 0.05 Pa s, energy tracked.
Simulation sheared_cell() {
  constexpr int n = 10;
  const double R = 0.5e-3, s = 2.05 * R;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Particles p;
  for (const Vec3& x : lattice_sites(LatticeKind::simple_cubic, n, s)) {
    p.add(x + Vec3{0.02 * R * u(rng), 0.02 * R * u(rng), 0.02 * R * u(rng)}, R * (1 + 0.02 * u(rng)), 2500, 0);
    p.v.back() = Vec3{0.1 * u(rng), 0.1 * u(rng), 0.1 * u(rng)};
  }
  Material m0;
  m0.name = "glass";
  m0.youngs_modulus = 1e8;
  m0.poisson_ratio = 0.25;
  m0.density = 2500;
  ContactModel m;
  m.materials = {m0};
  m.normal = NormalLaw::hertz;
  m.tangential = TangentialLaw::mindlin;
  m.finalize();
  m.pair(0, 0).friction = 0.5;
  m.pair(0, 0).restitution = 0.5;
  m.finalize();
  Settings set;
  set.skin = 0.04 * R;
  set.threads = 1;
  set.track_energy = true;
  Simulation sim(std::move(p), Cell::box({0, 0, 0}, {n * s, n * s, n * s}, true), m, set);
  sim.body_forces().fluid_viscosity = 0.05;
  sim.cell_control().velocity_gradient(0, 1) = 200.0;
  sim.set_time_step(0.2 * sim.critical_time_step());
  return sim;
}

struct Budget {
  double kinetic, elastic, dissipated, work, error, e_scale;
};
Budget budget(const Measurements& m) {
  const double e0 = m.kinetic_energy + m.elastic_energy + m.dissipated_energy - m.external_work - m.energy_balance_error;
  return {m.kinetic_energy, m.elastic_energy, m.dissipated_energy, m.external_work, m.energy_balance_error,
          std::abs(e0) + std::abs(m.external_work) + std::abs(m.dissipated_energy) + m.kinetic_energy + m.elastic_energy};
}

void compare_with_serial(const std::function<Simulation()>& make, int steps, int every, const char* name) {
  Simulation serial = make();
  Simulation sim = make();
  decompose(sim);
  std::string diff;
  double worst = 0;
  Budget last{};
  for (int k = 0; k < steps; k += every) {
    serial.run(every);
    sim.run(every);
    const Budget a = budget(serial.measure()), b = budget(sim.measure());
    const double tol = 1e-12 * a.e_scale;
    const double d[] = {a.kinetic - b.kinetic, a.elastic - b.elastic, a.dissipated - b.dissipated, a.work - b.work,
                        a.error - b.error};
    for (double x : d) worst = std::max(worst, std::abs(x) / a.e_scale);
    for (double x : d)
      if (!(std::abs(x) <= tol)) diff = std::string(name) + ": budget differs at step " + std::to_string(k + every);
    last = a;
  }
  const Particles all = gather_particles(sim);
  if (world_rank() == 0 && diff.empty()) {
    const Particles& p = serial.particles();
    for (std::size_t i = 0; i < p.size() && diff.empty(); ++i)
      if (!same(p.x[i], all.x[i]) || !same(p.v[i], all.v[i]) || !same(p.omega[i], all.omega[i]))
        diff = std::string(name) + ": particle " + std::to_string(i);
  }
  EXPECT_TRUE(all_ranks(diff.empty())) << diff;
  // Every term must be at work for the comparison to mean something.
  EXPECT_GT(last.dissipated, 0.1 * last.e_scale) << name;
  EXPECT_GT(std::abs(last.work), 0.1 * last.e_scale) << name;
  if (world_rank() == 0)
    std::printf("%s on %d ranks: E_kin %.4e, E_el %.4e, E_diss %.4e, W %.4e J, balance error %.2e J; worst "
                "difference %.1e of the budget\n", name, world_size(), last.kinetic, last.elastic, last.dissipated,
                last.work, last.error, worst);
}

TEST(DemDecompositionEnergy, FallingColumnWithWallsAndLocalDampingMatchesSerial) {
  compare_with_serial([] { return falling_column(true, 0.05); }, 2000, 250, "falling column");
}

TEST(DemDecompositionEnergy, ShearedCellWithStokesDragMatchesSerial) {
  compare_with_serial(sheared_cell, 1000, 250, "sheared cell");
}

}  // namespace

