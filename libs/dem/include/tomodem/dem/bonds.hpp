#pragma once
// Bonded-particle model: solid necks between particles (Jefferson, Haritos & McMeeking 2002;
// Potyondy & Cundall 2004; Jauffrès et al. 2012). A bond carries a normal force, a tangential
// force, a twisting and a bending moment from the relative motion since bonding; its radius
// does not change. Broken bonds leave the pair to the scene's contact law. Scenes without
// bonds allocate and run nothing of this.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "tomodem/core/vec3.hpp"

namespace tomodem::dem {

enum class BondFailure { none, stress, lefm };

/// Parameters of bonds between two phases (symmetric). Stiffnesses follow from the materials:
/// k_n = 2E* a g_n, k_t = 8G* a g_t (= E a g_n/(1-ν²) and 2E a g_t/((1+ν)(2-ν)) for like
/// phases), k_twist = ½ k_t a², k_bend = ¼ k_n a².
struct BondLaw {
  double E_star = 0, G_star = 0;      ///< Pa, from the materials
  /// Large-neck corrections g = 1 + c (a/R)², R = 2R_iR_j/(R_i+R_j); the defaults pass through
  /// g_n = 2 and g_t = 1.3 at a/R = 0.5 (ν = 0.2, docs/physics.md#bond-stiffness; the exact interpolation of
  /// Jauffrès et al. 2012 is not verified here: set c = 0 to use the small-neck limit).
  double g_n_coefficient = 4.0, g_t_coefficient = 1.2;
  double damping_ratio = 0;           ///< ζ of normal and tangential bond dashpots
  double tensile_strength = 0;        ///< Pa, stress criterion
  double shear_strength = 0;          ///< Pa, stress criterion
  double fracture_energy = 0;         ///< Γ = 2γ_s, J/m², LEFM criterion
  double friction = 0;                ///< Coulomb μ between the faces of a broken bond
  /// Dense networks (face_cap_stiffness): cap k_n, k_t at E_face A_face/L, A_face the pair's face
  /// in the radical tessellation. Applied where the packing's tessellation is at hand (the network
  /// tools, mechanics::bond_stiffnesses); the DEM bond loop uses the isolated-neck law.
  bool face_cap = false;
  double E_face = 0;                  ///< Pa, 2/(1/E_i + 1/E_j): Young's modulus of the face column
};

/// Stiffnesses of one bond (docs/physics.md#bonded-particles); shared by the DEM bond loop and
/// the stiffness matrix of libs/mechanics, so both use one formula.
struct BondStiffness {
  double kn, kt, ktwist, kbend, gn, gt;
};
/// The largest a/R̄ for which the corrections g_n, g_t are derived (the finite-element necks of
/// Jauffrès et al. 2012 reach a/R = 0.5, docs/bond.md#neck-laws): larger necks get the g of
/// a/R̄ = 0.5 (held, not extrapolated; young, fracture and bond count and warn about them).
inline constexpr double kNeckCorrectionMaxRatio = 0.5;
inline BondStiffness bond_stiffness(const BondLaw& law, double a, double ri, double rj) {
  const double rb = 2 * ri * rj / (ri + rj);
  const double q = std::min(a / rb, kNeckCorrectionMaxRatio), s = q * q;
  BondStiffness k;
  k.gn = 1 + law.g_n_coefficient * s;
  k.gt = 1 + law.g_t_coefficient * s;
  k.kn = 2 * law.E_star * a * k.gn;
  k.kt = 8 * law.G_star * a * k.gt;
  k.ktwist = 0.5 * k.kt * a * a;
  k.kbend = 0.25 * k.kn * a * a;
  return k;
}

/// Dense-network neck law (docs/bond.md#dense-networks): a neck's load-bearing area cannot exceed
/// the face the two particles share in the radical (Laguerre) tessellation, so k_n and k_t are
/// capped at the rigid-body-spring value of that face, E_face A_face/L (Bolander & Saito 1998,
/// k_t = k_n: the Voronoi/Laguerre spring network that reproduces a uniformly strained solid).
/// k_twist and k_bend scale with their spring (same neck radius). Small necks far apart sit below
/// the cap (their face is much larger than the neck) and are unchanged; at full density every
/// bond is at the cap and the network is the spring network of the tessellation (E = E_s, ν = 0).
/// Returns true when a spring was capped.
inline bool face_cap_stiffness(BondStiffness& k, double E_face, double face_area, double length) {
  const double cap = length > 0 ? E_face * face_area / length : HUGE_VAL;
  bool capped = false;
  if (k.kn > cap) {
    k.kbend *= cap / k.kn;
    k.kn = cap;
    capped = true;
  }
  if (k.kt > cap) {
    k.ktwist *= cap / k.kt;
    k.kt = cap;
    capped = true;
  }
  return capped;
}

/// Critical mean stresses of one bond (Pa): σ = F_n/(πa²) + 4|Γ_t|/(πa³) against `tension`,
/// τ = |F_t|/(πa²) + 2|Γ_n|/(πa³) against `shear` (Potyondy & Cundall 2004).
struct BondStrength {
  double tension, shear;
};
/// The critical stresses of a bond under `failure` (HUGE_VAL for none): each criterion's own
/// formula (src/laws/bond_failure_*.hpp, through the registry); the DEM bond loop calls the
/// same functions, compiled in.
BondStrength bond_strength(BondFailure failure, const BondLaw& law, double a, const BondStiffness& k);

/// Bonds as structure of arrays, i < j; `image` is the periodic image of j seen from i
/// (integer cell vectors) and follows the particles when they are wrapped into the cell.
struct BondSet {
  enum State : uint8_t { intact = 0, broken = 1 };
  enum Mode : uint8_t { not_broken = 0, tension = 1, shear = 2 };
  std::vector<int32_t> i, j;
  std::vector<Vec3> image;
  std::vector<double> radius;       ///< a_b, m
  std::vector<double> rest_length;  ///< centre distance at bonding, m
  std::vector<uint8_t> state;
  std::vector<uint8_t> mode;        ///< how it broke
  std::vector<double> broken_at;    ///< s
  // Accumulated state (on i; j gets the opposite).
  std::vector<Vec3> shear_force;    ///< N
  std::vector<double> twist;        ///< N m, along n
  std::vector<Vec3> bend;           ///< N m
  std::size_t size() const { return i.size(); }
  std::size_t intact_count() const;
  /// Adds a bond at the current distance of i and j (through `image`); returns its index.
  std::size_t add(int32_t a, int32_t b, const Vec3& image_ab, double radius, double rest_length);
};

/// What happened to the bonds in a run.
struct BondEvent {
  double time;
  int32_t bond;
  uint8_t mode;
  Vec3 position;          ///< where: the neck centre (on the bond axis, R_i/(R_i+R_j) from i), m
  double energy = 0;      ///< elastic energy the bond held when it broke (released), J
};

}  // namespace tomodem::dem
