#pragma once
// The fields file: HDF5 written under a temporary name and renamed, then its XDMF sidecar.
#include <string>

#include "tomodem/fields/cg.hpp"

namespace tomodem::fields::detail {

/// `root_attributes`: tool, version, parameters (JSON text), created_utc.
void write_fields(const std::string& path, const Accumulator::Fields& f, GridSpec::Kind kind, int axis,
                  const std::vector<std::pair<std::string, std::string>>& root_attributes);

}  // namespace tomodem::fields::detail
