// FIRE minimisation at a fixed cell (dem/fire.hpp) on 1, 2, 3 and 4 ranks against the serial
// engine (docs/dem.md, "Running on several ranks"). Every rank runs the serial reference itself;
// the decomposed particles are gathered on rank 0 and compared there, and the verdict is shared.
//
// Bitwise, and why: FIRE's decisions (mix or stop, the time step, α) read six sums over the free
// particles (power F·v, the mass-weighted |v|² and |F|², their rotational parts, Σ|F|²). On
// ranks they are the serial loop over every rank's free particles gathered in id order, so every
// rank holds the serial bits and decides as the serial run does in the same steps; the forces
// and the stiffness sums behind the scaled masses are the serial ones with one thread per rank
// (a ghost takes its owner's mass). So the steps, the positions and the restored masses are the
// serial ones bit for bit. The convergence test reads the measurement (unbalanced-force ratio),
// whose sums add the ranks' parts in rank order: it agrees to round-off, and the final energy,
// pressure and ratio are compared to relative 1e-12, the reordering bound n·ε of sums of
// n ~ 10^3 terms (ε = 2.2e-16) with margin. The enthalpy minimiser (the cell as a degree of
// freedom) is refused on ranks with an InputError on every rank.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <cstring>
#include <random>
#include <string>

#include "tomodem/core/error.hpp"
#include "tomodem/dem/decomposition.hpp"
#include "tomodem/dem/fire.hpp"
#include "tomodem/dem/scene.hpp"
#include "tomodem/dem/simulation.hpp"
#include "mpi_test.hpp"

using namespace tomodem;
using namespace tomodem::dem;
using namespace tomodem::test;  // world_rank, all_ranks, rank0_verdict, same

namespace {

/// A disordered packing above jamming: an FCC crystal of 5³ cells (500 spheres) of mean diameter d
/// at nearest-neighbour distance d (packing fraction 0.76 with the radii ±15 %), positions
/// jittered by ±0.25 d, periodic. Hertz contacts, frictionless, or with Mindlin
/// friction 0.3 (spins and torques in FIRE's sums).
Simulation jammed(bool friction) {
  constexpr int cells = 5;
  const double d = 1e-3, a = std::sqrt(2.0) * d;
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Particles p;
  for (const Vec3& x : lattice_sites(LatticeKind::fcc, cells, a))
    p.add(x + 0.25 * d * Vec3{u(rng), u(rng), u(rng)}, 0.5 * d * (1 + 0.15 * u(rng)), 2500, 0);
  Material m0;
  m0.name = "glass";
  m0.youngs_modulus = 1e8;
  m0.poisson_ratio = 0.25;
  m0.density = 2500;
  ContactModel m;
  m.materials = {m0};
  m.normal = NormalLaw::hertz;
  m.tangential = friction ? TangentialLaw::mindlin : TangentialLaw::none;
  m.finalize();
  m.pair(0, 0).friction = friction ? 0.3 : 0.0;
  m.finalize();
  Settings set;
  set.skin = 0.02 * d;  // small: rebuilds and migration during the minimisation
  set.threads = 1;
  Simulation sim(std::move(p), Cell::box({0, 0, 0}, {cells * a, cells * a, cells * a}, true), m, set);
  sim.set_time_step(0.1 * sim.critical_time_step());
  return sim;
}

void fire_matches_serial(bool friction, const char* name) {
  FireOptions o;
  o.unbalanced_force_ratio = 1e-6;
  Simulation serial = jammed(friction);
  const std::vector<double> m0 = serial.particles().m;
  const double dt0 = serial.time_step();
  const FireResult rs = minimise_fire(serial, o);
  Simulation sim = jammed(friction);
  decompose(sim);
  const FireResult rp = minimise_fire(sim, o);
  const Particles all = gather_particles(sim);
  double migrated = double(layout(sim).migrated);
  MPI_Allreduce(MPI_IN_PLACE, &migrated, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_EQ(rs.steps, rp.steps) << name;
  EXPECT_EQ(rs.converged, rp.converged) << name;
  EXPECT_EQ(sim.time_step(), dt0) << name << ": the caller's time step comes back";
  const auto rel = [](double a, double b) { return std::abs(a - b) / std::max(std::abs(a), 1e-300); };
  EXPECT_LE(rel(rs.last.elastic_energy, rp.last.elastic_energy), 1e-12) << name;
  EXPECT_LE(rel(rs.last.pressure, rp.last.pressure), 1e-12) << name;
  EXPECT_LE(rel(rs.last.unbalanced_force_ratio, rp.last.unbalanced_force_ratio), 1e-12) << name;
  EXPECT_EQ(rs.last.contacts, rp.last.contacts) << name;
  std::string diff;
  if (world_rank() == 0) {
    const Particles& p = serial.particles();
    for (std::size_t i = 0; i < p.size() && diff.empty(); ++i)
      if (!same(p.x[i], all.x[i]) || !same(p.v[i], all.v[i]) || p.m[i] != all.m[i] || all.m[i] != m0[i] ||
          (p.has_rotation() && !same(p.omega[i], all.omega[i])))
        diff = std::string(name) + ": particle " + std::to_string(i);
    EXPECT_TRUE(rs.converged) << name << ": " << rs.steps << " steps, ratio " << rs.last.unbalanced_force_ratio;
    std::printf("%s on %d ranks: %ld FIRE steps, converged %d, ratio %.2e, Z %.3f, pressure %.6e Pa, %.0f migrations\n",
                name, world_size(), rp.steps, int(rp.converged), rp.last.unbalanced_force_ratio, rp.last.coordination,
                rp.last.pressure, migrated);
  }
  EXPECT_TRUE(all_ranks(diff.empty())) << diff;
}

TEST(DemDecompositionFire, FrictionlessJammedPackingRelaxesAsSerial) { fire_matches_serial(false, "frictionless"); }

TEST(DemDecompositionFire, FrictionalJammedPackingRelaxesAsSerial) { fire_matches_serial(true, "frictional"); }

TEST(DemDecompositionFire, EnthalpyMinimiserIsRefusedOnEveryRank) {
  Simulation sim = jammed(false);
  decompose(sim);
  std::string why;
  try {
    EnthalpyOptions e;
    e.pressure = 1e5;
    minimise_enthalpy(sim, {}, e);
  } catch (const InputError& err) {
    why = std::string(err.field()) + ": " + err.why();
  }
  EXPECT_EQ(why.rfind("minimise: the enthalpy minimiser (the cell as a degree of freedom) is not decomposed yet", 0), 0u) << why;
  sim.run(10);  // still runnable, every rank in step
}

}  // namespace

