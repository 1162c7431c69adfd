// Checkpoints and restarts on ranks of runs with bonds, walls and the energy budget (docs/dem.md,
// "Checkpoints on several ranks"), on 1, 2, 3 and 4 ranks against the serial engine. Every rank
// runs the serial reference itself and rank 0 writes its checkpoint; the decomposed run writes its
// own at the same step (every rank at once, HDF5 MPI-IO). Then, on this rank count:
//  - the two files hold the same datasets, bit for bit: the decomposed trajectory is the serial
//    one, and the writer puts every particle, contact row, wall candidate and bond at its serial
//    place. Only the energy accounts (/engine/scalars 5-7) are sums over the ranks in rank order:
//    relative 1e-12, the reordering bound n·ε of sums of n ~ 10^3-10^4 terms (ε = 2.2e-16) per
//    step with margin;
//  - a restart from either file (decompose_restored) ends on the uninterrupted serial run bit for
//    bit: positions, velocities, spins, every bond's state and failure event, the walls' position,
//    velocity and force; the energy terms to 1e-12 of the budget (sums in rank order, as
//    test_energy_decomposed.cpp);
//  - the serial engine restarts from the decomposed file and ends there bit for bit too.
// The scenes: the bonded lattice of the bond tests under tension and shear, checkpointed while
// bonds break (the first at step 480), and the falling column of the wall tests with the energy
// budget and local damping, checkpointed while the lid comes down on the settled column.
#include <gtest/gtest.h>
#include <mpi.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "bonded_lattice.hpp"
#include "falling_column.hpp"
#include "tomodem/core/h5.hpp"
#include "tomodem/dem/checkpoint_ranks.hpp"
#include "tomodem/dem/decomposition.hpp"
#include "tomodem/dem/scene.hpp"
#include "tomodem/dem/simulation.hpp"
#include "mpi_test.hpp"

using namespace tomodem;
using namespace tomodem::dem;
using namespace tomodem::test;  // world_rank, all_ranks, rank0_verdict, same
namespace fs = std::filesystem;

