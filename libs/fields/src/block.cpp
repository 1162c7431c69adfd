// Fields from the tools' in-memory states: the fields: block of tomodem-dem (parsing, snapshots
// along the run) and the loaded networks of tomodem-young and tomodem-fracture (docs/cg.md).
#include <omp.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "common.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/dem/bonds.hpp"
#include "tomodem/dem/scene.hpp"
#include "tomodem/dem/simulation.hpp"
#include "tomodem/dem/yaml_fields.hpp"
#include "tomodem/fields/block.hpp"
#include "tomodem/fields/tool.hpp"

namespace tomodem::fields {

using json = nlohmann::json;
namespace fs = std::filesystem;

// ---- the block -------------------------------------------------------------------------------

FieldsBlock parse_fields_block(const std::string& scene_text, const std::string& file) {
  FieldsBlock out;
  try {
    const YAML::Node doc = yaml::load(scene_text, file);
    const yaml::Section root(doc, "", file);
    if (!root.has("fields")) return out;
    const yaml::Section b = root.map("fields");
    out.present = true;
    out.text = b.text("");
    b.allow({"output", "vdb", "kernel", "width", "cutoff", "nodes", "slice", "profile", "quadrature", "every", "from",
             "to", "displacement"});
    FieldsSettings& s = out.settings;
    SettingNames& n = s.names;
    n.file = file;
    n.output = b.where("output");
    n.vdb = b.where("vdb");
    n.kernel = b.where("kernel");
    n.width = b.where("width");
    n.cutoff = b.where("cutoff");
    n.nodes = b.where("nodes");
    n.slice = b.where("slice");
    n.profile = b.where("profile");
    n.quadrature = b.where("quadrature");
    s.output = b.string("output", "");
    if (s.output.empty()) throw b.error("output", "", "missing: the fields file (.h5), e.g. output: fields.h5");
    refuse_output_outside(s.output, "given by --output-dir", file, n.output);
    s.vdb = b.string("vdb", "");
    if (!s.vdb.empty()) refuse_output_outside(s.vdb, "given by --output-dir", file, n.vdb);
    s.kernel = b.string("kernel", s.kernel);
    if (b.has("width")) s.width = b.text("width");
    s.cutoff = b.number("cutoff", s.cutoff);
    if (b.has("nodes")) {
      const YAML::Node nodes = b.raw("nodes");
      if (nodes.IsSequence()) {
        s.nodes.clear();
        for (std::size_t k = 0; k < nodes.size(); ++k) s.nodes += (k ? "," : "") + yaml::text(nodes[k]);
      } else {
        s.nodes = b.text("nodes");
      }
    }
    s.slice = b.string("slice", "");
    s.profile = b.string("profile", "");
    s.quadrature = int(b.integer("quadrature", 0, 0, 16));
    out.every = b.integer("every", 0, 0);
    out.from = b.non_negative("from", 0);
    out.to = b.has("to") ? b.non_negative("to", 0) : out.to;
    if (out.to < out.from)
      throw b.error("to", b.text("to"), "the window ends before it starts (from: " + b.text("from") + ")");
    out.displacement = b.flag("displacement", false);
    check_settings(s);
    // No output of the block may be another of the scene's (output.packing and its sidecar, series, checkpoint).
    const yaml::Section om = root.map("output");
    const std::string packing = om.string("packing", "packing.h5");
    const std::vector<std::string> others = {packing, fs::path(packing).replace_extension(".xdmf").string(),
                                             om.string("series", "series.csv"), om.string("checkpoint", "")};
    for (const auto& [option, path] : output_names(s))
      for (const std::string& o : others)
        if (!o.empty() && fs::path(path).lexically_normal() == fs::path(o).lexically_normal())
          throw InputError(file, option, path, "is also the scene's output " + o + ": choose another name");
  } catch (const YAML::Exception& e) {
    throw yaml::as_input_error(e, file);
  }
  return out;
}

// ---- a DEM state -----------------------------------------------------------------------------

Snapshot snapshot_of(dem::Simulation& sim, const std::vector<Material>& materials, const std::string& file,
                     const Packing* reference) {
  const Packing p = dem::to_packing(sim, materials);
  SnapshotOptions o;
  o.bond_forces = "none";  // the packing carries no bonds; the engine's are added below
  Snapshot s = make_snapshot(p, file, o, reference, file);
  const dem::BondSet& B = sim.bonds();
  if (B.size() == 0) return s;
  const std::vector<dem::BondLaw>& laws = sim.bond_laws();
  const int nph = sim.model().n_phases;
  const auto& P = sim.particles();
  for (std::size_t b = 0; b < B.size(); ++b) {
    if (B.state[b] != dem::BondSet::intact) continue;
    PairForce c;
    c.i = B.i[b], c.j = B.j[b];
    c.branch = P.x[c.j] + sim.cell().h * B.image[b] - P.x[c.i];
    const dem::BondLaw& law = laws[std::size_t(P.phase[c.i] * nph + P.phase[c.j])];
    const double kn = dem::bond_stiffness(law, B.radius[b], P.r[c.i], P.r[c.j]).kn;
    const double len = norm(c.branch);
    // The bond loop's elastic force on j: normal from the rest length, minus the shear force on i
    // (the dashpots are left out: the fields are of the elastic state).
    c.force = (-kn * (len - B.rest_length[b]) / len) * c.branch - B.shear_force[b];
    s.bonds.push_back(c);
  }
  return s;
}

struct DemFields::Impl {
  FieldsBlock block;
  std::string file;
  const std::vector<Material>* materials = nullptr;
  std::unique_ptr<FieldsOutput> out;
  Packing reference;
  double dt = 0;
};

DemFields::DemFields(const FieldsBlock& b, dem::Simulation& sim, const std::vector<Material>& materials,
                     const std::string& file, const std::string& output_path, const std::string& vdb_path)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.block = b;
  m.block.settings.output = output_path;
  m.block.settings.vdb = b.settings.vdb.empty() ? "" : vdb_path;
  m.file = file;
  m.materials = &materials;
  m.dt = sim.time_step();
#if TOMODEM_HAVE_MPI
  if (sim.domain())
    throw InputError(file, "fields", b.settings.output,
                     "the fields block coarse-grains every particle on one rank: run the scene on one rank");
#endif
  if (b.every > 0 && sim.cell_control().active())
    throw InputError(file, "fields.every", std::to_string(b.every),
                     "a time average needs one grid, and this scene deforms its cell: use every: 0 (the final state) "
                     "or coarse-grain packings of the run with tomodem-cg");
  const auto& P = sim.particles();
  if (P.size() == 0) throw InputError(file, "particles", "0", "nothing to coarse-grain");
  double rsum = 0;
  for (double r : P.r) rsum += r;
  const double mean_d = 2 * rsum / double(P.size());
  // Every check of the settings against the cell (width, grid memory) happens here, before any step.
  m.out = std::make_unique<FieldsOutput>(m.block.settings, sim.cell(), mean_d, sim.settings().threads);
  if (b.displacement) m.reference = dem::to_packing(sim, materials);
}
DemFields::~DemFields() = default;

