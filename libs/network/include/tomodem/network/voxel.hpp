#pragma once
// Image cross-check: the effective conductivity of a voxel image of the same structure.
// The conducting particles, and a cylinder of radius a_b for each intact bond between two of them
// (the neck the network gives the bond), are rasterised with partial volumes: a voxel wholly
// inside takes its material's conductivity, a voxel cut by a surface the mean over s³ samples.
// Centre sampling (one sample) made the imaged necks jump with the grid (a neck narrower than a
// voxel is lost or bridged depending on where the voxel centres fall), so the sequence of grids
// had no observed order. The image is solved by the segmented-image transport solver
// (image_transport.hpp: two-point flux finite volumes, harmonic face means, half a voxel to each
// Dirichlet face, flood-fill pruning, AMG-CG). One scheme serves --image and --voxel-check.
#include <cstdint>
#include <string>
#include <vector>

#include "tomodem/core/packing.hpp"
#include "tomodem/network/solver.hpp"

namespace tomodem::network {

struct VoxelOptions {
  int axis = 0;
  int resolution = 32;              ///< voxels along the longest cell edge (the voxel is cubic)
  bool per_diameter = false;        ///< resolution counts voxels per mean diameter of the conducting particles
  bool bonds = true;                ///< rasterise intact bonds as cylinders of radius a_b
  int subsamples = 4;               ///< samples per axis in a voxel cut by a surface
  double diameter = 0;              ///< m, the diameter of per_diameter; 0: the conducting mean diameter of the packing
  std::vector<std::string> phases;  ///< conducting phases; empty = all
  SolverOptions solver;
  std::string source;               ///< file name for error messages
  std::vector<double> neck_radii;   ///< m, a of the network's edges (optional: neck diagnostics)
  std::vector<double> neck_reduced_radii;  ///< m, R* = R_i R_j/(R_i + R_j) of the same edges
};

/// Neck resolution q = a²/(R* h): beside a neck of radius a the two surfaces part as
/// (ρ² − a²)/(2R*), so the gap is thinner than a voxel out to ρ² ≈ a² + 2R*h and the image
/// widens the neck by a relative O(R*h/a²). The grid resolves the necks when the median q is
/// at least kNeckResolution (docs/conduct.md#voxel-cross-check, bonded lattices: error ≤ 2 % at
/// q = 4, 8 % at q = 2, 33 % at q = 1).
constexpr double kNeckResolution = 4.0;

struct VoxelResult {
  int nx = 0, ny = 0, nz = 0;
  double voxel_size = 0;            ///< m
  int resolution_per_longest_edge = 0;  ///< voxels along the longest edge
  double solid_fraction = 0;        ///< conducting volume fraction of the image (partial volumes counted)
  bool percolates = false;
  double sigma_eff = 0;             ///< S/m
  double conservation_error = 0;
  SolverReport solver;
  double wall_time_s = 0;
  double voxels_per_diameter = 0;   ///< mean diameter of the conducting particles / voxel size
  double neck_min_voxels = 0, neck_median_voxels = 0;  ///< neck radius / voxel size (neck_radii given)
  double neck_resolution_min = 0, neck_resolution_median = 0;  ///< q = a²/(R* h) (with neck_reduced_radii)
  bool necks_resolved = true;       ///< neck_resolution_median >= kNeckResolution (true without neck data)
  long required_resolution_min = 0;     ///< resolution (in the options' unit) for q = kNeckResolution at the smallest q
  long required_resolution_median = 0;  ///< ... at the median q
};

/// Refuses (InputError naming --voxel-check and the resolution) a grid that cannot be built: a cell
/// that is not rectangular, fewer than 2 voxels, more voxels than the solver's 32-bit node
/// indices hold, or more memory than the machine has (need vs have). Called before any work.
void check_voxel_grid(const Packing& packing, const VoxelOptions& options);

/// Needs a rectangular (diagonal h) cell. Periodic directions other than `axis` wrap.
VoxelResult voxel_conductivity(const Packing& packing, const VoxelOptions& options);

/// Mean diameter of the particles of the conducting phases (all phases when `phases` is empty; all
/// particles when none conducts), m: the unit of --voxel-check 16d.
double conducting_mean_diameter(const Packing& packing, const std::vector<std::string>& phases);

/// The part of a packing in the box [lower, lower + edge) (m, absolute): the particles whose
/// centres lie in it (the periodic image in the box where the cell is periodic), with the bonds and
/// contacts between them; the cell is the box, not periodic. The voxel image clips the spheres at
/// the box faces; the network of the box takes the particles touching the faces normal to the axis
/// as electrodes, as for a whole cell. Every neck between two kept particles lies in the box (it
/// is centred on the segment between their centres), so network and image hold the same necks.
/// Needs a rectangular cell; along a periodic direction the box is at most half the cell edge (the
/// pairs in it are then minimum images), along another it lies inside the cell. InputError naming
/// `option` and the box otherwise.
Packing packing_box(const Packing& packing, const Vec3& lower, const Vec3& edge, const std::string& option);

/// Richardson extrapolation of three results on grids refined by the same factor:
/// returns the extrapolated value, the observed order in *order and the error estimate of the
/// finest result (|finest − extrapolated|) in *error. Falls back to the finest when not monotone.
double richardson(double coarse, double medium, double fine, double ratio, double* order, double* error);

}  // namespace tomodem::network
