#pragma once
// One force pass: the compiled pair and bond loops over the thread split, the fixed-order
// reduction, the walls and the body forces; with tallies on measurement and check steps.
#include <vector>

#include "neighbour_list.hpp"
#include "pair_bands.hpp"
#include "sim_state.hpp"

namespace tomodem::dem {

class ForceLoop {
 public:
  Tally last;                     // tally of the last tally pass
  std::vector<double> stiffness;  // per-particle Σ S_c of the last tally pass
  long pair_tests = 0;            // distance tests of listed pairs, all passes

  /// Forces and torques at the current state over a current list. With `tally`, also the
  /// virial, energies and per-particle stiffness (into `last`, `stiffness`).
  void compute(SimState& s, NeighbourList& nl, bool tally, Vec3* pair_force = nullptr);
  /// The neighbour list is about to be rebuilt: what was derived from it is freed.
  void list_changes() { bands.release(); }

 private:
  std::vector<Vec3> u;  // absolute velocities when the cell deforms
  std::vector<PackedSphere> sphere;  // x and r packed for the four-wide loops (ForceJob::sphere)
  PackedSphere shift4[27] = {};
  std::vector<std::vector<Vec3>> fbuf, tbuf;
  std::vector<std::vector<double>> sbuf;
  std::vector<std::vector<BondEvent>> event_buf;
  PairBands bands;

  ForceJob job(const SimState& s, NeighbourList& nl);
  void prepare_buffers(int threads, std::size_t n, bool rot, bool tally);
  void wall_forces(SimState& s, NeighbourList& nl, const ForceJob& jb, bool tally, Tally& total);
  void body_forces(SimState& s, Tally* tally) const;
};

}  // namespace tomodem::dem
