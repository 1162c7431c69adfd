#pragma once
// Reading and writing the shared data model (docs/data-model.md).
#include <array>
#include <string>
#include <vector>

#include "tomodem/core/packing.hpp"

namespace tomodem::h5 { class File; }

namespace tomodem {

/// Writes `p` to `path` atomically (a temporary name renamed at the end) and an XDMF sidecar
/// `path` with extension .xdmf so ParaView opens the particles (radius, phase, velocity).
void write_packing(const std::string& path, const Packing& p);

/// Reads a packing; a missing mandatory dataset or an inconsistent length is an InputError
/// naming the file and the dataset. Radii must be finite and positive.
Packing read_packing(const std::string& path);

/// Lower-level pieces, reused by checkpoints that add their own groups to the same file.
void write_packing_groups(h5::File& f, const Packing& p);
Packing read_packing_groups(const h5::File& f);

/// For HDF5 writers, inside their catch block: removes the temporary `tmp` of `path` and
/// rethrows the current exception; a RuntimeFailure names `path` (what the user asked for)
/// wherever it named the temporary.
[[noreturn]] void discard_and_rethrow(const std::string& path, const std::string& tmp);

/// Writes the XDMF sidecar that indexes the particle datasets of an HDF5 file.
/// Also a `bonds` grid when the file holds /bonds/connectivity: one line per bond (radius,
/// rest_length, state, broken_at per line).
void write_xdmf_sidecar(const std::string& h5_path, std::size_t n_particles, bool has_velocity,
                        std::size_t n_bonds = 0);

/// Root attributes every tomodem HDF5 output carries (docs/data-model.md, "Units and provenance"):
/// `units` = "m" (the length unit of every position, spacing and origin in the file), `tool`,
/// `version`, `command_line`, `created_utc` (ISO 8601 UTC), and under /provenance/inputs the
/// content hash of each input that is a file. Attributes the writer set already are kept.
void write_provenance(h5::File& f, const std::vector<std::string>& inputs = {});
/// Metres per length unit: "m" 1, "mm" 1e-3, "um"/"µm" 1e-6, "nm" 1e-9; 0 for anything else.
double metres_per_unit(const std::string& unit);
/// Metres per length unit of an HDF5 file, from its root attribute `units`. A file without one
/// was written before tomodem stored it, when every HDF5 length was in metres: 1, with a warning
/// naming the file when `warn_missing`. An unknown unit is an InputError.
double h5_length_unit(const h5::File& f, bool warn_missing);

/// One (z, y, x) dataset of an HDF5 volume, for write_volume_xdmf.
struct XdmfField {
  std::string name, dataset;
  std::string number_type = "Float";  ///< XDMF NumberType: Float, Int, UInt, UChar, Char
  int precision = 8;                  ///< bytes per value
};
/// XDMF 2 sidecar (xdmf_sidecar_of(h5_path)) for volumes of an HDF5 file: cell-centred values on
/// a 3DCoRectMesh whose cells are the voxels (origin = centre of voxel (0,0,0), in m; dims x y z).
void write_volume_xdmf(const std::string& h5_path, const std::array<std::size_t, 3>& dims,
                       const std::array<double, 3>& origin, const std::array<double, 3>& spacing,
                       const std::vector<XdmfField>& fields);

}  // namespace tomodem
