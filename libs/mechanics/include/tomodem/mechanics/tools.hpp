#pragma once
// The bodies of tomodem-bond and tomodem-young (main.cpp only parses the command line).
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tomodem/mechanics/bonding.hpp"
#include "tomodem/fields/block.hpp"
#include "tomodem/mechanics/elastic.hpp"

namespace tomodem::mechanics {

struct BondConfig {
  std::string input, output, json;
  NeckRule rule = NeckRule::overlap;
  std::string sinter_config;                ///< rule sinter: sintering settings (docs/sintering.md)
  int threads = 0;                          ///< rule sinter: threads of the run (0: OpenMP's default)
  double gap_tolerance = 1e-3, neck_ratio = 0.1, min_neck_ratio = 0.01, target_density = 0;
  std::vector<std::string> exclude;         ///< "A:B" phase pairs (names or indices) without bonds
  std::vector<std::string> pair_ratio;      ///< "A:B=0.2" per-pair neck ratios (rule ratio)
  bool allow_disconnected = true;           ///< false: exit 2 when no cluster spans the cell
};
/// Returns the JSON summary (also written to `json` when set).
std::string run_bond(const BondConfig& c);

/// What tomodem-young runs: the implicit solve, the explicit DEM test, or both (cross-check).
enum class YoungMethod : uint8_t { implicit, explicit_test, both };
inline constexpr NameTable<YoungMethod, 3> kYoungMethodNames = {
    {{YoungMethod::implicit, "implicit"}, {YoungMethod::explicit_test, "explicit"}, {YoungMethod::both, "both"}}};
inline const char* to_string(YoungMethod m) { return name_of(kYoungMethodNames, m); }
inline std::optional<YoungMethod> parse_young_method(std::string_view name) { return value_of(kYoungMethodNames, name); }

struct YoungConfig {
  std::string input, json, output_csv;
  YoungMethod method = YoungMethod::implicit;
  int axis = 2;                             ///< loading axis of E and ν: 0 x, 1 y, 2 z (kAxisNames)
  LawOptions law;
  ImplicitOptions implicit;
  ExplicitOptions explicit_;
  std::optional<double> youngs_modulus, poisson_ratio, density;  ///< overrides for every phase (unset: file)
  fields::FieldsSettings fields;  ///< --fields: the state under uniaxial stress at --strain, coarse-grained (docs/cg.md)
};
std::string run_young(const YoungConfig& c);

}  // namespace tomodem::mechanics
