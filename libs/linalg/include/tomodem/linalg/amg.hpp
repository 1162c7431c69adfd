#pragma once
// Smoothed-aggregation algebraic multigrid (Vaněk, Mandel & Brezina 1996) as the preconditioner of
// conjugate gradients for sparse symmetric positive definite systems: graph Laplacians (resistor
// networks, libs/network) and bonded-particle stiffness matrices (translations and rotations per
// particle, libs/mechanics). Eigen stays inside amg.cpp; this header carries plain arrays.
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "tomodem/core/vec3.hpp"

namespace tomodem {

/// A square sparse matrix in compressed rows with full symmetric storage and 32-bit indices: the
/// arrays of a compressed Eigen::SparseMatrix<double, Eigen::RowMajor, int> (outerIndexPtr,
/// innerIndexPtr, valuePtr). A view: the caller keeps the arrays alive while they are used.
struct CsrView {
  int32_t rows = 0;
  const int32_t* start = nullptr;   ///< rows + 1 offsets
  const int32_t* column = nullptr;
  const double* value = nullptr;
};

/// The unknowns' meaning, from which the coarse spaces are built so that they reproduce the
/// zero-energy modes of the operator without boundary conditions (the near-null space).
struct NearNullspace {
  enum Kind : int8_t { scalar = -1, ux = 0, uy, uz, rx, ry, rz };
  /// Per unknown, its node; the unknowns of one node must be consecutive. Empty: one node per
  /// unknown, all scalar (a graph Laplacian: the constant vector).
  std::vector<int32_t> node;
  /// Per unknown: scalar, or a translation (ux..uz) or rotation (rx..rz, stored as
  /// rotation_scale × angle) of its node: the six rigid-body modes then form the near-null space.
  std::vector<int8_t> kind;
  std::vector<Vec3> position;       ///< per node (m): the lever arms of the rotation modes
  double rotation_scale = 1;        ///< m: rotations are unknowns φ = rotation_scale · θ
  Mat3 cell = Mat3::identity();     ///< columns: lattice vectors of the periodic cell
  bool periodic[3] = {false, false, false};  ///< lever arms by the minimum image along these
};

struct AmgOptions {
  double strength = 0.08;     ///< θ: nodes i, j are coupled when |A_ij| ≥ θ sqrt(|A_ii| |A_jj|) (Frobenius norms of node blocks; halved per level)
  int aggregate_radius = 1;   ///< an aggregate is a root and its free coupled nodes up to this many hops
  bool smooth = true;         ///< smoothed prolongator P = (I − ω D⁻¹A) P_tent; false: plain aggregation
  int sweeps = 2;             ///< damped block-Jacobi sweeps before and after the coarse correction
  int coarse_size = 500;      ///< unknowns below which a level is solved directly (dense LDLᵀ: O(n²) per cycle)
  int max_levels = 12;
};

struct AmgStats {
  std::vector<long> rows, nonzeros;  ///< per level, finest first
  double operator_complexity = 0;    ///< Σ nonzeros / nonzeros of the finest
  double setup_s = 0;
  std::size_t memory_bytes = 0;      ///< hierarchy (without the finest matrix, which is the caller's)
};

/// One V-cycle of smoothed-aggregation multigrid: a symmetric positive definite approximation of
/// A⁻¹ (the same damped block-Jacobi sweeps before and after the coarse correction).
class Amg {
 public:
  /// Builds the hierarchy. Keeps the view of A (finest level): A must outlive this object.
  Amg(const CsrView& A, const NearNullspace& ns, const AmgOptions& options = {});
  ~Amg();
  Amg(Amg&&) noexcept;
  Amg& operator=(Amg&&) noexcept;
  /// z = M⁻¹ r (one V-cycle from z = 0). Thread-safe for one caller at a time.
  void apply(const double* r, double* z) const;
  /// Swaps the finest matrix for another of the same size and pattern family (e.g. after a few bond
  /// stiffnesses changed) and keeps the coarse levels: still a good preconditioner while the change
  /// is local. The block-Jacobi smoother is recomputed.
  void replace_finest(const CsrView& A);
  const AmgStats& stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct PcgReport {
  int iterations = 0;
  double residual = 0;   ///< recomputed |b − A x| / |b| at the end
  bool converged = false;
  double seconds = 0;
};

/// Preconditioned conjugate gradients until |b − A x| / |b| ≤ tolerance (the recursive residual;
/// the report recomputes it). `x` holds the initial guess. `M` null: Jacobi (diagonal) scaling.
/// OpenMP parallel loops above 50 000 unknowns.
PcgReport pcg(const CsrView& A, const Amg* M, const double* b, double* x, double tolerance, int max_iterations);

}  // namespace tomodem
