#pragma once
// LEFM criterion (Jauffrès et al. 2012, docs/fracture.md): the neck is a circular ligament whose
// compliance 1/k gives the energy release rate G = (F²/2) dC/dA (dA = −2πa da, g held fixed);
// G = Γ gives F_c² = 8π E* g_n a³ Γ, i.e. σ_c = 2 sqrt(2E* Γ g_n/(π a)) and τ_c = 2 sqrt(8G* Γ g_t/(π a))
// (for g = 1 the first is Tada's external circular crack, K_I = F/(2a sqrt(πa)) = K_IC): smaller
// necks are stronger in stress. σ and τ as the stress criterion's.
#include <array>
#include <cmath>

#include "../bond_law_base.hpp"

namespace tomodem::dem::law {

namespace bond_param {
inline constexpr BondParam fracture_energy{"fracture_energy", "--fracture-energy", "J/m²",
                                           "Γ = 2γ_s of the neck (0: γ_i + γ_j of the materials)",
                                           "γ_i + γ_j of the materials", 0, kInf, false, false,
                                           [](BondLaw& l) { return &l.fracture_energy; }};
}  // namespace bond_param

struct FailureLefm : BondDescribed {
  static constexpr const char* kKey = "lefm";
  static constexpr const char* kSummary = "σ, τ as stress against σ_c = 2 sqrt(2E*Γ g_n/(πa)), τ_c = 2 sqrt(8G*Γ g_t/(πa))";
  static constexpr const char* kSource = "Jauffrès et al. 2012; Tada, Paris & Irwin";
  static constexpr BondFailure kId = BondFailure::lefm;
  static constexpr bool kBreaks = true;
  static constexpr bool kNeedsSurfaceEnergy = true;
  static constexpr std::array<BondParam, 2> kParams{bond_param::fracture_energy, bond_param::friction};
  static BondStrength strength(const BondLaw& law, double a, const BondStiffness& k) {
    return {2 * std::sqrt(2 * law.E_star * law.fracture_energy * k.gn / (M_PI * a)),
            2 * std::sqrt(8 * law.G_star * law.fracture_energy * k.gt / (M_PI * a))};
  }
};

}  // namespace tomodem::dem::law
