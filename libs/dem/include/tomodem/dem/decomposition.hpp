#pragma once
// Spatial domain decomposition of a Simulation over MPI ranks (docs/dem.md, "Running on several
// ranks"). Only in the MPI build (-DTOMODEM_MPI=ON); this header includes no MPI header.
//
// The cell is cut into a regular grid of sub-domains in fractional coordinates (a sheared cell
// is cut along its own lattice planes). A rank owns the particles whose centre lies in its box
// and holds copies ("ghosts") of the other ranks' particles within the interaction reach plus
// the neighbour-list skin of its box. Periodic images are not copied: a ghost is an exact copy
// of its owner's particle and the rank's neighbour list finds its images through the same image
// codes as the serial engine. Pairs between an owned particle and a ghost are computed on both
// ranks ("newton off"); each particle sums its contacts in the serial order (rows by particle id,
// each row by partner and image), so with one thread per rank every rank count gives the serial
// trajectory bit for bit.
#include <array>
#include <cstdint>
#include <cstring>
#include <type_traits>
#include <vector>

#include "tomodem/core/packing.hpp"
#include "tomodem/core/vec3.hpp"
#include "tomodem/dem/bonds.hpp"
#include "tomodem/dem/particles.hpp"

namespace tomodem::dem {

class Simulation;
struct SimState;
class NeighbourList;
struct Tally;
struct Measurements;
struct EnergyAccount;
struct ForceJob;

/// One term of an ordered sum over the ranks (DomainHooks::ordered_sum).
struct OrderedTerm {
  int32_t group = 0;  ///< which sum (a wall)
  int64_t id = 0;     ///< the particle: terms are added in id order, the serial engine's
  Vec3 v;
};

/// What the engine asks of a decomposition at its few synchronisation points. Implemented in
/// libs/dem/src/mpi/; the serial engine never sees it.
class DomainHooks {
 public:
  virtual ~DomainHooks() = default;
  /// Per local particle: 1 for a ghost (a copy of another rank's particle), 0 for an owned one.
  std::vector<uint8_t> ghost;
  /// Per bond of the rank's bond set: its index in the whole sample's set (events carry it).
  std::vector<int32_t> bond_id;
  /// Refreshes the ghosts' positions, velocities and spins from their owners (every force pass).
  virtual void forward(SimState& s) = 0;
  /// Refreshes the ghosts' radii, masses and inverse inertia from their owners, for a driver that
  /// changes them between steps (sintering: radius growth, mass scaling). Collective.
  virtual void refresh_ghost_bodies(Particles& p) = 0;
  /// True on every rank when it is true on any.
  virtual bool any(bool local) = 0;
  /// Migration and a new ghost layer, with the contact history carried by particle id.
  virtual void before_build(SimState& s, NeighbourList& nl) = 0;
  virtual void after_build(SimState& s, NeighbourList& nl) = 0;
  /// Sums (in rank order, the same on every rank) of the tally of owned rows.
  virtual void reduce(Tally& t) = 0;
  /// Sums of v[0..n) over the ranks, in rank order: the same doubles on every rank.
  virtual void sum(double* v, int n) = 0;
  virtual double min(double v) = 0;
  /// The wall pass when decomposed (the engine's ForceLoop::wall_forces otherwise): the wall
  /// contacts of the owned particles, and on tally passes each wall's force, summed over every
  /// rank in the serial order of its contacts, so that every rank holds the same bits and moves
  /// the walls alike.
  virtual void walls(SimState& s, NeighbourList& nl, const ForceJob& jb, bool tally, Tally& total, double* stiffness) = 0;
  /// Per group g < groups, Σ v of every rank's terms of that group, added in ascending id order
  /// from zero: the bits of the serial loop over the particles. Collective.
  virtual std::vector<Vec3> ordered_sum(const std::vector<OrderedTerm>& terms, int groups) = 0;
  /// Every rank's bytes, concatenated in rank order, on every rank (FIRE's sums). Collective.
  virtual std::vector<char> all_bytes(const std::vector<char>& mine) = 0;
  /// all_bytes for records of a trivially copyable type: every rank's, in rank order. Collective.
  template <class T>
  std::vector<T> all_records(const std::vector<T>& mine) {
    static_assert(std::is_trivially_copyable_v<T>, "records travel as their bytes");
    std::vector<char> bytes(mine.size() * sizeof(T));
    if (!bytes.empty()) std::memcpy(bytes.data(), mine.data(), bytes.size());
    const std::vector<char> all = all_bytes(bytes);
    std::vector<T> out(all.size() / sizeof(T));
    if (!out.empty()) std::memcpy(out.data(), all.data(), out.size() * sizeof(T));
    return out;
  }
  /// The measurement of the whole cell from the rank's tally (already reduced) and owned particles.
  virtual Measurements measure(const SimState& s, const Tally& tally, const EnergyAccount& energy) = 0;
};

struct DecompositionOptions {
  /// Sub-domains along each cell vector; 0 entries are chosen by MPI_Dims_create.
  std::array<int, 3> dims{0, 0, 0};
};

/// Where this rank stands (for reports and tests).
struct DomainLayout {
  int rank = 0, ranks = 1;
  std::array<int, 3> dims{1, 1, 1}, coords{0, 0, 0};
  long owned = 0, ghosts = 0;
  long migrated = 0;        ///< particles this rank sent to another since the start
  long exchanges = 0;       ///< ghost layers built (one per neighbour-list build)
};

/// Splits `sim`, built identically on every rank of MPI_COMM_WORLD (same particles, cell, model
/// and settings), into sub-domains: each rank keeps its own particles and gets its ghost layer.
/// Collective. Throws InputError (the same on every rank) when a sub-domain would be thinner
/// than the interaction reach plus skin (too many ranks along a cell vector for this sample).
///
/// Walls: each rank computes the wall contacts of the particles it owns; a wall's force is the
/// sum of its contacts' forces over every rank in the serial order (ordered_sum), so the servo
/// of a force-controlled wall moves it by the same bits on every rank. A particle's wall history
/// travels with it when it migrates.
///
/// Bonds: a rank holds every bond with an owned end whose other end it holds too (owned or
/// ghost), in the order of the whole set; a bond between an owned particle and a ghost is
/// computed on both ranks from the same bits, so both find the same forces, the same history
/// and the same failure in the same step, with no message. Its tally and its failure event count
/// where its first particle (the lower index) is owned. The bond state travels with migrating
/// particles. An intact bond stretched beyond the ghost reach is a NumericalError on every rank.
void decompose(Simulation& sim, const DecompositionOptions& opt = {});

/// This rank's place in the decomposition (ranks = 1, owned = all, for a serial simulation).
DomainLayout layout(const Simulation& sim);

/// The owned particles of every rank, sorted by id, on rank 0 (empty elsewhere). Collective.
/// Rotational columns are included when the scene has them; forces are not gathered.
Particles gather_particles(const Simulation& sim);

/// The contact table of the whole cell on rank 0 (empty elsewhere), in the serial order (rows by
/// particle id, each row by partner and image), indices into gather_particles' order. Collective
/// (a tally pass, as Simulation::contacts; the trajectory is unchanged).
ContactTable gather_contacts(Simulation& sim);

/// The whole sample's bond set on rank 0 (empty elsewhere), bonds in their original order, i and
/// j indices into gather_particles' order. A broken bond whose particles drifted out of each
/// other's reach keeps the image it had when they were last within reach. Collective.
BondSet gather_bonds(const Simulation& sim);

/// The bond events of the whole run on rank 0 (empty elsewhere), each once, in the serial order
/// (by time, then bond). Collective.
std::vector<BondEvent> gather_bond_events(const Simulation& sim);

/// Simulation::contacts and dem::to_packing of the whole cell, on rank 0 (other ranks get an
/// empty packing). Collective.
Packing gather_packing(Simulation& sim, const std::vector<Material>& materials);

}  // namespace tomodem::dem
