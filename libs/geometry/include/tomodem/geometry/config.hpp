#pragma once
// tomodem-pack configuration files (YAML, format in docs/pack.md). Every key is checked:
// unknown keys, wrong types and impossible values are InputErrors naming file, field and value.
#include <string>

#include "tomodem/geometry/pack.hpp"

namespace tomodem::geometry {

struct PackConfig {
  PackSpec spec;
  std::string packing = "packing.h5";  ///< output file (relative to the config's working directory)
  std::string text;                    ///< the file as read (provenance)
  std::vector<std::string> inputs;     ///< files read (CSV tables)
};

PackConfig load_pack_config(const std::string& path);

}  // namespace tomodem::geometry
