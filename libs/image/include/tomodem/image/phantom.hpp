#pragma once
// Synthetic volumes with ground truth (docs/segment.md, "Phantoms").
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "tomodem/core/names.hpp"
#include "tomodem/core/packing.hpp"
#include "tomodem/image/volume.hpp"

namespace tomodem::image {

/// What the phantom holds: macropores and fine pores in a solid, lamellae, one centred spherical
/// macropore, or a packing of touching spheres.
enum class PhantomKind : uint8_t { pores, lamellae, sphere, packing };
inline constexpr NameTable<PhantomKind, 4> kPhantomKindNames = {{{PhantomKind::pores, "pores"},
                                                                 {PhantomKind::lamellae, "lamellae"},
                                                                 {PhantomKind::sphere, "sphere"},
                                                                 {PhantomKind::packing, "packing"}}};
inline const char* to_string(PhantomKind k) { return name_of(kPhantomKindNames, k); }

struct PhantomOptions {
  PhantomKind kind = PhantomKind::pores;
  std::size_t n = 96;             ///< cubic size (voxels)
  double voxel = 1e-5;            ///< m
  double snr = 5;                 ///< contrast / noise sigma (0 = no noise)
  double blur = 1.0;              ///< Gaussian PSF sigma (voxels), 0 = none
  double rings = 0;               ///< ring artefact amplitude (fraction of the contrast)
  double cupping = 0;             ///< beam-hardening cupping amplitude (fraction of the contrast)
  uint64_t seed = 1;
  // pores: macropores (spheres and ellipsoids) and fine pores in a solid matrix
  int n_macropores = 6;
  /// tomodem-phantom without --macropores: up to n_macropores, as many as fit (a small --size
  /// holds fewer); with it, exactly n_macropores or InputError.
  bool macropores_auto = false;
  double macro_radius_min = 9, macro_radius_max = 14;  ///< voxels
  double fine_porosity = 0.02;    ///< target volume fraction of fine pores
  double fine_radius = 3.0;       ///< voxels
  // packing: polydisperse touching spheres
  double grain_radius_min = 7, grain_radius_max = 11;  ///< voxels
  int n_grains = 60;
  // sphere: one spherical macropore of this radius (voxels) at the centre (+ sub-voxel offset)
  double sphere_radius = 15.3;
  // intensities (before blur and noise)
  double pore_value = 10000, solid_value = 30000;
  /// Option values as the user typed them ("--voxel" -> "-1e-5"), for messages that echo them.
  std::map<std::string, std::string> as_written;
};

/// Truth labels: 0 solid, 1 fine pore, 2 macropore (pores, lamellae, sphere); for packing:
/// 0 void, k = grain k (1-based index into `packing`).
struct Phantom {
  Volume grey;
  Labels truth;
  std::vector<std::size_t> macropore_voxels;   ///< per macropore k = truth id k+1 in `macropore_ids`
  Labels macropore_ids;                        ///< 0 none, k macropore k (pores kind)
  std::vector<Vec3> macropore_centres;         ///< m
  std::vector<Vec3> macropore_semi_axes;       ///< m, along x, y, z (pores kind)
  std::vector<Vec3> fine_pore_centres;         ///< m (pores kind; radius PhantomOptions::fine_radius voxels)
  Packing packing;                             ///< packing kind: the true spheres (m)
};

/// Refuses (InputError naming the option and the value) options that are out of range, NaN or
/// infinite, and a size whose memory (phantom_bytes_per_voxel) the machine does not have.
void check_phantom_options(const PhantomOptions& o);
/// Peak memory per voxel of make_phantom and the writers (truth, ids, grey, blur, the writer's
/// copy): 19.2 B measured as peak RSS above the bare process at 128^3, plus 25 %.
inline constexpr double kPhantomBytesPerVoxel = 24;

/// Macropore radii below --size 64 shrink with the size (a 16-voxel cube holds radii 2.25 to 3.5).
Phantom make_phantom(const PhantomOptions& o);

}  // namespace tomodem::image
