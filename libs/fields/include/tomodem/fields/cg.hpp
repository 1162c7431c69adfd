#pragma once
// Coarse-graining of particles, contacts and bonds onto a grid (Goldhirsch 2010; Weinhart,
// Thornton, Luding & Goldhirsch 2012). Formulas: docs/physics.md#coarse-graining; the tool:
// docs/cg.md. Tension-positive stress, the convention of the Love-Weber stress of tomodem-dem.
#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "tomodem/core/packing.hpp"
#include "tomodem/fields/kernel.hpp"

namespace tomodem::fields {

/// Where the fields are evaluated. Nodes sit at fractions of the cell vectors, so a triclinic
/// cell gets a sheared grid. `full`: n[0]·n[1]·n[2] nodes at cell centres ((I + ½)/n); `slice`:
/// the plane at `fraction` of cell vector `axis` (n[axis] is 1); `profile`: n[axis] nodes along
/// cell vector `axis`, each the field averaged over the plane spanned by the other two vectors.
struct GridSpec {
  enum class Kind { full, slice, profile };
  Kind kind = Kind::full;
  std::array<int, 3> n{0, 0, 0};
  int axis = 2;
  double fraction = 0.5;
};

/// A pair that carries force: contact or bond. `force` acts on j from i; `branch` runs from the
/// centre of i to the centre of j's image (x_j + H·n − x_i).
struct PairForce {
  int32_t i = 0, j = 0;
  Vec3 branch, force;
};

/// One snapshot as the coarse-graining sees it (SI units).
struct Snapshot {
  Cell cell;
  std::vector<Vec3> x, v;        ///< v may be empty (a static packing)
  std::vector<double> m;         ///< kg
  std::vector<PairForce> contacts, bonds;
  std::vector<Vec3> u;           ///< displacement from the reference (empty: none)
  Mat3 h_reference;              ///< cell of the reference (displacement of periodic images)
};

/// Raw sums of one or more snapshots on the grid; fields are derived from them at the end.
class Accumulator {
 public:
  /// Kernel, grid, quadrature points per branch (0: automatic, see docs/cg.md) and threads.
  Accumulator(const Kernel& kernel, const GridSpec& grid, const Cell& cell, int quadrature, int threads);
  ~Accumulator();
  Accumulator(Accumulator&&) noexcept;
  Accumulator& operator=(Accumulator&&) noexcept;
  /// Adds one snapshot (same cell shape as the first: time averages need one grid).
  void add(const Snapshot& s);
  std::size_t points() const;
  int snapshots() const;
  int max_quadrature() const;  ///< the most points used on one branch

  struct Fields;
  /// The time-averaged fields (see Fields).
  Fields fields() const;

 private:
  struct Impl;
  Impl* impl_;
};

/// Fields per node, averaged over the snapshots; tensors as 9 values (row-major, σ_ab: a the
/// force component, b the branch component). Velocity, displacement and the kinetic stress are 0
/// where the density is 0 (no particle within the kernel's reach).
struct Accumulator::Fields {
  std::vector<Vec3> points;              ///< node positions, m (profile: the plane through the node at the cell's origin)
  std::vector<double> coordinate;        ///< profile: distance along the plane normal, m
  std::array<int, 3> dims{0, 0, 0};      ///< nodes per cell vector (slice: 1 along the normal)
  std::vector<double> density;           ///< kg/m^3
  std::vector<Vec3> momentum, velocity;  ///< kg/(m^2 s), m/s
  std::vector<double> stress_kinetic, stress_contact, stress_bond, stress;  ///< Pa, 9 per node
  std::vector<Vec3> divergence;          ///< ∇·(σ_contact + σ_bond), N/m^3 (kernel gradients, no finite differences)
  std::vector<Vec3> displacement;        ///< m (with a reference)
  std::vector<double> strain;            ///< small strain sym(∇U), 9 per node (full grids with a reference)
  std::vector<uint8_t> interior;         ///< 1 where the support stays a cut-off away from non-periodic faces
  double node_volume = 0;                ///< m^3 per node (full grids and profiles), 0 for slices
};

/// Mean diameter 2·mean(R), m.
double mean_diameter(const Packing& p);

/// Gauss-Legendre nodes on [0, 1] and weights (summing to 1), n = 1 … 16.
void gauss_legendre(int n, std::vector<double>& s, std::vector<double>& w);

}  // namespace tomodem::fields
