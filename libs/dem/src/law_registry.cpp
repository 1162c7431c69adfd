// The registry entries, built from the laws' own declarations (law_list.hpp), and what is read
// from them: names for messages, the chosen laws of a model, the docs table.
#include "tomodem/dem/law_registry.hpp"

#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>
#include <type_traits>

#include "law_list.hpp"
#include "tomodem/core/error.hpp"

namespace tomodem::dem {

namespace {

template <Slot S, class L>
LawInfo describe() {
  LawInfo e;
  e.slot = S;
  e.key = L::kKey;
  e.summary = L::kSummary;
  e.source = L::kSource;
  e.params.assign(L::kParams.begin(), L::kParams.end());
  e.needs_modulus = L::kNeedsModulus;
  e.needs_adhesion = L::kNeedsAdhesion;
  e.check = &L::check;
  if constexpr (S == Slot::normal) {
    e.history = L::kHistory;
    e.touch_flag = L::kTouchFlag;
    e.driven = L::kDriven;
    e.stiffness_kind = L::kStiffness;
    e.stiffness = &L::stiffness;
    e.restitution_damping = &L::restitution_damping;
  } else if constexpr (S == Slot::damping) {
    e.damping = &L::damping;
  } else {
    e.history = L::kHistory;
    e.rotation = L::kRotation;
    if constexpr (S == Slot::tangential) {
      e.needs_spring = L::kNeedsSpring;
      e.requires_normal = L::kRequiresNormal;
    }
  }
  return e;
}

template <Slot S, class L>
void add(std::vector<LawInfo>& out) {
  if constexpr (!std::is_same_v<L, law::End>) out.push_back(describe<S, L>());
}
template <Slot S, class... L>
std::vector<LawInfo> describe_all(law::List<L...>) {
  std::vector<LawInfo> out;
  (add<S, L>(out), ...);
  return out;
}

template <class L>
BondLawInfo describe_bond_law() {
  BondLawInfo e;
  e.slot = "bond";
  e.key = L::kKey;
  e.summary = L::kSummary;
  e.source = L::kSource;
  e.params.assign(L::kParams.begin(), L::kParams.end());
  e.stiffness = &L::stiffness;
  e.energy = &L::energy;
  return e;
}
template <class F>
BondFailureInfo describe_bond_failure() {
  BondFailureInfo e;
  e.slot = "bond failure";
  e.key = F::kKey;
  e.summary = F::kSummary;
  e.source = F::kSource;
  e.params.assign(F::kParams.begin(), F::kParams.end());
  e.id = F::kId;
  e.breaks = F::kBreaks;
  e.needs_surface_energy = F::kNeedsSurfaceEnergy;
  e.strength = &F::strength;
  return e;
}
template <class... L>
std::vector<BondLawInfo> describe_bond_laws(law::List<L...>) {
  std::vector<BondLawInfo> out;
  ([&] { if constexpr (!std::is_same_v<L, law::End>) out.push_back(describe_bond_law<L>()); }(), ...);
  return out;
}
template <class... F>
std::vector<BondFailureInfo> describe_bond_failures(law::List<F...>) {
  std::vector<BondFailureInfo> out;
  ([&] { if constexpr (!std::is_same_v<F, law::End>) out.push_back(describe_bond_failure<F>()); }(), ...);
  return out;
}

/// "a, b or c".
std::string either(const std::vector<std::string>& names) {
  std::string out;
  for (std::size_t k = 0; k < names.size(); ++k)
    out += (k == 0 ? "" : (k + 1 == names.size() ? " or " : ", ")) + names[k];
  return out;
}

}  // namespace

std::string to_string(Slot s) {
  switch (s) {
    case Slot::normal: return "normal";
    case Slot::tangential: return "tangential";
    case Slot::rolling: return "rolling";
    case Slot::damping: return "damping";
  }
  return "?";
}

bool LawParam::required() const { return std::string(fallback) == "required"; }

const LawParam* LawInfo::param(const std::string& k) const {
  for (const auto& p : params)
    if (k == p.key) return &p;
  return nullptr;
}

std::string LawInfo::keys() const {
  std::string s;
  for (const auto& p : params) s += (s.empty() ? "" : ", ") + std::string(p.key);
  return s.empty() ? "none" : s;
}

const std::vector<LawInfo>& laws(Slot s) {
  static const std::vector<LawInfo> normal = describe_all<Slot::normal>(law::NormalLaws{});
  static const std::vector<LawInfo> tangential = describe_all<Slot::tangential>(law::TangentialLaws{});
  static const std::vector<LawInfo> rolling = describe_all<Slot::rolling>(law::RollingLaws{});
  static const std::vector<LawInfo> damping = describe_all<Slot::damping>(law::DampingLaws{});
  switch (s) {
    case Slot::normal: return normal;
    case Slot::tangential: return tangential;
    case Slot::rolling: return rolling;
    case Slot::damping: return damping;
  }
  return normal;
}

const LawInfo* find_law(Slot s, const std::string& key) {
  for (const auto& e : laws(s))
    if (e.key == key) return &e;
  return nullptr;
}

namespace {
const LawInfo& known(Slot s, const std::string& key) {
  if (const LawInfo* e = find_law(s, key)) return *e;
  throw InputError("", "physics." + to_string(s), key, "unknown " + to_string(s) + " law; expected " + law_names(s));
}
}  // namespace
const LawInfo& law_info(const NormalLaw& l) { return known(Slot::normal, l.key); }
const LawInfo& law_info(const TangentialLaw& l) { return known(Slot::tangential, l.key); }
const LawInfo& law_info(const RollingLaw& l) { return known(Slot::rolling, l.key); }
const LawInfo& law_info(const DampingLaw& l) { return known(Slot::damping, l.key); }

std::string law_names(Slot s, bool (*keep)(const LawInfo&)) {
  std::vector<std::string> names;
  for (const auto& e : laws(s))
    if (!keep || keep(e)) names.push_back(e.key);
  return either(names);
}

std::vector<std::string> all_param_keys() {
  std::set<std::string> keys;
  for (Slot s : {Slot::normal, Slot::tangential, Slot::rolling, Slot::damping})
    for (const auto& e : laws(s))
      for (const auto& p : e.params) keys.insert(p.key);
  return {keys.begin(), keys.end()};
}

std::vector<const LawInfo*> chosen_laws(const ContactModel& m) {
  return {&law_info(m.normal), &law_info(m.tangential), &law_info(m.rolling), &law_info(m.damping)};
}

namespace {
std::string needs_of(const LawInfo& e) {
  std::vector<std::string> n;
  if (e.history > 0) n.push_back("history " + std::to_string(e.history));
  if (e.rotation) n.push_back("rotation");
  if (e.touch_flag) n.push_back("contact flag");
  if (e.needs_modulus) n.push_back("youngs_modulus");
  if (e.needs_adhesion) n.push_back("adhesion (w or γ)");
  if (e.driven) n.push_back("tomodem-sinter");
  if (e.needs_spring) n.push_back("an elastic normal law");
  if (!e.requires_normal.empty()) n.push_back("normal " + e.requires_normal);
  std::string s;
  for (const auto& x : n) s += (s.empty() ? "" : ", ") + x;
  return s.empty() ? "–" : s;
}
std::string range_of(const LawParam& p) {
  std::ostringstream s;
  s << (p.lo_open ? "(" : "[") << p.lo << ", ";
  if (std::isinf(p.hi)) s << "∞)";
  else s << p.hi << (p.hi_open ? ")" : "]");
  return s.str();
}
std::string range_of(const BondParam& p) {
  return range_of(LawParam{p.key, p.unit, p.meaning, p.fallback, p.lo, p.hi, p.lo_open, p.hi_open, nullptr});
}
std::string bond_params_of(const BondEntry& e) {
  std::string s;
  for (const auto& p : e.params)
    s += (s.empty() ? "" : "; ") + std::string("`") + p.key + "` (`" + p.option + "`) [" + p.unit + "] ∈ " +
         range_of(p) + ", " + (p.required() ? std::string("required") : "default " + std::string(p.fallback));
  return s.empty() ? "–" : s;
}
std::string params_of(const LawInfo& e) {
  std::string s;
  for (const auto& p : e.params)
    s += (s.empty() ? "" : "; ") + std::string("`") + p.key + "` [" + p.unit + "] ∈ " + range_of(p) + ", " +
         (p.required() ? std::string("required") : "default " + std::string(p.fallback));
  return s.empty() ? "–" : s;
}
std::string cell(const std::string& t) {  // a '|' inside a cell would end it
  std::string o;
  for (char c : t) o += c == '|' ? std::string("\\|") : std::string(1, c);
  return o;
}
}  // namespace

std::string law_table_markdown() {
  std::ostringstream s;
  s << "| slot | law | parameters [unit] ∈ range, default | needs | force | source |\n";
  s << "|---|---|---|---|---|---|\n";
  for (Slot sl : {Slot::normal, Slot::tangential, Slot::rolling, Slot::damping})
    for (const auto& e : laws(sl))
      s << "| " << to_string(sl) << " | `" << e.key << "` | " << params_of(e) << " | " << needs_of(e) << " | "
        << cell(e.summary) << " | " << (e.source.empty() ? "–" : cell(e.source)) << " |\n";
  const auto bond_row = [&](const BondEntry& e, const std::string& needs) {
    s << "| " << e.slot << " | `" << e.key << "` | " << bond_params_of(e) << " | " << needs << " | " << cell(e.summary)
      << " | " << (e.source.empty() ? "–" : cell(e.source)) << " |\n";
  };
  for (const auto& e : bond_law_entries()) bond_row(e, "youngs_modulus, poisson_ratio");
  for (const auto& e : bond_failure_entries())
    bond_row(e, e.needs_surface_energy ? "surface_energy (or `--fracture-energy`)" : "–");
  return s.str();
}

// ---- Bond slots.

bool BondParam::required() const { return std::string(fallback) == "required"; }

const BondParam* BondEntry::param(const std::string& k) const {
  for (const auto& p : params)
    if (k == p.key) return &p;
  return nullptr;
}

std::string BondEntry::keys() const {
  std::string s;
  for (const auto& p : params) s += (s.empty() ? "" : ", ") + std::string(p.key);
  return s.empty() ? "none" : s;
}

std::string BondEntry::what() const { return "the " + key + (slot == "bond" ? " bond law" : " bond failure criterion"); }

const std::vector<BondLawInfo>& bond_law_entries() {
  static const std::vector<BondLawInfo> entries = describe_bond_laws(law::BondLaws{});
  return entries;
}
const std::vector<BondFailureInfo>& bond_failure_entries() {
  static const std::vector<BondFailureInfo> entries = describe_bond_failures(law::BondFailures{});
  return entries;
}

const BondLawInfo* find_bond_law(const std::string& key) {
  for (const auto& e : bond_law_entries())
    if (e.key == key) return &e;
  return nullptr;
}
const BondFailureInfo* find_bond_failure(const std::string& key) {
  for (const auto& e : bond_failure_entries())
    if (e.key == key) return &e;
  return nullptr;
}

const BondFailureInfo& bond_failure_info(BondFailure f) {
  for (const auto& e : bond_failure_entries())
    if (e.id == f) return e;
  throw std::logic_error("bond failure criterion " + std::to_string(int(f)) + " is not registered (law_list.hpp)");
}

std::string bond_law_names() {
  std::vector<std::string> names;
  for (const auto& e : bond_law_entries()) names.push_back(e.key);
  return either(names);
}
std::string bond_failure_names(bool breaking_only) {
  std::vector<std::string> names;
  for (const auto& e : bond_failure_entries())
    if (e.breaks || !breaking_only) names.push_back(e.key);
  return either(names);
}

const BondLawInfo& parse_bond_law(const std::string& name, const std::string& file, const std::string& field) {
  if (const BondLawInfo* e = find_bond_law(name)) return *e;
  throw InputError(file, field, name, "unknown bond law; expected " + bond_law_names());
}

BondFailure parse_bond_failure(const std::string& name, const std::string& file, const std::string& field,
                               bool breaking_only) {
  const BondFailureInfo* e = find_bond_failure(name);
  if (e && (e->breaks || !breaking_only)) return e->id;
  throw InputError(file, field, name,
                   std::string(e ? "bonds that never break make no fracture test" : "unknown bond failure criterion") +
                       "; expected " + bond_failure_names(breaking_only));
}

std::vector<std::string> bond_param_keys() {
  std::set<std::string> keys;
  for (const auto& e : bond_law_entries())
    for (const auto& p : e.params) keys.insert(p.key);
  for (const auto& e : bond_failure_entries())
    for (const auto& p : e.params) keys.insert(p.key);
  return {keys.begin(), keys.end()};
}

namespace {
/// The option that sets bond parameter `key` (whichever entry declares it), or the key itself.
std::string option_of(const std::string& key) {
  for (const auto& e : bond_law_entries())
    if (const BondParam* p = e.param(key)) return p->option;
  for (const auto& e : bond_failure_entries())
    if (const BondParam* p = e.param(key)) return p->option;
  return key;
}
}  // namespace

void check_bond_settings(const BondEntry& entry, const std::vector<BondSetting>& settings) {
  for (const BondSetting& s : settings) {
    const BondParam* p = entry.param(s.key);
    if (!p) {
      if (s.given)
        throw InputError("", option_of(s.key), value_text(s.value),
                         entry.what() + " does not take " + s.key + "; it takes " + entry.keys());
      continue;
    }
    if (!s.given) {
      if (p->required())
        throw InputError("", p->option, value_text(s.value),
                         entry.what() + " needs " + p->key + ": " + p->meaning + " (" + p->unit + ", ∈ " +
                             range_of(*p) + ")");
      continue;
    }
    require_range(p->option, s.value, p->lo, p->lo_open, p->hi, p->hi_open, p->meaning);
  }
}

void apply_bond_settings(const BondEntry& entry, const std::vector<BondSetting>& settings, BondLaw& law) {
  for (const BondSetting& s : settings)
    if (const BondParam* p = entry.param(s.key)) *p->ref(law) = s.value;
}

}  // namespace tomodem::dem
