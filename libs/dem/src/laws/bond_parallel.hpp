#pragma once
// The parallel bond (Potyondy & Cundall 2004) with large-neck corrections (Jauffrès et al. 2012;
// docs/physics.md#bond-stiffness): a neck of radius a carries a normal force in total form from
// the rest length, a tangential force, a twisting and a bending moment, each incremental.
#include <array>

#include "../bond_law_base.hpp"

namespace tomodem::dem::law {

namespace bond_param {
inline constexpr BondParam g_n{"g_n_coefficient", "--gn-coefficient", "-", "c of g_n = 1 + c (a/R)²", "4", 0, kInf,
                               false, false, [](BondLaw& l) { return &l.g_n_coefficient; }};
inline constexpr BondParam g_t{"g_t_coefficient", "--gt-coefficient", "-", "c of g_t = 1 + c (a/R)²", "1.2", 0, kInf,
                               false, false, [](BondLaw& l) { return &l.g_t_coefficient; }};
inline constexpr BondParam damping_ratio{"damping_ratio", "--damping-ratio", "-",
                                         "ζ of the normal and tangential bond dashpots",
                                         "0.3 (explicit tests)", 0, kInf, false, false,
                                         [](BondLaw& l) { return &l.damping_ratio; }};
}  // namespace bond_param

struct BondParallel : BondDescribed {
  static constexpr const char* kKey = "parallel";
  static constexpr const char* kSummary =
      "k_n = 2E*a g_n, k_t = 8G*a g_t, k_twist = ½k_t a², k_bend = ¼k_n a²; F_n from the rest length, F_t and "
      "moments incremental";
  static constexpr const char* kSource = "Potyondy & Cundall 2004; Jauffrès et al. 2012";
  static constexpr std::array<BondParam, 3> kParams{bond_param::g_n, bond_param::g_t, bond_param::damping_ratio};

  /// The stiffnesses (bonds.hpp: one formula with the stiffness matrix of libs/mechanics); k_n
  /// bounds the time step.
  static BondStiffness stiffness(const BondLaw& law, double a, double ri, double rj) {
    return bond_stiffness(law, a, ri, rj);
  }
  /// Elastic energy the bond holds in this state, J (tallies; released when it breaks).
  static double energy(const BondStiffness& k, double un, const Vec3& fs, double tw, const Vec3& mb) {
    return 0.5 * k.kn * un * un + (k.kt > 0 ? 0.5 * norm2(fs) / k.kt : 0.0) +
           (k.ktwist > 0 ? 0.5 * tw * tw / k.ktwist : 0.0) + (k.kbend > 0 ? 0.5 * norm2(mb) / k.kbend : 0.0);
  }
};

}  // namespace tomodem::dem::law
