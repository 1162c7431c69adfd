// Walls across ranks (docs/dem.md, "Running on several ranks"): spheres falling under gravity
// onto a fixed floor while a force-controlled lid comes down on them, on 1, 2, 3 and 4 ranks
// against the serial engine, cut across the walls' plane (default grid) and along the walls'
// normal (every rank a layer: the floor's contacts on one rank, the lid's on another, spheres
// migrating down through the layers). Every rank runs the serial reference itself; the
// decomposed particles are gathered on rank 0 and compared there, the walls on every rank, and
// the verdict is shared so that every rank passes or fails together.
//
// Bitwise, and why: with one thread per rank a particle sums its contacts, then its walls in
// wall order, as the serial engine does; a wall's force is gathered contact by contact and added
// in particle order on every rank (the serial loop's order), so the lid's servo, which reads
// that force and the floor's contact stiffness, moves the lid by the same bits on every rank
// and the whole trajectory is the serial one bit for bit. Sums over the cell (stress) add the
// ranks' parts in rank order: relative 1e-12, the reordering bound n·ε of a sum of n ~ 10^4
// terms (ε = 2.2e-16) with margin.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <cstring>
#include <memory>

#include "falling_column.hpp"
#include "tomodem/dem/decomposition.hpp"
#include "tomodem/dem/simulation.hpp"
#include "mpi_test.hpp"

using namespace tomodem;
using namespace tomodem::dem;
using namespace tomodem::test;  // world_rank, all_ranks, rank0_verdict, same
using namespace tomodem::dem::mpi_test;

namespace {

struct Trace {
  std::vector<Measurements> rows;
  std::vector<std::vector<Wall>> walls;  // after each block of steps
};

Trace run(Simulation& sim) {
  Trace t;
  for (int s = 0; s < kSteps; s += kEvery) {
    sim.run(kEvery);
    t.rows.push_back(sim.measure());
    t.walls.push_back(sim.walls());
  }
  return t;
}

/// The serial run, once per process (each test compares its decomposition with it).
const std::pair<Particles, Trace>& serial_run() {
  static std::unique_ptr<std::pair<Particles, Trace>> ref;
  if (!ref) {
    Simulation sim = falling_column();
    Trace t = run(sim);
    ref = std::make_unique<std::pair<Particles, Trace>>(sim.particles(), std::move(t));
  }
  return *ref;
}

/// Runs the column decomposed with `opt` and compares it with the serial run.
void compare_with_serial(const DecompositionOptions& opt) {
  const auto& [ref_p, ref] = serial_run();
  Simulation sim = falling_column();
  decompose(sim, opt);
  const Trace got = run(sim);
  std::string diff;
  double worst_stress = 0;
  // The walls on every rank: point, velocity and force bitwise, after every block.
  for (std::size_t k = 0; k < ref.walls.size() && diff.empty(); ++k)
    for (std::size_t w = 0; w < ref.walls[k].size(); ++w) {
      const Wall &a = ref.walls[k][w], &b = got.walls[k][w];
      if (!same(a.point, b.point) || !same(a.velocity, b.velocity) || !same(a.force, b.force))
        diff = "wall " + std::to_string(w) + " after block " + std::to_string(k) + " on rank " + std::to_string(world_rank());
    }
  for (std::size_t k = 0; k < ref.rows.size() && diff.empty(); ++k) {
    const Measurements &a = ref.rows[k], &b = got.rows[k];
    if (a.contacts != b.contacts || a.wall_contacts != b.wall_contacts || a.neighbor_rebuilds != b.neighbor_rebuilds)
      diff = "counts at block " + std::to_string(k);
    for (std::size_t w = 0; w < a.wall_forces.size(); ++w)
      if (!same(a.wall_forces[w], b.wall_forces[w])) diff = "measured wall force " + std::to_string(w);
    if (a.volume != b.volume) diff = "measured volume at block " + std::to_string(k);
    const double scale = std::max(std::abs(a.stress(2, 2)), 1e-300);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) worst_stress = std::max(worst_stress, std::abs(a.stress(i, j) - b.stress(i, j)) / scale);
    const std::pair<double, double> sums[] = {{a.kinetic_energy, b.kinetic_energy}, {a.elastic_energy, b.elastic_energy},
                                              {a.unbalanced_force_ratio, b.unbalanced_force_ratio}};
    for (const auto& [x, y] : sums)
      if (std::abs(x - y) > 1e-12 * std::abs(x)) diff = "energies or unbalanced force at block " + std::to_string(k);
  }
  if (worst_stress > 1e-12) diff = "stress differs by " + std::to_string(worst_stress);
  long migrated = layout(sim).migrated;
  MPI_Allreduce(MPI_IN_PLACE, &migrated, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
  const Particles all = gather_particles(sim);
  if (world_rank() == 0 && diff.empty()) {
    if (all.size() != ref_p.size()) diff = "particle count";
    for (std::size_t i = 0; i < ref_p.size() && diff.empty(); ++i)
      if (!same(ref_p.x[i], all.x[i]) || !same(ref_p.v[i], all.v[i]) || !same(ref_p.omega[i], all.omega[i]))
        diff = "particle " + std::to_string(i);
  }
  EXPECT_TRUE(all_ranks(diff.empty())) << diff;
  // The comparison proves something only if the walls did: both carry contacts at the end, the
  // floor's servo has moved it, and on several ranks particles migrated.
  const Measurements& last = ref.rows.back();
  EXPECT_GT(last.wall_contacts, 50);
  EXPECT_GT(-last.wall_forces[0].z, 1.0);  // the floor carries the weight and the lid's push
  EXPECT_GT(last.wall_forces[1].z, 0.1);   // the lid touches
  EXPECT_NE(ref.walls.back()[0].point.z, 0.0);
  if (world_size() > 1) EXPECT_GT(migrated, 0);
  if (world_rank() == 0)
    std::printf("%d ranks (%dx%dx%d): %ld migrations, %ld wall contacts, floor %.4f N at z %.4f mm, lid %.4f N; "
                "stress agrees to %.1e\n", world_size(), layout(sim).dims[0], layout(sim).dims[1], layout(sim).dims[2],
                migrated, last.wall_contacts, -last.wall_forces[0].z, 1e3 * ref.walls.back()[0].point.z,
                last.wall_forces[1].z, worst_stress);
}

TEST(DemDecompositionWalls, FallingColumnDefaultGridMatchesSerial) { compare_with_serial({}); }

TEST(DemDecompositionWalls, FallingColumnLayersAlongTheWallNormalMatchSerial) {
  DecompositionOptions opt;
  opt.dims = {1, 1, world_size()};  // each rank a layer: floor and lid contacts on different ranks
  compare_with_serial(opt);
}

}  // namespace

