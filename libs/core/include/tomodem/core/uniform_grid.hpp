#pragma once
// One writer for cell data on a uniform (voxel) grid: an HDF5 file written under a temporary name
// and renamed, with provenance, plus the XDMF sidecar that ParaView opens as cell data on a
// 3DCoRectMesh. Used by tomodem-conduct --image (fields), tomodem-cg --compare-image, and any
// tool whose output is a field on a regular grid.
//
// Layout: per block, a group ("" = the root) holding one dataset per field, shape (nz, ny, nx) or
// (nz, ny, nx, components), x fastest; each dataset carries "units" (when given), "spacing"
// (x y z, m) and "origin" (x y z, m: the centre of cell (0, 0, 0), the convention of the label
// volumes tomodem-segment writes). Each block becomes one XDMF Grid named after the block.
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace tomodem {

namespace h5 {
class File;
}

/// One field on the grid: a view of the caller's values (kept alive until the write returns),
/// nx·ny·nz·components of them, x fastest, components innermost. Floats are stored as doubles;
/// bytes as uint8 (masks, labels).
struct GridField {
  GridField(std::string name, const std::vector<double>& v, std::string unit, int components = 1);
  GridField(std::string name, const std::vector<float>& v, std::string unit, int components = 1);
  GridField(std::string name, const std::vector<uint8_t>& v, std::string unit, int components = 1);
  std::string name;  ///< dataset name inside its block ("potential")
  std::string unit;  ///< the "units" attribute; empty: none
  int components;    ///< 1 scalar, 3 vector, 9 tensor (row-major 3×3)
  const std::vector<double>* f64 = nullptr;
  const std::vector<float>* f32 = nullptr;
  const std::vector<uint8_t>* u8 = nullptr;
  std::size_t size() const;
};

/// A group of fields shown as one XDMF grid: group "/x" for name "x"; name "" writes the fields at
/// the root and names the XDMF grid `xdmf_name`.
struct GridBlock {
  std::string name;
  std::vector<GridField> fields;
  std::string xdmf_name = "grid";
};

struct UniformGrid {
  std::array<std::size_t, 3> dims{0, 0, 0};  ///< cells along x, y, z
  std::array<double, 3> spacing{1, 1, 1};    ///< m, x y z (> 0)
  std::array<double, 3> corner{0, 0, 0};     ///< m: the lower corner of cell (0, 0, 0)
  std::size_t cells() const { return dims[0] * dims[1] * dims[2]; }
};

/// What the root of the file says besides the standard provenance (write_provenance: units,
/// version, command line, time, content hashes of `inputs`).
struct GridProvenance {
  std::string tool;                                              ///< root attribute "tool"
  std::vector<std::pair<std::string, std::string>> attributes;   ///< more root string attributes ("parameters")
  std::vector<std::string> inputs;                               ///< files whose hashes are recorded
  std::function<void(h5::File&)> extra;  ///< writes more datasets/attributes before the file is closed
};

/// Writes `blocks` to `path` (HDF5, atomically: temporary name, checked close, rename) and the XDMF
/// sidecar xdmf_sidecar_of(path). RuntimeFailure (naming `path`) on a write error, with neither file
/// left behind; RuntimeFailure before anything is written when a field's size does not match the
/// grid, components is not 1, 3 or 9, or the grid is empty.
void write_uniform_grid(const std::string& path, const UniformGrid& grid, const std::vector<GridBlock>& blocks,
                        const GridProvenance& provenance);

/// The XDMF text write_uniform_grid puts beside `h5_name` (the HDF5 file name, relative to the
/// sidecar).
std::string uniform_grid_xdmf(const std::string& h5_name, const UniformGrid& grid, const std::vector<GridBlock>& blocks);

}  // namespace tomodem