namespace {

/// A scratch folder every rank knows (rank 0's name).
std::string shared_dir(const std::string& name) {
  std::string dir = world_rank() == 0 ? (fs::temp_directory_path() / (name + "_" + std::to_string(::getpid()))).string() : "";
  int len = int(dir.size());
  MPI_Bcast(&len, 1, MPI_INT, 0, MPI_COMM_WORLD);
  dir.resize(std::size_t(len));
  MPI_Bcast(dir.data(), len, MPI_CHAR, 0, MPI_COMM_WORLD);
  if (world_rank() == 0) fs::remove_all(dir), fs::create_directories(dir);
  MPI_Barrier(MPI_COMM_WORLD);
  return dir;
}

void datasets(const h5::File& f, const std::string& group, std::vector<std::string>& out) {
  for (const std::string& name : f.children(group)) {
    const std::string path = (group == "/" ? "" : group) + "/" + name;
    try {
      f.shape(path);
      out.push_back(path);
    } catch (...) {
      datasets(f, path, out);
    }
  }
}

/// What differs between two checkpoints ("" when nothing), bit for bit but the energy accounts.
std::string file_differences(const std::string& a, const std::string& b) {
  const h5::File fa(a, h5::File::Mode::read), fb(b, h5::File::Mode::read);
  std::vector<std::string> da, db;
  datasets(fa, "/", da);
  datasets(fb, "/", db);
  if (da != db) return "dataset lists differ";
  for (const auto& d : da) {
    std::vector<std::size_t> sa, sb;
    const auto va = fa.read_double(d, &sa), vb = fb.read_double(d, &sb);
    if (sa != sb) return d + " (shape)";
    for (std::size_t k = 0; k < va.size(); ++k) {
      const double rel = d == "/engine/scalars" && k >= 5 ? 1e-12 : 0.0;
      if (!(same(va[k], vb[k]) || std::abs(va[k] - vb[k]) <= rel * std::max(std::abs(va[k]), std::abs(vb[k]))))
        return d + "[" + std::to_string(k) + "]: " + std::to_string(va[k]) + " vs " + std::to_string(vb[k]);
    }
  }
  return "";
}

/// The budget's terms and scale (test_energy_decomposed.cpp).
struct Budget {
  double terms[5], scale;
};
Budget budget(const Measurements& m) {
  const double e0 = m.kinetic_energy + m.elastic_energy + m.dissipated_energy - m.external_work - m.energy_balance_error;
  return {{m.kinetic_energy, m.elastic_energy, m.dissipated_energy, m.external_work, m.energy_balance_error},
          std::abs(e0) + std::abs(m.external_work) + std::abs(m.dissipated_energy) + m.kinetic_energy + m.elastic_energy};
}

/// What differs between the end of a run and the serial reference ("" when nothing); the
/// particles, bonds and events are those gathered on rank 0 (empty elsewhere); events_before:
/// the events the checkpoint holds.
std::string state_differences(Simulation& ref, Simulation& sim, const Measurements& mref, const Measurements& m,
                              bool tracked, std::size_t events_before) {
  const Particles all = gather_particles(sim);
  const BondSet bonds = gather_bonds(sim);
  const std::vector<BondEvent> events = gather_bond_events(sim);
  std::string diff;
  for (std::size_t w = 0; w < ref.walls().size() && diff.empty(); ++w) {
    const Wall &a = ref.walls()[w], &b = sim.walls()[w];
    if (!same(a.point, b.point) || !same(a.velocity, b.velocity) || !same(a.force, b.force)) diff = "wall " + std::to_string(w);
  }
  if (tracked && diff.empty()) {
    const Budget a = budget(mref), b = budget(m);
    for (int k = 0; k < 5; ++k)
      if (!(std::abs(a.terms[k] - b.terms[k]) <= 1e-12 * a.scale)) diff = "energy term " + std::to_string(k);
  }
  if (world_rank() != 0 && sim.domain()) return diff;
  const Particles& p = ref.particles();
  const Particles& q = sim.domain() ? all : sim.particles();
  if (q.size() != p.size()) return "particle counts";
  for (std::size_t i = 0; i < p.size() && diff.empty(); ++i)
    if (!same(p.x[i], q.x[i]) || !same(p.v[i], q.v[i]) || (p.has_rotation() && !same(p.omega[i], q.omega[i])))
      diff = "particle " + std::to_string(i);
  const BondSet& A = ref.bonds();
  const BondSet& B = sim.domain() ? bonds : sim.bonds();
  if (diff.empty() && A.size() != B.size()) diff = "bond counts";
  for (std::size_t b = 0; b < A.size() && diff.empty(); ++b)
    if (A.i[b] != B.i[b] || A.j[b] != B.j[b] || A.state[b] != B.state[b] || A.mode[b] != B.mode[b] ||
        !same(A.broken_at[b], B.broken_at[b]) || !same(A.shear_force[b], B.shear_force[b]) ||
        !same(A.twist[b], B.twist[b]) || !same(A.bend[b], B.bend[b]) || !same(A.image[b], B.image[b]))
      diff = "bond " + std::to_string(b);
  const std::vector<BondEvent>& E = ref.bond_events();
  const std::vector<BondEvent>& F = sim.domain() ? events : sim.bond_events();
  if (diff.empty() && E.size() != F.size()) diff = "event counts " + std::to_string(E.size()) + " and " + std::to_string(F.size());
  // The checkpoint keeps an event's time, bond and mode (the serial format): its place and
  // released energy are compared for the events after the restart.
  for (std::size_t k = 0; k < E.size() && diff.empty(); ++k)
    if (!same(E[k].time, F[k].time) || E[k].bond != F[k].bond || E[k].mode != F[k].mode ||
        (k >= events_before && (!same(E[k].position, F[k].position) || !same(E[k].energy, F[k].energy))))
      diff = "event " + std::to_string(k);
  return diff;
}

/// The scene's simulation restored from `file` (every rank reads it whole), decomposed when asked.
std::unique_ptr<Simulation> restored(const std::function<Simulation()>& make, const std::string& file, bool decomposed) {
  Scene scene;
  scene.file = "(test)";
  scene.sim = std::make_unique<Simulation>(make());
  read_checkpoint(file, scene);
  if (decomposed) decompose_restored(*scene.sim);
  return std::move(scene.sim);
}

void restart_matches_serial(const std::function<Simulation()>& make, int first, int second, bool tracked, const char* name) {
  const std::string dir = shared_dir(std::string("tomodem_ck_state_") + name);
  const std::string serial_file = dir + "/serial.h5", ranks_file = dir + "/ranks.h5";
  // The uninterrupted serial run, with rank 0's checkpoint half way.
  Simulation ref = make();
  ref.run(first);
  const std::size_t events_before = ref.bond_events().size();
  const long wall_contacts_before = ref.measure().wall_contacts;
  if (world_rank() == 0) write_checkpoint(serial_file, ref, "");
  ref.run(second);
  const Measurements mref = ref.measure();
  // The decomposed first half and its checkpoint, written by every rank.
  {
    Simulation sim = make();
    decompose(sim);
    sim.run(first);
    write_checkpoint(ranks_file, sim, "");
  }
  MPI_Barrier(MPI_COMM_WORLD);
  const std::string files = world_rank() == 0 ? file_differences(serial_file, ranks_file) : "";
  EXPECT_TRUE(all_ranks(files.empty())) << name << ": the checkpoints differ: " << files;
  for (const std::string& file : {ranks_file, serial_file}) {
    SCOPED_TRACE(std::string(name) + ", restart on " + std::to_string(world_size()) + " ranks from " + file);
    const auto sim = restored(make, file, true);
    sim->run(second);
    const Measurements m = sim->measure();
    const std::string diff = state_differences(ref, *sim, mref, m, tracked, events_before);
    EXPECT_TRUE(all_ranks(diff.empty())) << diff;
  }
  {
    SCOPED_TRACE(std::string(name) + ", the serial engine from the decomposed checkpoint");
    const auto sim = restored(make, ranks_file, false);
    sim->run(second);
    const std::string diff = state_differences(ref, *sim, mref, sim->measure(), tracked, events_before);
    EXPECT_TRUE(all_ranks(diff.empty())) << diff;
  }
  if (world_rank() == 0) {
    std::printf("%s on %d ranks: checkpoint at step %d of %d; %zu bonds, %zu broken before it and %zu in all; "
                "%ld wall contacts at the checkpoint, %ld at the end\n", name, world_size(), first, first + second,
                ref.bonds().size(), events_before, ref.bond_events().size(), wall_contacts_before, mref.wall_contacts);
    fs::remove_all(dir);
  }
}

TEST(DemCheckpointState, BondedLatticeBreakingRestartsAsIfNeverStopped) {
  restart_matches_serial([] { return mpi_test::bonded_lattice(); }, 700, 500, false, "bonded lattice");
}

TEST(DemCheckpointState, WallsAndEnergyBudgetRestartAsIfNeverStopped) {
  restart_matches_serial([] { return mpi_test::falling_column(true, 0.05); }, 1200, 1200, true, "falling column");
}

}  // namespace

