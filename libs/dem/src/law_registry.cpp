// The registry entries, built from the laws' own declarations (law_list.hpp), and what is read
// from them: names for messages, the chosen laws of a model, the docs table.
#include "tomodem/dem/law_registry.hpp"

#include <cmath>
#include <set>
#include <sstream>
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
  std::string out;
  for (std::size_t k = 0; k < names.size(); ++k)
    out += (k == 0 ? "" : (k + 1 == names.size() ? " or " : ", ")) + names[k];
  return out;
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
  return s.str();
}

}  // namespace tomodem::dem
