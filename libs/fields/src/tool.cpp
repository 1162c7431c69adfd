// tomodem-cg: options, inputs, the coarse-graining, outputs and the JSON summary (docs/cg.md).
#include "tomodem/fields/tool.hpp"

#include <omp.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "geometry.hpp"
#include "common.hpp"
#include "output.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/h5.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/packing_io.hpp"
#include "tomodem/core/summary.hpp"
#include "tomodem/core/units.hpp"
#include "tomodem/core/tool.hpp"

namespace tomodem::fields {

using json = nlohmann::json;

namespace {
json mat_json(const Mat3& m) {
  json r = json::array();
  for (int i = 0; i < 3; ++i) r.push_back({m(i, 0), m(i, 1), m(i, 2)});
  return r;
}
json finite(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

/// Optional datasets the packing reader does not know: /bonds/image and /bonds/force.
SnapshotOptions optional_bond_data(const std::string& file, const Packing& p, const CgConfig& c) {
  SnapshotOptions o;
  o.density = c.density;
  o.bond_forces = c.bond_forces;
  if (p.bonds.size() == 0) return o;
  h5::File f(file, h5::File::Mode::read);
  const std::size_t nb = p.bonds.size();
  if (f.exists("/bonds/image")) {
    std::vector<std::size_t> dims;
    const auto v = f.read_int32("/bonds/image", &dims);
    if (dims.size() != 2 || dims[0] != nb || dims[1] != 3)
      throw InputError(file, "/bonds/image", std::to_string(v.size()) + " values", "expected shape (" +
                                                                                      std::to_string(nb) + ", 3)");
    for (std::size_t b = 0; b < nb; ++b) o.bond_image.push_back({v[3 * b], v[3 * b + 1], v[3 * b + 2]});
  }
  if (f.exists("/bonds/force") && c.bond_forces != "none" && c.bond_forces != "stretch") {
    std::vector<std::size_t> dims;
    const auto v = f.read_double("/bonds/force", &dims);
    if (dims.size() != 2 || dims[0] != nb || dims[1] != 3)
      throw InputError(file, "/bonds/force", std::to_string(v.size()) + " values",
                       "expected shape (" + std::to_string(nb) + ", 3): the force on j from i per bond");
    for (std::size_t b = 0; b < nb; ++b) {
      o.stored_bond_force.push_back({v[3 * b], v[3 * b + 1], v[3 * b + 2]});
      if (!std::isfinite(v[3 * b]) || !std::isfinite(v[3 * b + 1]) || !std::isfinite(v[3 * b + 2]))
        throw InputError(file, "/bonds/force[" + std::to_string(b) + "]", "nan", "bond forces must be finite");
    }
  }
  return o;
}

/// A packing, or a clear refusal of a checkpoint (no contact forces stored: the engine recomputes them).
Packing read_snapshot(const std::string& file) {
  {
    h5::File f(file, h5::File::Mode::read);
    if (f.has_attr("/", "tomodem_checkpoint_format"))
      throw InputError(file, "/", "a tomodem-dem checkpoint",
                       "checkpoints hold no contact forces (the engine recomputes them); coarse-grain the packing "
                       "the run writes (output.packing)");
  }
  Packing p = read_packing(file);
  const std::size_t nc = p.contacts.size();
  for (std::size_t c = 0; c < nc; ++c) {
    const Vec3 F = p.contacts.normal_force[c] + p.contacts.tangential_force[c];
    if (!std::isfinite(F.x) || !std::isfinite(F.y) || !std::isfinite(F.z))
      throw InputError(file, "/contacts/normal_force[" + std::to_string(c) + "]", "non-finite", "contact forces must be finite");
  }
  for (std::size_t i = 0; i < p.particles.velocity.size(); ++i) {
    const Vec3 v = p.particles.velocity[i];
    if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
      throw InputError(file, "/particles/velocity[" + std::to_string(i) + "]", "non-finite", "velocities must be finite");
  }
  return p;
}

void same_cell(const Cell& a, const Cell& b, const std::string& file) {
  double scale = 0, diff = 0;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) scale = std::max(scale, std::abs(a.h(r, c))), diff = std::max(diff, std::abs(a.h(r, c) - b.h(r, c)));
  diff = std::max(diff, norm(a.origin - b.origin));
  bool periodic_same = true;
  for (int k = 0; k < 3; ++k) periodic_same = periodic_same && a.periodic[k] == b.periodic[k];
  if (diff > 1e-9 * scale || !periodic_same)
    throw InputError(file, "/cell/h", "differs by " + value_text(diff) + " m",
                     "a time average needs one cell: every snapshot must have the first one's cell");
}
}  // namespace

namespace {
/// tomodem-cg's options as the settings every fields output shares.
FieldsSettings settings_of(const CgConfig& c) {
  FieldsSettings s;
  s.output = c.output;
  s.vdb = c.vdb;
  s.kernel = c.kernel;
  s.width = c.width;
  s.cutoff = c.cutoff;
  s.nodes = c.grid;
  s.slice = c.slice;
  s.profile = c.profile;
  s.quadrature = c.quadrature;
  return s;
}
}  // namespace

std::string run_cg(const CgConfig& c) {
  if (!c.compare_image.empty()) return run_compare_image(c);
  if (c.inputs.empty()) throw InputError("", "input", "", "at least one packing is needed");
  if (c.output.empty()) throw InputError("", "-o", "", "an output file (.h5) is needed");
  if (c.bond_forces != "auto" && c.bond_forces != "stored" && c.bond_forces != "stretch" && c.bond_forces != "none")
    throw InputError("", "--bond-forces", c.bond_forces, "expected auto, stored, stretch or none");
  if (c.density != 0) require_positive("--density", c.density, "kg/m^3");
  const FieldsSettings settings = settings_of(c);
  check_settings(settings);
  std::vector<std::string> all_inputs = c.inputs;
  if (!c.reference.empty()) all_inputs.push_back(c.reference);
  std::vector<OutputName> outputs = {{"--json", c.json}};
  for (const auto& [option, path] : output_names(settings)) outputs.push_back({option, path});
  check_outputs(all_inputs, outputs);
  std::vector<std::string> warnings;
  Packing first = read_snapshot(c.inputs.front());
  const std::string& file = c.inputs.front();
  if (first.particles.size() == 0) throw InputError(file, "/particles/radius", "0 particles", "nothing to coarse-grain");
  if (std::abs(first.cell.h.det()) <= 0 || !std::isfinite(first.cell.h.det()))
    throw InputError(file, "/cell/h", value_text(first.cell.h.det()) + " m^3", "the cell must have a positive volume");
  const FieldsSetup s = make_setup(settings, first.cell, mean_diameter(first));
  Packing reference;
  if (!c.reference.empty()) reference = read_snapshot(c.reference);
  // Every snapshot is read and checked before the grid is allocated.
  std::vector<Packing> rest;
  for (std::size_t k = 1; k < c.inputs.size(); ++k) {
    rest.push_back(read_snapshot(c.inputs[k]));
    same_cell(first.cell, rest.back().cell, c.inputs[k]);
  }
  const int threads = c.threads > 0 ? c.threads : omp_get_max_threads();
  Accumulator acc(s.kernel, s.grid, first.cell, c.quadrature, threads);
  double mass = 0;
  Mat3 love;
  std::size_t n_contacts = 0, n_bonds = 0;
  std::string bond_source;
  for (std::size_t k = 0; k < c.inputs.size(); ++k) {
    const Packing& p = k == 0 ? first : rest[k - 1];
    const Snapshot snap = make_snapshot(p, c.inputs[k], optional_bond_data(c.inputs[k], p, c),
                                        c.reference.empty() ? nullptr : &reference, c.reference, &bond_source);
    info("coarse-graining " + c.inputs[k] + ": " + std::to_string(snap.x.size()) + " particles, " +
         std::to_string(snap.contacts.size()) + " contacts, " + std::to_string(snap.bonds.size()) + " bonds");
    for (double m : snap.m) mass += m / double(c.inputs.size());
    Mat3 l = detail::love_static(snap);
    l *= 1.0 / double(c.inputs.size());
    love += l;
    n_contacts += snap.contacts.size(), n_bonds += snap.bonds.size();
    acc.add(snap);
  }
  if (first.bonds.size() && bond_source == "none") {
    warnings.push_back("bond stress left out: " + c.inputs.front() +
                       " has bonds but neither /bonds/force nor materials to compute their stretch force");
    warn(warnings.back());
  }
  const Accumulator::Fields f = acc.fields();
  const detail::Diagnostics d = detail::diagnose(f, s.grid.kind, mass, s.width);
  json params = {{"kernel", c.kernel}, {"width", c.width}, {"cutoff_widths", c.cutoff}, {"grid", c.grid},
                 {"slice", c.slice},   {"profile", c.profile}, {"quadrature", c.quadrature},
                 {"density", c.density}, {"bond_forces", c.bond_forces}, {"reference", c.reference}};
  if (!c.vdb.empty()) params["vdb"] = c.vdb;
  const std::vector<std::pair<std::string, std::string>> root = {
      {"tool", "tomodem-cg"}, {"version", version_string()}, {"parameters", params.dump()}, {"created_utc", utc_now()}};
  // The VDB first: when it fails, no fields file is left either.
  if (!c.vdb.empty()) detail::write_vdb(c.vdb, f, first.cell, root);
  try {
    detail::write_fields(c.output, f, s.grid.kind, s.grid.axis, root);
  } catch (...) {
    if (!c.vdb.empty()) std::filesystem::remove(c.vdb);
    throw;
  }
  double love_norm = 0, diff = 0;
  for (int i = 0; i < 9; ++i)
    love_norm += love.a[i / 3][i % 3] * love.a[i / 3][i % 3],
        diff += std::pow(love.a[i / 3][i % 3] - d.mean_static.a[i / 3][i % 3], 2);
  Summary out("tomodem-cg");
  out.input(c.inputs.front(), {{"snapshots", c.inputs}, {"reference", c.reference}});
  out.output("fields", c.output);
  out.output("xdmf", xdmf_sidecar_of(c.output));
  if (!c.vdb.empty()) out.output("vdb", c.vdb);
  out.n_particles(first.particles.size());
  out["parameters"] = params;
  out["grid"] = s.grid.kind == GridSpec::Kind::full ? "full" : s.grid.kind == GridSpec::Kind::slice ? "slice" : "profile";
  out["dims"] = f.dims;
  out["n_points"] = f.points.size();
  out["kernel"] = s.kernel.name();
  out["width_m"] = s.width;
  out["width_mean_diameters"] = s.width / s.mean_diameter;
  out["cutoff_m"] = s.kernel.cutoff;
  out["mean_diameter_m"] = s.mean_diameter;
  out["quadrature_points_max"] = acc.max_quadrature();
  out["snapshots"] = c.inputs.size();
  out["n_contacts"] = n_contacts;
  out["n_bonds"] = n_bonds;
  out["bond_forces"] = bond_source.empty() ? "none" : bond_source;
  out["total_mass_kg"] = mass;
  out["mass_error"] = finite(d.mass_error);
  out["divergence_residual"] = finite(d.divergence_residual);
  out["love_static_stress_Pa"] = mat_json(love);
  if (s.grid.kind == GridSpec::Kind::full) {
    out["cg_mean_static_stress_Pa"] = mat_json(d.mean_static);
    out["mean_stress_difference"] = love_norm > 0 ? json(std::sqrt(diff / love_norm)) : json(nullptr);
  }
  out["warnings"] = warnings;
  out["threads"] = threads;
  out.unit("mass_error", "1 (relative)");
  out.unit("divergence_residual", "1 (|div sigma| w / |sigma|)");
  out.unit("mean_stress_difference", "1 (relative, Frobenius)");
  const std::string text = out.text();
  return text;
}

}  // namespace tomodem::fields
