#include "tomodem/geometry/config.hpp"

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "tomodem/core/error.hpp"

namespace tomodem::geometry {

namespace {
class Node {
 public:
  Node(YAML::Node n, std::string path, const std::string& file) : n_(n), path_(std::move(path)), file_(file) {}
  std::string field(const std::string& k) const { return path_.empty() ? k : path_ + "." + k; }
  std::string where(const std::string& k) const {
    const auto v = n_[k];
    return field(k) + (v && v.Mark().line >= 0 ? " (line " + std::to_string(v.Mark().line + 1) + ")" : "");
  }
  void allow(std::initializer_list<const char*> keys) const {
    if (!n_ || n_.IsNull()) return;
    if (!n_.IsMap()) throw InputError(file_, path_, "", "must be a mapping of keys to values");
    const std::set<std::string> ok(keys.begin(), keys.end());
    for (const auto& kv : n_) {
      const auto k = kv.first.as<std::string>();
      if (!ok.count(k)) {
        std::string list;
        for (const char* a : keys) list += (list.empty() ? "" : ", ") + std::string(a);
        throw InputError(file_, field(k), k, "unknown key; expected one of: " + list);
      }
    }
  }
  bool has(const std::string& k) const { return n_ && n_.IsMap() && n_[k]; }
  Node sub(const std::string& k) const { return Node(has(k) ? n_[k] : YAML::Node(), field(k), file_); }
  std::string text(const std::string& k) const { return n_[k].IsScalar() ? n_[k].as<std::string>() : "<non-scalar>"; }
  double number(const std::string& k, double def) const {
    if (!has(k)) return def;
    try {
      return n_[k].as<double>();
    } catch (const YAML::Exception&) {
      throw InputError(file_, where(k), text(k), "not a number");
    }
  }
  long integer(const std::string& k, long def) const {
    if (!has(k)) return def;
    try {
      return n_[k].as<long>();
    } catch (const YAML::Exception&) {
      throw InputError(file_, where(k), text(k), "not an integer");
    }
  }
  bool boolean(const std::string& k, bool def) const {
    if (!has(k)) return def;
    try {
      return n_[k].as<bool>();
    } catch (const YAML::Exception&) {
      throw InputError(file_, where(k), text(k), "not true/false");
    }
  }
  std::string string(const std::string& k, const std::string& def) const { return has(k) ? text(k) : def; }
  const YAML::Node& raw() const { return n_; }

