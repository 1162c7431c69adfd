#pragma once
// Outputs of tomodem-segment (all atomic: temporary name, then rename). Plain types only.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "tomodem/core/vec3.hpp"
#include "tomodem/image/volume.hpp"

namespace tomodem::image {

/// PNG bytes (8-bit RGB, zlib) of an 8-bit BGR picture whose rows are row_bytes apart.
std::string png_from_bgr(const uint8_t* bgr, int width, int height, std::size_t row_bytes);

/// Phase labels as written: 0 solid, 1 fine pore, 2 macropore, 3 second solid phase (multi-Otsu 3).
inline constexpr const char* kLegend = "0:solid,1:fine_pore,2:macropore,3:solid_phase_2";

/// HDF5: /labels (z,y,x uint8), /macropores (int32 ids, 0 = none), /grains (int32, when given);
/// each with attributes spacing and origin (m, x y z) and /labels@legend; root attributes units
/// ("m") and provenance (hashes of `inputs`). An XDMF sidecar (xdmf_sidecar_of(path)) beside it.
void write_labels_h5(const std::string& path, const Mask& phases, const Labels& macropores, const Labels* grains,
                     const std::vector<std::string>& inputs = {});

/// The set m != 0 as an OpenVDB narrow-band signed-distance level set (FloatGrid "macropores",
/// negative inside) in MILLIMETRES (world and values; metadata units = "mm", metres_per_unit):
/// OpenVDB refuses transforms whose determinant is below 3e-15, i.e. voxels under 14 um in m; from the 0.5 iso-surface of the mask smoothed by a Gaussian of
/// sigma 1 voxel (sub-voxel surface instead of the voxel staircase), rebuilt by OpenVDB.
void write_level_set(const std::string& path, const Mask& m, double half_width_vox = 3.0);
/// Trilinear samples of the level set at world points given in m, returned in m.
/// Refuses (InputError naming the file and the grid) an OpenVDB file that is cut short, empty, a
/// folder or not OpenVDB, by walking its table of contents before OpenVDB reads it: OpenVDB reads
/// past the end of a cut file without noticing (garbage counts, unbounded allocation).
void check_vdb_file(const std::string& path);
std::vector<double> sample_level_set(const std::string& path, const std::vector<Vec3>& world_points);

/// What an overlay needs of the grey volume: the grey window and the three mid-planes (xy at
/// z = nz/2, xz at y = ny/2, yz at x = nx/2; first index fastest). Taken before the grey volume is
/// released, so the later stages do not hold 4 bytes per voxel for three PNGs.
struct OverlayPlanes {
  Dims dims;
  double lo = 0, hi = 1;
  std::vector<float> xy, xz, yz;
};
OverlayPlanes overlay_planes(const Volume& grey);
/// A scale bar for a picture of `width_px` pixels of `metres_per_pixel` each: the longest of 1, 2
/// or 5 x 10^k m that fits in a quarter of the width, its length in pixels and its label
/// ("200 um", "1 mm"; ASCII "um" because the overlay font has no micro sign).
struct ScaleBar {
  double length_m = 0;
  int pixels = 0;
  std::string label;
};
ScaleBar scale_bar(double metres_per_pixel, int width_px);

/// Mid-plane overlays <prefix>_xy.png, _xz.png, _yz.png (OpenCV): grey between the 0.5 and 99.5
/// percentiles; fine pores blue, macropores red, a second solid phase green. Below the picture a
/// white strip with a scale bar (scale_bar) and a legend of the phases the volume has (grey is
/// the scan). Returns the paths.
std::vector<std::string> write_overlays(const std::string& prefix, const OverlayPlanes& grey, const Mask& phases);

}  // namespace tomodem::image
