#pragma once
// The physics a scene uses, chosen by name per slot (normal, tangential, rolling, damping), each
// slot with an explicit "none" where it may be empty. The names, parameters and needs of every
// law come from one registry (tomodem/dem/law_registry.hpp); the force loop is compiled once per
// combination (src/kernels.cpp), so a scene pays only for the slots it fills.
#include <string>
#include <vector>

#include "tomodem/core/packing.hpp"

namespace tomodem::dem {

/// The law chosen in one slot, by its registry key. The constants name the laws the library
/// itself uses; any other registered law is chosen by key (`NormalLaw{"luding"}`) or parse().
struct NormalLaw {
  std::string key;
  static const NormalLaw linear, hertz, hertz_dmt, hertz_jkr, sintering;
};
struct TangentialLaw {
  std::string key;
  static const TangentialLaw none, linear, mindlin, viscous;
};
struct RollingLaw {
  std::string key;
  static const RollingLaw none, elastic_plastic;
};
/// How the normal dashpot η_n = c sqrt(m* S_n) gets its coefficient c (a slot of its own).
struct DampingLaw {
  std::string key;
  static const DampingLaw restitution, none;
};
inline const NormalLaw NormalLaw::linear{"linear"}, NormalLaw::hertz{"hertz"}, NormalLaw::hertz_dmt{"dmt"},
    NormalLaw::hertz_jkr{"jkr"}, NormalLaw::sintering{"sintering"};
inline const TangentialLaw TangentialLaw::none{"none"}, TangentialLaw::linear{"linear"},
    TangentialLaw::mindlin{"mindlin"}, TangentialLaw::viscous{"viscous"};
inline const RollingLaw RollingLaw::none{"none"}, RollingLaw::elastic_plastic{"elastic_plastic"};
inline const DampingLaw DampingLaw::restitution{"restitution"}, DampingLaw::none{"none"};
#define TOMODEM_LAW_COMPARE(L)                                                   \
  inline bool operator==(const L& a, const L& b) { return a.key == b.key; } \
  inline bool operator!=(const L& a, const L& b) { return a.key != b.key; }
TOMODEM_LAW_COMPARE(NormalLaw)
TOMODEM_LAW_COMPARE(TangentialLaw)
TOMODEM_LAW_COMPARE(RollingLaw)
TOMODEM_LAW_COMPARE(DampingLaw)
#undef TOMODEM_LAW_COMPARE

/// Parameters of one phase pair (symmetric). Derived fields are filled by ContactModel::finalize.
/// Each field belongs to the laws that declare it as a parameter (law_registry.hpp).
struct PairParams {
  // From the two materials (Hertz family).
  double E_star = 0;  ///< effective modulus, 1/E* = (1-ν1²)/E1 + (1-ν2²)/E2, Pa
  double G_star = 0;  ///< effective shear modulus, 1/G* = (2-ν1)/G1 + (2-ν2)/G2, Pa
  // Linear laws.
  double k_n = 0;     ///< normal stiffness, N/m
  double k_t = 0;     ///< tangential stiffness, N/m (default 2/7 of the normal stiffness)
  // Damping slot: restitution e (calibrated per normal law) or ζ.
  double restitution = 1;
  double damping_ratio = 0;      ///< ζ: when given, c = 2ζ replaces the restitution calibration
  double damping = 0;            ///< c in η_n = c sqrt(m* S_n) (derived by the damping law)
  /// sqrt(k_t/S_n) of the tangential dashpot η_t = η_n sqrt(k_t/S_n) when it is constant
  /// (Hertz family + Mindlin: sqrt(4G*/E*); linear + linear: sqrt(k_t/k_n)); 0: per contact.
  double tangential_damping_ratio = 0;
  // Friction, rolling, adhesion.
  double friction = 0;           ///< Coulomb μ
  double rolling_friction = 0;   ///< μ_r: |M_r| ≤ μ_r R* F_n
  double work_of_adhesion = 0;   ///< w = 2γ for like surfaces, J/m²
  // Sintering (docs/sintering.md); set by the sintering driver for the current temperature.
  double sinter_delta_b = 0;      ///< Δ_b = Ω δ_b D_b/(kT), m⁵/(N s); 0: the pair does not sinter (Hertz)
  double sinter_gamma = 0;        ///< surface energy γ_s, J/m²
  double sinter_dihedral = 0;     ///< dihedral angle ψ, rad
  double sinter_eta = 0;          ///< tangential viscosity parameter η (dimensionless)
  double sinter_initial_neck = 0; ///< a_min/R of a neck when its contact forms
  /// Values of a normal law's own parameters (laws whose parameters no other law shares, e.g.
  /// luding): each such law maps its keys onto these slots in its registry entry.
  double own[6] = {0, 0, 0, 0, 0, 0};
};

/// The per-temperature values of a sintering pair (the only pair values that change after a
/// Simulation has chosen its kernels: Simulation::set_sinter_values).
struct SinterValues {
  double delta_b = 0, gamma = 0, dihedral = 0, eta = 0, initial_neck = 0;
};

struct ContactModel {
  NormalLaw normal{"hertz"};
  TangentialLaw tangential{"none"};
  RollingLaw rolling{"none"};
  DampingLaw damping{"restitution"};
  int n_phases = 1;
  std::vector<Material> materials;  ///< per phase: E, ν, density, surface energy
  std::vector<PairParams> pairs;    ///< n_phases × n_phases, symmetric