 private:
  YAML::Node n_;
  std::string path_;
  const std::string& file_;
};
}  // namespace

PackConfig load_pack_config(const std::string& path) {
  PackConfig cfg;
  std::ifstream in(path);
  if (!in) throw InputError(path, "file", path, "cannot be opened for reading");
  std::stringstream ss;
  ss << in.rdbuf();
  cfg.text = ss.str();
  YAML::Node root;
  try {
    root = YAML::Load(cfg.text);
  } catch (const YAML::Exception& e) {
    throw InputError(path, "line " + std::to_string(e.mark.line + 1), "", "not valid YAML: " + e.msg);
  }
  PackSpec& s = cfg.spec;
  s.source = path;
  const Node r(root, "", path);
  r.allow({"particles", "arrangement", "initial_solid_fraction", "seed", "threads", "phases", "contact", "target", "protocol", "output"});
  const long np = r.integer("particles", 1000);
  if (np < 1) throw InputError(path, r.where("particles"), std::to_string(np), "must be >= 1");
  s.n_particles = std::size_t(np);
  s.arrangement = r.string("arrangement", "random");
  s.initial_solid_fraction = r.number("initial_solid_fraction", s.initial_solid_fraction);
  s.seed = uint64_t(r.integer("seed", 1));
  s.threads = int(r.integer("threads", 1));
  if (!r.has("phases") || !root["phases"].IsSequence())
    throw InputError(path, "phases", "", "a list of phases is required (name, volume_fraction, material, size_distribution)");
  const auto dir = std::filesystem::path(path).parent_path();
  for (std::size_t p = 0; p < root["phases"].size(); ++p) {
    const Node ph(root["phases"][p], "phases[" + std::to_string(p) + "]", path);
    ph.allow({"name", "volume_fraction", "material", "size_distribution", "pore_former", "aggregate_size"});
    PhaseSpec spec;
    spec.name = ph.string("name", "phase" + std::to_string(p));
    spec.volume_fraction = ph.number("volume_fraction", root["phases"].size() == 1 ? 1.0 : -1.0);
    if (spec.volume_fraction < 0 && !ph.has("volume_fraction"))
      throw InputError(path, ph.field("volume_fraction"), "", "required when there are several phases");
    spec.pore_former = ph.boolean("pore_former", false);
    spec.aggregate_size = int(ph.integer("aggregate_size", 1));
    const Node m = ph.sub("material");
    m.allow({"youngs_modulus", "poisson_ratio", "density", "surface_energy", "conductivity"});
    spec.material.name = spec.name;
    spec.material.youngs_modulus = m.number("youngs_modulus", 0);
    spec.material.poisson_ratio = m.number("poisson_ratio", 0.3);
    spec.material.density = m.number("density", 0);
    spec.material.surface_energy = m.number("surface_energy", 0);
    spec.material.conductivity = m.number("conductivity", 0);
    const Node d = ph.sub("size_distribution");
    if (!ph.has("size_distribution")) throw InputError(path, d.field(""), "", "required");
    d.allow({"kind", "diameter", "sigma", "diameter2", "fraction2", "basis", "file", "truncation"});
    const std::string kind = d.string("kind", "monodisperse");
    const std::string basis = d.string("basis", kind == "tabulated" ? "volume" : "number");
    PsdBasis b;
    if (basis == "number") b = PsdBasis::number;
    else if (basis == "volume") b = PsdBasis::volume;
    else throw InputError(path, d.where("basis"), basis, "expected number or volume");
    if (kind == "tabulated") {
      if (!d.has("file")) throw InputError(path, d.field("file"), "", "a tabulated distribution needs a CSV file");
      std::string f = d.string("file", "");
      if (std::filesystem::path(f).is_relative()) f = (dir / f).string();
      spec.psd = read_psd_csv(f, b);
      cfg.inputs.push_back(f);
    } else {
      if (!parse(kind, spec.psd.kind))
        throw InputError(path, d.where("kind"), kind, "expected monodisperse, normal, lognormal, bimodal or tabulated");
      spec.psd.basis = b;
      spec.psd.diameter = d.number("diameter", 0);
      spec.psd.sigma = d.number("sigma", 0);
      spec.psd.diameter2 = d.number("diameter2", 0);
      spec.psd.fraction2 = d.number("fraction2", 0.5);
      spec.psd.truncation = d.number("truncation", 3);
    }
    s.phases.push_back(spec);
  }
  const Node c = r.sub("contact");
  c.allow({"normal", "friction", "restitution", "work_of_adhesion", "normal_stiffness", "aggregate_bond_radius",
           "rolling_friction"});
  const std::string law = c.string("normal", "hertz");
  if (!dem::parse(law, s.normal)) {
    if (law == "dmt") s.normal = dem::NormalLaw::hertz_dmt;
    else if (law == "jkr") s.normal = dem::NormalLaw::hertz_jkr;
    else throw InputError(path, c.where("normal"), law, "expected linear, hertz, dmt or jkr");
  }
  s.friction = c.number("friction", 0);
  s.rolling_friction = c.number("rolling_friction", 0);
  s.restitution = c.number("restitution", s.restitution);
  if (!(s.restitution > 0 && s.restitution <= 1)) throw InputError(path, c.field("restitution"), std::to_string(s.restitution), "must lie in (0, 1]");
  s.work_of_adhesion = c.number("work_of_adhesion", 0);
  s.normal_stiffness = c.number("normal_stiffness", 0);
  s.aggregate_bond_radius = c.number("aggregate_bond_radius", s.aggregate_bond_radius);
  if (!(s.aggregate_bond_radius > 0 && s.aggregate_bond_radius <= 1))
    throw InputError(path, c.where("aggregate_bond_radius"), std::to_string(s.aggregate_bond_radius),
                     "must lie in (0, 1] (fraction of the smaller radius)");
  const Node t = r.sub("target");
  t.allow({"pressure", "solid_fraction"});
  if (t.has("pressure") && t.has("solid_fraction"))
    throw InputError(path, "target", "", "give either pressure or solid_fraction, not both");
  if (t.has("solid_fraction")) s.target = Target::solid_fraction, s.target_solid_fraction = t.number("solid_fraction", 0);
  else s.target = Target::pressure, s.target_pressure = t.number("pressure", 0);
  const Node pr = r.sub("protocol");
  pr.allow({"method", "strain_rate", "final_strain_rate", "local_damping", "timestep_fraction", "unbalanced_force_ratio", "max_steps"});
  s.method = pr.string("method", s.method);
  if (s.method != "quasistatic" && s.method != "dynamic")
    throw InputError(path, pr.where("method"), s.method, "expected quasistatic or dynamic");
  s.strain_rate = pr.number("strain_rate", 0);
  s.final_strain_rate = pr.number("final_strain_rate", 0);
  s.local_damping = pr.number("local_damping", s.local_damping);
  s.timestep_fraction = pr.number("timestep_fraction", s.timestep_fraction);
  s.unbalanced_force_ratio = pr.number("unbalanced_force_ratio", s.unbalanced_force_ratio);
  s.max_steps = pr.integer("max_steps", s.max_steps);
  const Node o = r.sub("output");
  o.allow({"packing", "tessellation"});
  cfg.packing = o.string("packing", cfg.packing);
  s.tessellate = o.boolean("tessellation", true);
  return cfg;
}

}  // namespace tomodem::geometry
