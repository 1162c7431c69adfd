#pragma once
// What `tomodem-conduct` does, as a library call (the executable only parses its command line).
#include <string>
#include <vector>

namespace tomodem::network {

struct ConductConfig {
  std::string input;                 ///< packing (.h5)
  std::string output;                ///< potentials and currents (.h5 + .xdmf); empty = none
  std::string json;                  ///< --json: checked against the other outputs (the tool writes it)
  std::vector<std::string> phases;   ///< conducting phases; empty = all
  std::string bc = "electrodes";     ///< "electrodes" | "periodic"
  std::string axes = "x";            ///< electrode axes: any of "xyz", or "all"
  std::string contact_radius = "geometric";
  double gap_tolerance = 1e-3, min_contact_ratio = 0.01, electrode_tolerance = 0.05, voltage = 1.0;
  bool bonds = true, contacts = true;
  /// --neck-law: "flux_tube" (default), "face_capped" (NetworkOptions::flux_tube = false, the law
  /// before issue 18 item 7) or "isolated" (Holm alone, NetworkOptions::face_cap = false).
  std::string neck_law = "flux_tube";
  bool isolated_necks = false;       ///< --isolated-necks: an alias of neck_law "isolated"
  double tolerance = 1e-10;
  int max_iterations = 0;
  std::string preconditioner = "ic";
  // Composite electrode (enabled when both lists are given).
  std::vector<std::string> electronic, ionic;
  double charge_transfer = 0;        ///< S/m per metre of TPB
  // Voxel cross-check: resolutions (voxels along the longest edge), e.g. {16, 32, 64}, or voxels
  // per mean diameter of the conducting particles when voxel_per_diameter (--voxel-check 16d,32d).
  std::vector<int> voxel;
  bool voxel_per_diameter = false;
  // --voxel-box: network and image of a cube cut from the packing ("3d": mean diameters, or m),
  // lower corner at these fractions of the cell (empty: centred).
  std::string voxel_box;
  std::vector<double> voxel_box_corner;
  // Transport in a segmented image (--image): a label volume instead of a packing.
  std::string image;                 ///< labels (.h5, dataset /labels) from tomodem-segment
  int phase = -1;                    ///< the conducting label (σ = 1); -1: not given
  std::string phase_conductivity;    ///< "1:1.0,2:0.3": several conducting labels
  std::string sides = "noflux";      ///< faces parallel to the axis: "noflux" | "periodic"
};

/// --voxel-check values: "16" (voxels along the longest edge) or "16d" (per mean diameter), one
/// unit for all; fills config.voxel and config.voxel_per_diameter. InputError for anything else.
void parse_voxel_resolutions(const std::vector<std::string>& values, ConductConfig& config);

/// Runs the computation and writes the outputs (atomically). Returns the JSON summary text.
/// Throws InputError for bad input (exit 2).
std::string run_conduct(const ConductConfig& config);

}  // namespace tomodem::network
