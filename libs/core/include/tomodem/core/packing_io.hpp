#pragma once
// Reading and writing the shared data model (docs/data-model.md).
#include <string>

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
void write_xdmf_sidecar(const std::string& h5_path, std::size_t n_particles, bool has_velocity);

}  // namespace tomodem
