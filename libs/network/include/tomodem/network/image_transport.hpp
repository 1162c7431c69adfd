#pragma once
// Transport in a segmented image (docs/conduct.md#transport-in-a-segmented-image): the effective
// conductivity of a label volume along an axis by a two-point flux finite-volume scheme on the
// voxels, the PuMA / TauFactor convention. Potentials 1 and 0 on the two faces normal to the axis
// (a boundary voxel meets its face through half a voxel, conductance 2σA/h), no-flux or periodic
// side faces, the harmonic mean 2σ₁σ₂/(σ₁+σ₂) of the two voxel conductivities on an inner face.
// Only the voxels connected (6-neighbourhood, the faces the scheme couples) to both Dirichlet faces
// are solved for; the linear system is solved by conjugate gradients, the operator applied from the
// labels (matrix-free), preconditioned with a multigrid whose coarse levels aggregate the voxels in
// 2×2×2 blocks (Galerkin products), the smoothed-aggregation multigrid of tomodem/linalg/amg.hpp
// below them.
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace tomodem::network {

/// A label volume: v[(z * ny + y) * nx + x] (the HDF5 dataset's z, y, x order).
struct LabelImage {
  std::size_t nx = 0, ny = 0, nz = 0;
  std::array<double, 3> spacing{1, 1, 1};  ///< m, x y z
  std::array<double, 3> origin{0, 0, 0};   ///< m, x y z
  std::vector<uint8_t> v;
  std::size_t size() const { return nx * ny * nz; }
};

/// Shape (nx, ny, nz) of the 3-D dataset `dataset` of `path` without reading it (InputError naming
/// the file and dataset when missing or not 3-D).
std::array<std::size_t, 3> label_image_shape(const std::string& path, const std::string& dataset = "/labels");
/// Reads a label volume written by tomodem-segment: `dataset` (z, y, x, uint8) with the attribute
/// "spacing" (x y z, m; finite and > 0, else InputError naming it). No attribute: 1 m voxels.
LabelImage read_label_image(const std::string& path, const std::string& dataset = "/labels");

/// Bytes per voxel the solve needs at most (every voxel an unknown), with or without fields.
double image_transport_bytes_per_voxel(bool fields);

struct ImageTransportOptions {
  std::array<double, 256> conductivity{};  ///< per label; 0: does not conduct
  int axis = 0;
  bool periodic_sides = false;   ///< wrap the faces parallel to the axis instead of no-flux
  double tolerance = 1e-10;      ///< relative residual of the CG solve
  int max_iterations = 0;        ///< 0: automatic
  bool fields = false;           ///< keep the potential and the current magnitude per voxel
  /// false (default): the fine operator is applied from the labels (matrix-free) and preconditioned by
  /// the voxel-aggregation multigrid (src/image_multigrid.hpp). true: the reference path, the matrix
  /// assembled in compressed rows with the smoothed-aggregation multigrid of amg.hpp on it (~7x the
  /// memory; the tests compare the two).
  bool assembled = false;
};

struct ImageAxisResult {
  int axis = 0;
  bool percolates = false;
  double sigma_eff = 0;          ///< in the units of the conductivity table (relative when σ0 = 1)
  double sigma0 = 1;             ///< the largest conductivity of the table
  double porosity = 0;           ///< volume fraction of conducting voxels
  double tortuosity = 0;         ///< ε σ0 / σ_eff; +inf without a spanning path
  double sigma_eff_error = 0;    ///< max(flux imbalance, relative residual)
  double current_in = 0, current_out = 0;  ///< A per V (σ in S/m, lengths in m)
  double flux_imbalance = 0;     ///< |I_in − I_out| / (I_in + I_out) = |Σ residuals| / (I_in + I_out)
  double residual = 0;           ///< recomputed |b − Ax| / |b|
  int iterations = 0;
  bool converged = false;
  std::size_t unknowns = 0, nonzeros = 0;
  int levels = 0;
  double operator_complexity = 0;
  double spanning_fraction = 0;  ///< of the conducting voxels: connected to both faces
  double dead_end_fraction = 0;  ///< of the conducting voxels: in clusters touching one face only
  double isolated_fraction = 0;  ///< of the conducting voxels: in clusters touching neither face
  double setup_time_s = 0, solve_time_s = 0, wall_time_s = 0;
  std::vector<float> potential;  ///< per voxel (fields only); NaN off the spanning clusters
  std::vector<float> current;    ///< per voxel |j| (A/m² per V), 0 off the spanning clusters
};

ImageAxisResult image_conductivity(const LabelImage& image, const ImageTransportOptions& options);

/// Writes the fields of every axis (/<axis>/potential, /<axis>/current_magnitude, z y x) to `path`
/// atomically, with an XDMF sidecar (xdmf_sidecar_of(path)) for ParaView.
void write_image_fields(const std::string& path, const LabelImage& image, const std::vector<ImageAxisResult>& results,
                        const std::string& parameters);

}  // namespace tomodem::network
