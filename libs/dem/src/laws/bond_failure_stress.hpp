#pragma once
// Stress criterion (Potyondy & Cundall 2004): a bond breaks when σ = F_n/(πa²) + 4|M_b|/(πa³)
// exceeds the tensile strength or τ = |F_t|/(πa²) + 2|Γ_n|/(πa³) the shear strength.
#include <array>

#include "../bond_law_base.hpp"

namespace tomodem::dem::law {

namespace bond_param {
inline constexpr BondParam tensile_strength{"tensile_strength", "--tensile-strength", "Pa", "bond tensile strength σ_c",
                                            "required", 0, kInf, true, false,
                                            [](BondLaw& l) { return &l.tensile_strength; }};
inline constexpr BondParam shear_strength{"shear_strength", "--shear-strength", "Pa", "bond shear strength τ_c",
                                          "required", 0, kInf, true, false,
                                          [](BondLaw& l) { return &l.shear_strength; }};
}  // namespace bond_param

struct FailureStress : BondDescribed {
  static constexpr const char* kKey = "stress";
  static constexpr const char* kSummary = "σ = F_n/(πa²) + 4|M_b|/(πa³) > σ_c or τ = |F_t|/(πa²) + 2|Γ_n|/(πa³) > τ_c";
  static constexpr const char* kSource = "Potyondy & Cundall 2004";
  static constexpr BondFailure kId = BondFailure::stress;
  static constexpr bool kBreaks = true;
  static constexpr bool kNeedsSurfaceEnergy = false;
  static constexpr std::array<BondParam, 3> kParams{bond_param::tensile_strength, bond_param::shear_strength,
                                                    bond_param::friction};
  static BondStrength strength(const BondLaw& law, double, const BondStiffness&) {
    return {law.tensile_strength, law.shear_strength};
  }
};

}  // namespace tomodem::dem::law
