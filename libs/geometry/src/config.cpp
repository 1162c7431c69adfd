#include "tomodem/geometry/config.hpp"

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/dem/law_registry.hpp"
#include "tomodem/dem/model.hpp"
#include "tomodem/dem/yaml_fields.hpp"

namespace tomodem::geometry {

namespace {
/// Every YAML value is read through yaml::Section (tomodem/dem/yaml_fields.hpp), as in scenes.
using Node = yaml::Section;
void read_config(PackConfig& cfg, const YAML::Node& root, const std::string& path);
}  // namespace

PackConfig load_pack_config(const std::string& path) {
  PackConfig cfg;
  cfg.text = read_input_text(path, "pack config");
  const YAML::Node root = yaml::load(cfg.text, path);
  if (!root || !root.IsMap()) throw InputError(path, "", yaml::text(root), "the config must be a YAML mapping of keys to values");
  try {
    read_config(cfg, root, path);
  } catch (const YAML::Exception& e) {
    throw yaml::as_input_error(e, path);  // a conversion that bypassed yaml::Section
  }
  return cfg;
}

namespace {
void read_config(PackConfig& cfg, const YAML::Node& root, const std::string& path) {
  PackSpec& s = cfg.spec;
  s.source = path;
  const Node r(root, "", path);
  r.allow({"particles", "arrangement", "initial_solid_fraction", "seed", "threads", "phases", "contact", "target", "protocol", "output"});
  const long np = r.integer("particles", 1000, 1);
  s.n_particles = std::size_t(np);
  check_particle_memory(s.n_particles, path, r.where("particles"), r.text("particles"));
  s.arrangement = *parse_arrangement(r.choice("arrangement", to_string(s.arrangement), name_list(kArrangementNames)));
  s.initial_solid_fraction = r.in_range("initial_solid_fraction", s.initial_solid_fraction, 0, 0.4, true, true);
  s.seed = r.seed("seed", 1);
  // Not written: every core, the CLI's default (docs/cli.md); a count the config writes is kept.
  s.threads = r.has("threads") ? int(r.integer("threads", 1, 1, 4096)) : all_threads();
  const YAML::Node phases =
      r.list("phases", 1, "[{name: a, material: {density: 2500, youngs_modulus: 1e8}, size_distribution: {diameter: 1e-3}}]");
  const auto dir = std::filesystem::path(path).parent_path();
  for (std::size_t p = 0; p < phases.size(); ++p) {
    const Node ph = r.item("phases", p);
    ph.allow({"name", "volume_fraction", "material", "size_distribution", "pore_former", "aggregate_size"});
    PhaseSpec spec;
    spec.name = ph.string("name", "phase" + std::to_string(p));
    spec.volume_fraction = ph.in_range("volume_fraction", phases.size() == 1 ? 1.0 : -1.0, 0, 1, false, false);
    if (spec.volume_fraction < 0 && !ph.has("volume_fraction"))
      throw InputError(path, ph.field("volume_fraction"), "", "required when there are several phases");
    spec.pore_former = ph.flag("pore_former", false);
    spec.aggregate_size = int(ph.integer("aggregate_size", 1, 1, 1000000));
    const Node m = ph.map("material");
    m.allow({"youngs_modulus", "poisson_ratio", "density", "surface_energy", "conductivity"});
    spec.material.name = spec.name;
    spec.material.youngs_modulus = m.number("youngs_modulus", 0);
    spec.material.poisson_ratio = m.number("poisson_ratio", 0.3);
    // The same check as a tomodem-dem scene's materials (dem::material_problem); E and the
    // density are required later by validate(), which knows the normal law.
    {
      Material probe = spec.material;
      probe.density = m.number("density", 1);
      const dem::MaterialProblem bad = dem::material_problem(probe, false);
      if (!bad.key.empty()) throw m.error(bad.key, m.text(bad.key), bad.why);
    }
    spec.material.density = m.number("density", 0);
    spec.material.surface_energy = m.number("surface_energy", 0);
    spec.material.conductivity = m.number("conductivity", 0);
    if (!ph.has("size_distribution"))
      throw ph.error("", "", "needs a size_distribution, e.g. {kind: monodisperse, diameter: 1e-3}");
    const Node d = ph.map("size_distribution");
    d.allow({"kind", "diameter", "sigma", "diameter2", "fraction2", "basis", "file", "truncation"});
    const std::string kind = d.string("kind", "monodisperse");
    const std::string basis = d.string("basis", kind == "tabulated" ? "volume" : "number");
    PsdBasis b;
    if (basis == "number") b = PsdBasis::number;
    else if (basis == "volume") b = PsdBasis::volume;
    else throw d.error("basis", basis, "expected number or volume");
    if (kind == "tabulated") {
      if (!d.has("file")) throw d.error("file", "", "a tabulated distribution needs a CSV file");
      std::string f = d.string("file", "");
      if (std::filesystem::path(f).is_relative()) f = (dir / f).string();
      spec.psd = read_psd_csv(f, b);
      cfg.inputs.push_back(f);
    } else {
      if (!parse(kind, spec.psd.kind))
        throw d.error("kind", kind, "expected monodisperse, normal, lognormal, bimodal or tabulated");
      spec.psd.basis = b;
      spec.psd.diameter = d.number("diameter", 0);
      spec.psd.sigma = d.number("sigma", 0);
      spec.psd.diameter2 = d.number("diameter2", 0);
      spec.psd.fraction2 = d.number("fraction2", 0.5);
      spec.psd.truncation = d.number("truncation", 3);
    }
    s.phases.push_back(spec);
  }
  const Node c = r.map("contact");
  c.allow({"normal", "friction", "restitution", "work_of_adhesion", "normal_stiffness", "aggregate_bond_radius",
           "rolling_friction"});
  // The normal laws of the registry that a pack config can give parameters to (law_registry.hpp).
  const auto packable = [](const dem::LawInfo& e) {
    if (e.driven) return false;  // set per step by a driver (sintering: tomodem-sinter)
    for (const auto& p : e.params)
      if (p.required() && std::string(p.key) != "normal_stiffness" && std::string(p.key) != "work_of_adhesion")
        return false;
    return true;
  };
  const std::string law = c.string("normal", "hertz");
  const dem::LawInfo* known = dem::find_law(dem::Slot::normal, law);
  if (!known) throw c.error("normal", law, "unknown normal law; expected " + dem::law_names(dem::Slot::normal, packable));
  if (!packable(*known))
    throw c.error("normal", law,
                  known->driven ? "runs under its driver (tomodem-sinter), not in a packing; expected " +
                                      dem::law_names(dem::Slot::normal, packable)
                                : "takes parameters a pack config does not give (" + known->keys() + "); expected " +
                                      dem::law_names(dem::Slot::normal, packable));
  dem::parse(law, s.normal);
  s.friction = c.non_negative("friction", 0);
  s.rolling_friction = c.non_negative("rolling_friction", 0);
  s.restitution = c.in_range("restitution", s.restitution, dem::kMinRestitution, 1, false, false);
  s.work_of_adhesion = c.non_negative("work_of_adhesion", 0);
  s.normal_stiffness = c.non_negative("normal_stiffness", 0);
  s.aggregate_bond_radius = c.in_range("aggregate_bond_radius", s.aggregate_bond_radius, 0, 1, true, false);
  const Node t = r.map("target");
  t.allow({"pressure", "solid_fraction"});
  if (t.has("pressure") && t.has("solid_fraction"))
    throw InputError(path, "target", "", "give either pressure or solid_fraction, not both");
  if (t.has("solid_fraction"))
    s.target = Target::solid_fraction, s.target_solid_fraction = t.in_range("solid_fraction", 0, 0, 1, true, true);
  else s.target = Target::pressure, s.target_pressure = t.positive("pressure", 0);
  const Node pr = r.map("protocol");
  pr.allow({"method", "strain_rate", "final_strain_rate", "local_damping", "timestep_fraction", "unbalanced_force_ratio", "max_steps", "cell"});
  s.method = *parse_pack_method(pr.choice("method", to_string(s.method), name_list(kPackMethodNames)));
  s.cell_relax = *parse_cell_relax(pr.choice("cell", to_string(s.cell_relax), name_list(kCellRelaxNames)));
  s.strain_rate = pr.non_negative("strain_rate", 0);
  s.final_strain_rate = pr.non_negative("final_strain_rate", 0);
  s.local_damping = pr.in_range("local_damping", s.local_damping, 0, 1, false, true);
  s.timestep_fraction = pr.in_range("timestep_fraction", s.timestep_fraction, 0, 1, true, false);
  s.unbalanced_force_ratio = pr.in_range("unbalanced_force_ratio", s.unbalanced_force_ratio, 0, 1, true, true);
  s.max_steps = pr.integer("max_steps", s.max_steps, 1, 1000000000000000L);
  const Node o = r.map("output");
  o.allow({"packing", "tessellation"});
  cfg.packing = o.string("packing", cfg.packing);
  // The output named in the config: a file next to where the tool runs, not elsewhere.
  if (o.has("packing")) refuse_output_outside(cfg.packing, "where tomodem-pack runs", path, o.where("packing"));
  s.tessellate = o.flag("tessellation", true);
}
}  // namespace

}  // namespace tomodem::geometry
