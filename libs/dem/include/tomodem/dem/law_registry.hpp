#pragma once
// The contact-law registry: one entry per law of every slot, built from the laws themselves
// (src/law_list.hpp lists them; each law file declares its key, parameters and needs). Scene
// parsers, tools' messages, kernel selection, the time step and docs/dem.md's law table all
// read it, so adding a law is its own file plus one line of src/law_list.hpp.
#include <string>
#include <vector>

#include "tomodem/dem/bonds.hpp"
#include "tomodem/dem/model.hpp"

namespace tomodem::dem {

enum class Slot { normal, tangential, rolling, damping };
std::string to_string(Slot);

/// One parameter of a law: a key of `physics` (and of `physics.pairs[k]`), its range and where
/// it lives in PairParams. Several laws may share a parameter (friction).
struct LawParam {
  const char* key;
  const char* unit;     ///< "N/m", "-" for dimensionless
  const char* meaning;
  const char* fallback; ///< the default as docs show it; "required" when it must be given
  double lo, hi;        ///< accepted range
  bool lo_open, hi_open;
  double* (*ref)(PairParams&);
  bool required() const;
};

/// How a normal law's stiffness enters the time step, FIRE masses and servos.
enum class StiffnessKind {
  hertz,     ///< S_n = 2E*a (Rayleigh time of the particles)
  spring,    ///< bounded by stiffness(pp, 0, 0) (two-particle Verlet limit)
  viscous,   ///< no spring (viscous limit of the necks)
};

/// A problem with a pair's values: the parameter at fault and why ("" when none).
struct LawProblem {
  std::string key, why;
};

struct LawInfo {
  Slot slot = Slot::normal;
  std::string key, summary, source;
  std::vector<LawParam> params;
  int history = 0;           ///< doubles per contact
  bool rotation = false;     ///< needs angular velocities
  bool touch_flag = false;   ///< a per-contact flag (JKR hysteresis)
  bool needs_modulus = false;   ///< materials must give youngs_modulus
  bool needs_adhesion = false;  ///< work_of_adhesion or surface energies must be given
  bool driven = false;       ///< normal: its values are set by a driver (tomodem-sinter), not a scene
  bool needs_spring = false; ///< tangential: needs an elastic normal law
  std::string requires_normal;  ///< tangential: only with this normal law
  // Normal laws.
  StiffnessKind stiffness_kind = StiffnessKind::hertz;
  /// Largest tangent stiffness S_n of a contact at overlap δ, N/m (servos, FIRE masses; at
  /// δ = 0 for the spring kind: the time step).
  double (*stiffness)(const PairParams&, double r_star, double delta) = nullptr;
  /// Coefficient c of η_n = c sqrt(m* S_n) that makes the law rebound at restitution e.
  double (*restitution_damping)(double e) = nullptr;
  /// Damping laws: c for a pair, given the normal law's calibration.
  double (*damping)(const PairParams&, double (*calibrate)(double)) = nullptr;
  /// Values that do not fit together (e.g. an unloading stiffness below the loading one).
  LawProblem (*check)(const PairParams&) = nullptr;

