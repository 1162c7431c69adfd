#pragma once
// tomodem-carve's configuration and driver (tools/carve/main.cpp stays thin).
#include <string>
#include <vector>

#include "tomodem/carve/carve.hpp"

namespace tomodem::carve {

struct CarveConfig {
  std::string packing;                 ///< input packing (.h5)
  // exactly one macropore source
  std::string level_set, grid;         ///< OpenVDB file and grid name ("" = macropores / first)
  std::string labels, dataset;         ///< label volume and HDF5 dataset ("" = /labels)
  std::vector<int> label_values{2};    ///< macropore labels (empty: any non-zero); tomodem-segment: 2
  std::string mesh;                    ///< closed surface mesh
  std::string spheres;                 ///< packing whose particles are the macropores
  double image_unit = 0;               ///< m per image unit (level set: overrides metadata; mesh: default 1)
  double spacing = 0;                  ///< label volume voxel size override, m
  Options options;
  // outputs
  std::string output;                  ///< carved packing (.h5 + .xdmf)
  std::string json;                    ///< "" or "-": stdout only
  std::string picture;                 ///< mid-plane PNG
  std::string command_line;            ///< provenance
};

/// Loads the macropores named by the config (InputError: none or several given).
std::unique_ptr<Macropores> load_macropores(const CarveConfig& cfg);

/// Refuses (InputError naming the option and the value) options out of range and outputs that
/// name an input or each other; run_carve calls it before reading anything.
void check_config(const CarveConfig& cfg);

/// Reads, carves, writes (packing, picture, JSON: all after the work, atomically); returns the
/// JSON summary.
std::string run_carve(const CarveConfig& cfg);

}  // namespace tomodem::carve
