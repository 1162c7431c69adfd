#pragma once
// Image cross-check: the effective conductivity of a voxel image of the same structure.
// The packing is rasterised into a label image (a voxel takes the material of the first
// conducting particle that contains its centre, void elsewhere) and solved by the segmented-image
// transport solver (image_transport.hpp: two-point flux finite volumes, harmonic face means, half
// a voxel to each Dirichlet face, flood-fill pruning, AMG-CG). One scheme serves --image and --voxel-check.
// The answer converges only once the necks are resolved: a neck of radius a below ~2 voxels is
// either lost or replaced by a voxel-wide bridge (neck_min_voxels, necks_resolved).
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
  std::vector<double> neck_radii;   ///< m, of the network's edges (optional: neck diagnostics)
};

/// Voxels across the smallest neck radius below which the grid does not resolve the necks.
constexpr double kNeckVoxels = 2.0;

struct VoxelResult {
  int nx = 0, ny = 0, nz = 0;
  double voxel_size = 0;            ///< m
  double solid_fraction = 0;        ///< fraction of voxels that conduct
  bool percolates = false;
  double sigma_eff = 0;             ///< S/m
  double conservation_error = 0;
  SolverReport solver;
  double wall_time_s = 0;
  double voxels_per_diameter = 0;   ///< mean diameter of the conducting particles / voxel size
  double neck_min_voxels = 0, neck_median_voxels = 0;  ///< neck radius / voxel size (neck_radii given)
  bool necks_resolved = true;       ///< neck_min_voxels >= kNeckVoxels (true without neck_radii)
  long required_resolution_min = 0;     ///< voxels per longest edge for kNeckVoxels across the smallest neck
  long required_resolution_median = 0;  ///< ... across the median neck
};

/// Refuses (InputError naming --voxel-check and the resolution) a grid that cannot be built: a cell
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
