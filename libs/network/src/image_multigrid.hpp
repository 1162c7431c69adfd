#pragma once
// Matrix-free solve of the voxel finite-volume system of image_transport.cpp: the 7-point operator
// is applied from the label volume and a per-voxel unknown map (no assembled fine matrix), and
// preconditioned by an aggregation multigrid whose coarse spaces follow the voxel grid: aggregates
// are the connected pieces of the solved voxels inside 2×2×2 blocks (a block cut by a wall gives two
// aggregates, so no coarse function spans a wall), coarse operators are Galerkin products PᵀAP with
// the piecewise-constant P (conductance sums: again weighted graph Laplacians), applied as compressed
// rows with 32-bit indices; when the blocks stop coarsening, the smoothed-aggregation multigrid of
// tomodem/linalg/amg.hpp takes the rest. Memory: ~60 bytes per unknown plus 5 per voxel, against
// ~400 for the assembled matrix with smoothed aggregation on it (docs/conduct.md, Performance).
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace tomodem::network::detail {

/// The fine level: the voxel grid, its conductivities and the numbering of the solved voxels.
struct VoxelSystem {
  long n[3] = {0, 0, 0};
  int axis = 0;
  bool periodic = false;          ///< wrap the faces parallel to the axis
  double g[3] = {0, 0, 0};        ///< A/h per unit conductivity across a face normal to x, y, z
  double g_boundary = 0;          ///< 2 A/h per unit conductivity: a Dirichlet face half a voxel away
  const uint8_t* label = nullptr; ///< per voxel
  const double* sigma = nullptr;  ///< per label (256)
  const int32_t* index = nullptr; ///< per voxel: its unknown, −1 when not solved for
  int32_t unknowns = 0;
};

struct MatrixFreeReport {
  int iterations = 0;
  double residual = 0;  ///< recomputed |b − A x| / |b|
  bool converged = false;
  int levels = 0;       ///< geometric levels (the fine one included) + those of the AMG below
  double operator_complexity = 0;
  std::size_t nonzeros = 0;  ///< of the fine operator (as if assembled)
  double setup_s = 0, solve_s = 0;
  std::size_t hierarchy_bytes = 0;  ///< coarse levels (matrices, maps, vectors)
};

struct MatrixFreeOptions {
  double tolerance = 1e-10;
  int max_iterations = 10000;
  int cycle = 2;  ///< coarse corrections per level: 1 V-cycle, 2 W-cycle
  int sweeps = 1; ///< Jacobi sweeps before and after each coarse correction
  double omega = 0.8;  ///< Jacobi damping
};

/// Solves A x = b (potential 1 on the low face of the axis, 0 on the high face); `x` holds the
/// initial guess (one value per unknown) and receives the solution.
MatrixFreeReport solve_matrix_free(const VoxelSystem& s, std::vector<double>& x, const MatrixFreeOptions& o);

}  // namespace tomodem::network::detail