  const LawParam* param(const std::string& key) const;
  std::string keys() const;  ///< "friction, rolling_friction" or "none"
};

/// Every law of a slot, in registry order.
const std::vector<LawInfo>& laws(Slot);
/// The law of `slot` with key `key`, or null.
const LawInfo* find_law(Slot, const std::string& key);
/// The entry of a law chosen in a model (which must be registered).
const LawInfo& law_info(const NormalLaw&);
const LawInfo& law_info(const TangentialLaw&);
const LawInfo& law_info(const RollingLaw&);
const LawInfo& law_info(const DampingLaw&);
/// "linear, hertz, dmt, jkr, sintering or luding", optionally only those `keep` accepts.
std::string law_names(Slot, bool (*keep)(const LawInfo&) = nullptr);
/// Every parameter key of any law (a key no law takes is simply unknown).
std::vector<std::string> all_param_keys();
/// The four laws chosen in a model (normal, tangential, rolling, damping).
std::vector<const LawInfo*> chosen_laws(const ContactModel&);
/// The markdown table of docs/dem.md ("Contact laws"): the contact slots, then the bond law and
/// the bond failure criteria. Printed by `tomodem-dem --list-laws`.
std::string law_table_markdown();

// ---- Bonds: two more slots, the bond law and the failure criterion (src/laws/bond_*.hpp). Their
// parameters are fields of BondLaw set by the tools' options, never keys of a scene's `physics`:
// they are listed apart from the contact keys (all_param_keys), so that neither list accepts the
// other's keys ("friction" is one of each, with two meanings).

/// One parameter of a bond law or failure criterion: where it lives (BondLaw field, option).
struct BondParam {
  const char* key;      ///< the BondLaw field, as messages and docs name it
  const char* option;   ///< the option of tomodem-young / tomodem-fracture that sets it
  const char* unit;     ///< "Pa", "-" for dimensionless
  const char* meaning;
  const char* fallback; ///< the default as docs show it; "required" when it must be given
  double lo, hi;        ///< accepted range
  bool lo_open, hi_open;
  double* (*ref)(BondLaw&);
  bool required() const;
};

/// What a bond law and a failure criterion both declare.
struct BondEntry {
  std::string slot;     ///< "bond" or "bond failure"
  std::string key, summary, source;
  std::vector<BondParam> params;
  const BondParam* param(const std::string& key) const;
  std::string keys() const;  ///< "tensile_strength, shear_strength, friction" or "none"
  std::string what() const;  ///< "the stress bond failure criterion"
};

struct BondLawInfo : BondEntry {
  /// Stiffnesses of a bond of radius a between radii ri, rj; k_n bounds the time step.
  BondStiffness (*stiffness)(const BondLaw&, double a, double ri, double rj) = nullptr;
  /// Elastic energy held in state (u_n, F_s, Γ_n, M_b), J: the tallies, and released on failure.
  double (*energy)(const BondStiffness&, double un, const Vec3& fs, double twist, const Vec3& bend) = nullptr;
};

struct BondFailureInfo : BondEntry {
  BondFailure id = BondFailure::none;
  bool breaks = false;               ///< false: bonds never break (no fracture test)
  bool needs_surface_energy = false; ///< Γ defaults to the materials' surface energies
  /// Critical mean stresses σ_c, τ_c of a bond of radius a (HUGE_VAL: never).
  BondStrength (*strength)(const BondLaw&, double a, const BondStiffness&) = nullptr;
};

/// Every bond law / failure criterion, in registry order.
const std::vector<BondLawInfo>& bond_law_entries();
const std::vector<BondFailureInfo>& bond_failure_entries();
/// The entry with `key`, or null.
const BondLawInfo* find_bond_law(const std::string& key);
const BondFailureInfo* find_bond_failure(const std::string& key);
/// The entry of a criterion (every BondFailure is registered).
const BondFailureInfo& bond_failure_info(BondFailure);
/// "parallel"; "none, stress or lefm" (`breaking_only`: the criteria that break bonds).
std::string bond_law_names();
std::string bond_failure_names(bool breaking_only = false);
/// The entry named `name`, or InputError(file, field, name, "unknown bond law; expected ...").
const BondLawInfo& parse_bond_law(const std::string& name, const std::string& file, const std::string& field);
/// The criterion named `name`, or InputError(file, field, name, "unknown bond failure criterion;
/// expected <the registry's names>").
BondFailure parse_bond_failure(const std::string& name, const std::string& file, const std::string& field,
                               bool breaking_only = false);
/// Every parameter key of any bond law or criterion (a list of its own, see above).
std::vector<std::string> bond_param_keys();

/// A value a tool received for a bond parameter; `given` is false when left at the tool's default.
struct BondSetting {
  std::string key;
  double value;
  bool given;
};
/// Checks the settings meant for one entry (InputError naming the option and value, exit 2): a
/// given key the entry does not take is refused with its accepted keys, a required one not given
/// is refused, a given value outside its range too.
void check_bond_settings(const BondEntry& entry, const std::vector<BondSetting>& settings);
/// Writes the value of every parameter the entry takes (given or default) into its BondLaw field.
void apply_bond_settings(const BondEntry& entry, const std::vector<BondSetting>& settings, BondLaw& law);

}  // namespace tomodem::dem
