#pragma once
// Potentials and currents of a solved network, to HDF5 with an XDMF sidecar for ParaView.
#include <string>
#include <vector>

#include "tomodem/network/conductivity.hpp"
#include "tomodem/network/network.hpp"

namespace tomodem::network {

struct FieldSet {
  std::string name;                  ///< group name, e.g. "x" or "composite"
  std::vector<double> potential;     ///< V per node (NaN where not solved)
  std::vector<double> edge_current;  ///< A per edge
};

/// Writes /nodes (particle index, position, radius, phase), /edges (i, j, conductance, contact
/// radius, kind, image), and /fields/<name>/{potential, current}; written under a temporary name
/// and renamed, with `path` minus extension + ".xdmf" next to it.
void write_fields(const std::string& path, const Network& net, const std::vector<FieldSet>& fields,
                  const std::string& parameters);

}  // namespace tomodem::network