  /// Sizes `pairs` for the materials (keeping what is set) and derives E*, G*, the damping
  /// coefficient (damping slot), k_t = 2/7 of the normal stiffness when unset, and
  /// w = 2 sqrt(γ_a γ_b) when unset.
  void finalize();

  bool needs_rotation() const;
  /// Empty when the slots fit together, else why not (e.g. the viscous tangential law needs sintering).
  std::string incompatibility() const;
  PairParams& pair(int a, int b) { return pairs[static_cast<std::size_t>(a * n_phases + b)]; }
  const PairParams& pair(int a, int b) const { return pairs[static_cast<std::size_t>(a * n_phases + b)]; }
  /// Sets parameter `key` of one of the chosen laws (its registry key, e.g. "friction") on every
  /// pair; an InputError when none of the chosen laws takes it (the message lists what they take).
  void set(const std::string& key, double value);
  std::string describe() const;  ///< e.g. "hertz+mindlin+none+restitution"
};

std::string to_string(const NormalLaw&);
std::string to_string(const TangentialLaw&);
std::string to_string(const RollingLaw&);
std::string to_string(const DampingLaw&);
/// Parsers return false for names the registry does not hold (the caller reports file, field
/// and value, with law_names() of the slot).
bool parse(const std::string& s, NormalLaw& out);
bool parse(const std::string& s, TangentialLaw& out);
bool parse(const std::string& s, RollingLaw& out);
bool parse(const std::string& s, DampingLaw& out);

/// What is wrong with a material's values, shared by scenes (tomodem-dem, tomodem-sinter) and pack
/// configs (tomodem-pack) so that both refuse the same values: the key at fault ("poisson_ratio"),
/// the value and why; an empty key when the material is sound. `need_modulus`: the normal law
/// needs youngs_modulus > 0 (the Hertz family).
struct MaterialProblem {
  std::string key, value, why;
};
MaterialProblem material_problem(const Material& m, bool need_modulus);

/// Dimensionless damping c of η_n = c sqrt(m* S_n) that makes a Hertz collision rebound at
/// restitution e, for every impact speed (the Hertz–Tsuji model is self-similar in the speed).
/// Found by integrating the dimensionless collision once and solving for c (bisection).
double hertz_damping_for_restitution(double e);
/// The smallest restitution a scene may ask for (refused below: see hertz_damping_for_restitution).
inline constexpr double kMinRestitution = 1e-3;
/// Restitution of the dimensionless Hertz collision with damping c (the inverse map).
double hertz_restitution_for_damping(double c);
/// Linear spring–dashpot: ζ = -ln e / sqrt(π² + ln² e).
double linear_damping_ratio_for_restitution(double e);

/// JKR helpers (Johnson, Kendall & Roberts 1971): δ(a) = a²/R − sqrt(2π w a/E*).
double jkr_contact_radius(double delta, double R, double E, double w);  ///< stable branch
double jkr_force(double a, double R, double E, double w);               ///< 4E a³/(3R) − sqrt(8π w E a³)
double jkr_break_overlap(double R, double E, double w);                 ///< δ_c < 0

}  // namespace tomodem::dem
