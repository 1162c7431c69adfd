#pragma once
// Image cross-check: the effective conductivity of a voxel image of the same structure.
// The packing is rasterised (a voxel takes the conductivity of the first conducting particle
// that contains its centre, 0 elsewhere) and solved with a two-point flux finite-volume scheme:
// the conductance between neighbouring voxels is h · 2σ₁σ₂/(σ₁+σ₂) (harmonic mean, face area
// h², distance h), a boundary voxel meets its electrode through half a voxel (2σh). The same
// Kirchhoff solver and percolation pruning as the particle network are used.
#include <cstdint>
#include <string>
#include <vector>

#include "tomodem/core/packing.hpp"
#include "tomodem/network/solver.hpp"

namespace tomodem::network {

struct VoxelOptions {
  int axis = 0;
  int resolution = 32;              ///< voxels along the longest cell edge (the voxel is cubic)
  std::vector<std::string> phases;  ///< conducting phases; empty = all
  SolverOptions solver;
  std::string source;               ///< file name for error messages
};

struct VoxelResult {
  int nx = 0, ny = 0, nz = 0;
  double voxel_size = 0;            ///< m
  double solid_fraction = 0;        ///< fraction of voxels that conduct
  bool percolates = false;
  double sigma_eff = 0;             ///< S/m
  double conservation_error = 0;
  SolverReport solver;
  double wall_time_s = 0;
};

/// Refuses (InputError naming --voxel and the resolution) a grid that cannot be built: a cell
/// that is not rectangular, fewer than 2 voxels, more voxels than the solver's 32-bit node
/// indices hold, or more memory than the machine has (need vs have). Called before any work.
void check_voxel_grid(const Packing& packing, const VoxelOptions& options);

/// Needs a rectangular (diagonal h) cell. Periodic directions other than `axis` wrap.
VoxelResult voxel_conductivity(const Packing& packing, const VoxelOptions& options);

/// Richardson extrapolation of three results on grids refined by the same factor:
/// returns the extrapolated value, the observed order in *order and the error estimate of the
/// finest result (|finest − extrapolated|) in *error. Falls back to the finest when not monotone.
double richardson(double coarse, double medium, double fine, double ratio, double* order, double* error);

}  // namespace tomodem::network
