#pragma once
// tomodem-cg: read packings (one or a time series), coarse-grain, write HDF5 + XDMF, summarise
// in JSON (docs/cg.md).
#include <string>
#include <vector>

#include "tomodem/core/packing.hpp"
#include "tomodem/fields/cg.hpp"
#include "tomodem/spatial/image.hpp"

namespace tomodem::fields {

struct CgConfig {
  std::vector<std::string> inputs;  ///< snapshots of one cell; the fields are their time average
  std::string reference;            ///< packing the displacement is measured from ("" none)
  std::string output;               ///< fields .h5 (and its .xdmf sidecar)
  std::string vdb;                  ///< --vdb: the scalar and vector fields as OpenVDB grids ("" none; full grids only)
  std::string json;                 ///< summary file ("" or "-": stdout only)
  std::string kernel = "gaussian";  ///< gaussian | lucy
  std::string width = "1";          ///< mean diameters, or a length with a unit ("20um")
  double cutoff = 3;                ///< Gaussian cut-off in widths
  std::string grid;                 ///< "N" or "NX,NY,NZ" nodes along the cell vectors; "" automatic
  std::string slice;                ///< "z=0.5": the plane at this fraction of the cell vector
  std::string profile;              ///< "z": profile along this cell vector
  int quadrature = 0;               ///< points per branch (0: automatic)
  double density = 0;               ///< kg/m^3 for every phase (0: from the materials)
  std::string bond_forces = "auto"; ///< auto | stored | stretch | none
  int threads = 0;
  std::string compare_image;        ///< --compare-image: a segmented scan (.h5 /labels) beside the packing
  std::string compare_phase;        ///< --phase: its solid label(s), "0" or "0,1"
};

/// Runs the tool; returns the JSON summary text (the caller emits it: emit_summary).
std::string run_cg(const CgConfig& c);
/// The --compare-image mode (docs/cg.md#image-and-model-side-by-side); run_cg calls it.
std::string run_compare_image(const CgConfig& c);

/// How the snapshot gets its masses and pair forces (for tests that build packings in memory).
struct SnapshotOptions {
  double density = 0;                   ///< kg/m^3 for every phase; 0: the materials' densities
  std::string bond_forces = "auto";     ///< auto | stored | stretch | none
  std::vector<Vec3> stored_bond_force;  ///< /bonds/force rows (force on j from i), when read
  std::vector<spatial::Image> bond_image;  ///< /bonds/image rows, when read
};
/// Masses, contact and bond forces and branch vectors of a packing; the displacement from
/// `reference` when given. InputError naming `file` and the dataset for what is missing.
/// `bond_source` receives where the bond forces came from.
Snapshot make_snapshot(const Packing& p, const std::string& file, const SnapshotOptions& o, const Packing* reference,
                       const std::string& reference_file, std::string* bond_source = nullptr);

}  // namespace tomodem::fields