long DemFields::every() const { return impl_->block.every; }

void DemFields::at_step(dem::Simulation& sim) {
  Impl& m = *impl_;
  const double t = sim.time(), tol = 0.5 * m.dt;
  if (t < m.block.from - tol || t > m.block.to + tol) return;
  m.out->add(snapshot_of(sim, *m.materials, m.file, m.block.displacement ? &m.reference : nullptr));
}

std::string DemFields::write(dem::Simulation& sim, const std::string& scene_text) {
  Impl& m = *impl_;
  const FieldsBlock& b = m.block;
  std::string state;
  if (m.out->snapshots() == 0) {
    if (b.every > 0)
      warn("fields: no step of the run (every " + std::to_string(b.every) + " steps) fell in [" + value_text(b.from) +
           ", " + value_text(b.to) + "] s: the final state (t = " + value_text(sim.time()) + " s) is coarse-grained");
    m.out->add(snapshot_of(sim, *m.materials, m.file, b.displacement ? &m.reference : nullptr));
    state = "the final state of the run, step " + std::to_string(sim.step_count()) + ", t = " + value_text(sim.time()) + " s";
  } else {
    state = "time average of " + std::to_string(m.out->snapshots()) + " snapshots, every " + std::to_string(b.every) +
            " steps from t = " + value_text(b.from) + " s to " +
            (std::isfinite(b.to) ? "t = " + value_text(b.to) + " s" : std::string("the end of the run"));
  }
  const FieldsSettings& s = b.settings;
  json params = {{"kernel", s.kernel}, {"width", s.width},   {"cutoff_widths", s.cutoff}, {"nodes", s.nodes},
                 {"slice", s.slice},   {"profile", s.profile}, {"quadrature", s.quadrature}, {"every", b.every},
                 {"from", b.from},     {"to", std::isfinite(b.to) ? json(b.to) : json(nullptr)},
                 {"displacement", b.displacement}, {"vdb", s.vdb}};
  (void)scene_text;
  return m.out->write("tomodem-dem", params.dump(),
                      {{"state", state},
                       {"scene", m.file},
                       {"displacement_reference", b.displacement ? "the state at the start of the run" : "none"}});
}

// ---- a loaded bonded network ---------------------------------------------------------------

Snapshot snapshot_of(const LoadedNetwork& s, const std::string& file) {
  const Packing& p = *s.reference;
  const std::size_t n = p.particles.size(), nb = p.bonds.size();
  if (s.displacement.size() != n || s.force.size() != nb || s.role.size() != nb || s.image.size() != nb)
    throw RuntimeFailure("fields: a loaded network needs one displacement per particle and one force, role and image per bond");
  Snapshot out;
  out.cell = s.cell;
  out.m = particle_masses(p, file);
  out.x.resize(n);
  for (std::size_t i = 0; i < n; ++i) out.x[i] = p.particles.position[i] + s.displacement[i];
  out.u = s.displacement;
  out.h_reference = p.cell.h;
  for (std::size_t b = 0; b < nb; ++b) {
    if (s.role[b] == PairRole::none) continue;
    PairForce c;
    c.i = p.bonds.i[b], c.j = p.bonds.j[b];
    c.branch = out.x[std::size_t(c.j)] + s.cell.h * spatial::as_vector(s.image[b]) - out.x[std::size_t(c.i)];
    c.force = s.force[b];
    (s.role[b] == PairRole::bond ? out.bonds : out.contacts).push_back(c);
  }
  return out;
}

}  // namespace tomodem::fields
