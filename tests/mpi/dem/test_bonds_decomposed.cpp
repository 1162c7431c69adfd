// A bonded network pulled to failure on 1, 2, 3 and 4 ranks against the serial engine
// (docs/dem.md, "Running on several ranks"). Every rank runs the serial reference itself; the
// decomposed run's particles, bonds and bond events are gathered on rank 0 and compared there,
// and the verdict is shared so that every rank passes or fails together.
//
// Bitwise where the order allows it: with one thread per rank a particle sums its contacts and
// then its bonds in the serial order (bonds in the order of the whole set), and a bond between
// an owned particle and a ghost is computed on both ranks from the same bits, so the trajectory,
// the bond state (shear force, twist, bending moment) and the step each bond breaks in are the
// serial ones bit for bit. The stress adds the ranks' parts in rank order: relative 1e-12, the
// reordering bound n·ε of a sum of n ~ 10^4 terms (ε = 2.2e-16) with margin.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <cstring>

#include "bonded_lattice.hpp"
#include "tomodem/dem/bonds.hpp"
#include "tomodem/dem/decomposition.hpp"
#include "tomodem/dem/scene.hpp"
#include "tomodem/dem/simulation.hpp"
#include "mpi_test.hpp"

using namespace tomodem;
using namespace tomodem::dem;
using namespace tomodem::test;  // world_rank, all_ranks, rank0_verdict, same
using tomodem::dem::mpi_test::bonded_lattice;

namespace {

TEST(DemDecompositionBonds, LatticeToFailureMatchesSerial) {
  const int rows = 15, every = 100;
  Simulation serial = bonded_lattice();
  Simulation sim = bonded_lattice();
  const double dt = serial.time_step();
  decompose(sim);
  double worst_stress = 0;
  long worst_intact = 0;
  for (int r = 0; r < rows; ++r) {
    serial.run(every);
    sim.run(every);
    const Measurements ms = serial.measure(), mp = sim.measure();
    const double scale = std::max(std::abs(ms.stress(2, 2)), 1.0);
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) worst_stress = std::max(worst_stress, std::abs(ms.stress(a, b) - mp.stress(a, b)) / scale);
    worst_intact = std::max(worst_intact, std::abs(ms.bonds - mp.bonds));
  }
  const Particles all = gather_particles(sim);
  const BondSet bonds = gather_bonds(sim);
  const std::vector<BondEvent> events = gather_bond_events(sim);
  std::string diff;
  if (world_rank() == 0) {
    EXPECT_LE(worst_stress, 1e-12);
    EXPECT_EQ(worst_intact, 0) << "intact bond counts differ";
    const Particles& p = serial.particles();
    for (std::size_t i = 0; i < p.size() && diff.empty(); ++i)
      if (!same(p.x[i], all.x[i]) || !same(p.v[i], all.v[i]) || !same(p.omega[i], all.omega[i]))
        diff = "particle " + std::to_string(i);
    const BondSet& B = serial.bonds();
    ASSERT_EQ(B.size(), bonds.size());
    for (std::size_t b = 0; b < B.size() && diff.empty(); ++b)
      if (B.i[b] != bonds.i[b] || B.j[b] != bonds.j[b] || B.state[b] != bonds.state[b] || B.mode[b] != bonds.mode[b] ||
          !same(B.broken_at[b], bonds.broken_at[b]) || !same(B.shear_force[b], bonds.shear_force[b]) ||
          !same(B.twist[b], bonds.twist[b]) || !same(B.bend[b], bonds.bend[b]) || !same(B.image[b], bonds.image[b]))
        diff = "bond " + std::to_string(b);
    const std::vector<BondEvent>& E = serial.bond_events();
    if (diff.empty() && E.size() != events.size()) diff = "event counts " + std::to_string(E.size()) + " and " + std::to_string(events.size());
    for (std::size_t k = 0; k < E.size() && diff.empty(); ++k)
      if (!same(E[k].time, events[k].time) || E[k].bond != events[k].bond || E[k].mode != events[k].mode ||
          !same(E[k].position, events[k].position) || !same(E[k].energy, events[k].energy))
        diff = "event " + std::to_string(k);
    // The test proves something only if bonds broke, in both modes, over many steps.
    long tension = 0, shear = 0;
    for (uint8_t m : B.mode) tension += m == BondSet::tension, shear += m == BondSet::shear;
    EXPECT_GT(tension, 10);
    EXPECT_GT(shear, 0);
    std::vector<double> times;
    for (const auto& e : E) times.push_back(e.time);
    std::sort(times.begin(), times.end());
    times.erase(std::unique(times.begin(), times.end()), times.end());
    EXPECT_GT(times.size(), 20u) << "bonds broke in " << times.size() << " distinct steps";
    EXPECT_LT(long(B.intact_count()), long(B.size()));
    std::printf("bonds %zu, broken %ld in tension and %ld in shear over %zu steps (first at step %.0f); stress "
                "agrees to %.1e\n", B.size(), tension, shear, times.size(), times.empty() ? 0.0 : times.front() / dt,
                worst_stress);
  }
  EXPECT_TRUE(rank0_verdict(diff.empty())) << diff;
}

}  // namespace

