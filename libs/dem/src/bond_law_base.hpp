#pragma once
// What the bond laws and failure criteria of src/laws/bond_*.hpp share: their parameters are
// fields of BondLaw that tools set from options (never keys of a scene's `physics`), and the
// defaults of their self-description.
#include <array>
#include <limits>

#include "tomodem/dem/bonds.hpp"
#include "tomodem/dem/law_registry.hpp"

namespace tomodem::dem::law {

namespace bond_param {
inline constexpr double kInf = std::numeric_limits<double>::infinity();
/// μ between the faces of a broken bond (any criterion that breaks bonds).
inline constexpr BondParam friction{"friction", "--friction", "-", "Coulomb μ between the faces of a broken bond",
                                    "0.5 (tomodem-fracture)", 0, kInf, false, false,
                                    [](BondLaw& l) { return &l.friction; }};
}  // namespace bond_param

struct BondDescribed {
  static constexpr const char* kSource = "";
  static constexpr std::array<BondParam, 0> kParams{};
};

}  // namespace tomodem::dem::law
