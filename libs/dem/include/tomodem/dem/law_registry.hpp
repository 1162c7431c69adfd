#pragma once
// The contact-law registry: one entry per law of every slot, built from the laws themselves
// (src/law_list.hpp lists them; each law file declares its key, parameters and needs). Scene
// parsers, tools' messages, kernel selection, the time step and docs/dem.md's law table all
// read it, so adding a law is its own file plus one line of src/law_list.hpp.
#include <string>
#include <vector>

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
/// The markdown table of docs/dem.md ("Contact laws"), printed by `tomodem-dem --list-laws`.
std::string law_table_markdown();

}  // namespace tomodem::dem
