// tomodem-cg: options, inputs, the coarse-graining, outputs and the JSON summary (docs/cg.md).
#include "tomodem/fields/tool.hpp"

#include <omp.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "geometry.hpp"
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
/// "1.5" or "1.5d" (mean diameters), or a length with a unit ("20um", "0.02mm": the shared
/// parser of docs/cli.md). A bare number is diameters here, unlike plain length options, since a
/// kernel width is chosen against the particle size.
double parse_width(const std::string& text, double mean_d, bool* in_diameters) {
  double v = 0;
  std::string unit;
  if (!split_number_unit(text, v, unit))
    throw InputError("", "--width", text, "expected a number of mean diameters or a length with a unit (20um)");
  while (!unit.empty() && unit.front() == ' ') unit.erase(unit.begin());
  *in_diameters = unit.empty() || unit == "d" || unit == "D";
  if (!*in_diameters) v = parse_length("--width", text);
  require_positive("--width", v, *in_diameters ? "mean diameters" : "length");
  return *in_diameters ? v * mean_d : v;
}

int parse_axis(const std::string& s, const std::string& option, const std::string& text) {
  if (s == "x" || s == "0") return 0;
  if (s == "y" || s == "1") return 1;
  if (s == "z" || s == "2") return 2;
  throw InputError("", option, text, "expected the cell vector x, y or z");
}

GridSpec parse_grid(const CgConfig& c, const Cell& cell, double width) {
  GridSpec g;
  if (!c.slice.empty() && !c.profile.empty())
    throw InputError("", "--slice", c.slice, "--slice and --profile exclude each other");
  if (!c.slice.empty()) {
    const auto eq = c.slice.find('=');
    if (eq == std::string::npos) throw InputError("", "--slice", c.slice, "expected AXIS=FRACTION, e.g. z=0.5");
    g.kind = GridSpec::Kind::slice;
    g.axis = parse_axis(c.slice.substr(0, eq), "--slice", c.slice);
    try {
      g.fraction = std::stod(c.slice.substr(eq + 1));
    } catch (const std::exception&) {
      throw InputError("", "--slice", c.slice, "the fraction is not a number");
    }
    require_range("--slice", g.fraction, 0, false, 1, false, "fraction of the cell vector");
  } else if (!c.profile.empty()) {
    g.kind = GridSpec::Kind::profile;
    g.axis = parse_axis(c.profile, "--profile", c.profile);
  }
  // Automatic: a node every half width, so the kernel is sampled at two or more nodes per width.
  for (int a = 0; a < 3; ++a)
    g.n[a] = int(std::min(1e6, std::max(1.0, std::ceil(detail::plane_distance(cell, a) / (0.5 * width)))));
  if (!c.grid.empty()) {
    std::vector<double> v;
    std::size_t pos = 0;
    while (pos <= c.grid.size()) {
      const auto comma = c.grid.find(',', pos);
      const std::string part = c.grid.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos);
      double x = 0;
      std::size_t used = 0;
      try {
        x = std::stod(part, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used != part.size() || part.empty() || !(x >= 1) || x != std::floor(x) || x > 1e9)
        throw InputError("", "--nodes", c.grid, "expected N or NX,NY,NZ: whole numbers of nodes >= 1");
      v.push_back(x);
      if (comma == std::string::npos) break;
      pos = comma + 1;
    }
    if (v.size() != 1 && v.size() != 3) throw InputError("", "--nodes", c.grid, "expected one or three counts");
    for (int a = 0; a < 3; ++a) g.n[a] = int(v.size() == 1 ? v[0] : v[a]);
  }
  if (g.kind == GridSpec::Kind::slice) g.n[g.axis] = 1;
  return g;
}

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
struct Diagnostics {
  double mass_error = NAN, divergence_residual = NAN, stress_scale = 0;
  Mat3 mean_static;  ///< grid mean of σ_contact + σ_bond (full grids)
};

Diagnostics diagnose(const Accumulator::Fields& f, GridSpec::Kind kind, double total_mass, double width) {
  Diagnostics d;
  const std::size_t N = f.points.size();
  if (f.node_volume > 0 && total_mass > 0) {
    double mass = 0;
    for (double rho : f.density) mass += rho * f.node_volume;
    d.mass_error = (mass - total_mass) / total_mass;
  }
  // ‖∇·σ‖ against ‖σ‖/w over the nodes whose kernel stays inside the body (no wall forces there).
  double div2 = 0, sig2 = 0;
  std::size_t n = 0;
  for (std::size_t k = 0; k < N; ++k) {
    for (int c = 0; c < 9; ++c) {
      const double s = f.stress_contact[9 * k + c] + f.stress_bond[9 * k + c];
      if (kind == GridSpec::Kind::full) d.mean_static.a[c / 3][c % 3] += s / double(N);
      if (f.interior[k]) sig2 += s * s;
    }
    if (f.interior[k]) div2 += norm2(f.divergence[k]), ++n;
  }
  if (n && sig2 > 0) {
    d.stress_scale = std::sqrt(sig2 / double(n));
    d.divergence_residual = std::sqrt(div2 / double(n)) * width / d.stress_scale;
  }
  return d;
}

/// Love-Weber static stress -(1/V) Σ F⊗d of one snapshot (docs/physics.md#stress-and-measurements).
Mat3 love_static(const Snapshot& s) {
  Mat3 m;
  for (const auto* list : {&s.contacts, &s.bonds})
    for (const PairForce& c : *list) m += outer(c.force, c.branch);
  m *= -1 / s.cell.volume();
  return m;
}

struct Setup {
  double mean_d = 0, width = 0;
  bool in_diameters = true;
  Kernel kernel;
  GridSpec grid;
};

Setup setup(const CgConfig& c, const Packing& first, std::vector<std::string>& warnings) {
  Setup s;
  const std::string& file = c.inputs.front();
  if (first.particles.size() == 0) throw InputError(file, "/particles/radius", "0 particles", "nothing to coarse-grain");
  if (std::abs(first.cell.h.det()) <= 0 || !std::isfinite(first.cell.h.det()))
    throw InputError(file, "/cell/h", value_text(first.cell.h.det()) + " m^3", "the cell must have a positive volume");
  s.mean_d = mean_diameter(first);
  s.width = parse_width(c.width, s.mean_d, &s.in_diameters);
  double smallest = 1e300;
  for (int a = 0; a < 3; ++a) smallest = std::min(smallest, detail::plane_distance(first.cell, a));
  if (s.width > smallest)
    throw InputError("", "--width", c.width,
                     "the width " + value_text(s.width) + " m exceeds the cell (smallest extent " + value_text(smallest) +
                         " m): every node would see the cell mean");
  if (s.width < 0.5 * s.mean_d) {
    warnings.push_back("--width " + c.width + " is " + value_text(s.width / s.mean_d) +
                       " mean diameters: below 0.5 the fields resolve single particles, not a continuum");
    warn(warnings.back());
  }
  KernelType type;
  if (c.kernel == "gaussian") type = KernelType::gaussian;
  else if (c.kernel == "lucy") type = KernelType::lucy;
  else throw InputError("", "--kernel", c.kernel, "expected gaussian or lucy");
  require_range("--cutoff", c.cutoff, 2, false, 8, false, "Gaussian cut-off in widths");
  s.kernel = Kernel::make(type, s.width, c.cutoff);
  s.grid = parse_grid(c, first.cell, s.width);
  double points = s.grid.kind == GridSpec::Kind::profile ? s.grid.n[s.grid.axis]
                                                         : double(s.grid.n[0]) * s.grid.n[1] * s.grid.n[2];
  // 34 sums and about 80 output values per node, as doubles.
  check_memory_request(points * 114 * 8, "", "--nodes", c.grid.empty() ? "automatic" : c.grid,
                       "a grid of " + value_text(points) + " nodes");
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
  if (c.quadrature < 0 || c.quadrature > 16)
    throw InputError("", "--quadrature", std::to_string(c.quadrature), "expected 0 (automatic) to 16");
  std::vector<std::string> all_inputs = c.inputs;
  if (!c.reference.empty()) all_inputs.push_back(c.reference);
  check_outputs(all_inputs, {{"-o", c.output}, {"-o (its .xdmf sidecar)", xdmf_sidecar_of(c.output)}, {"--json", c.json}});
  std::vector<std::string> warnings;
  Packing first = read_snapshot(c.inputs.front());
  const Setup s = setup(c, first, warnings);
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
    Mat3 l = love_static(snap);
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
  const Diagnostics d = diagnose(f, s.grid.kind, mass, s.width);
  json params = {{"kernel", c.kernel}, {"width", c.width}, {"cutoff_widths", c.cutoff}, {"grid", c.grid},
                 {"slice", c.slice},   {"profile", c.profile}, {"quadrature", c.quadrature},
                 {"density", c.density}, {"bond_forces", c.bond_forces}, {"reference", c.reference}};
  detail::write_fields(c.output, f, s.grid.kind, s.grid.axis,
                       {{"tool", "tomodem-cg"}, {"version", version_string()}, {"parameters", params.dump()},
                        {"created_utc", utc_now()}});
  double love_norm = 0, diff = 0;
  for (int i = 0; i < 9; ++i)
    love_norm += love.a[i / 3][i % 3] * love.a[i / 3][i % 3],
        diff += std::pow(love.a[i / 3][i % 3] - d.mean_static.a[i / 3][i % 3], 2);
  Summary out("tomodem-cg");
  out.input(c.inputs.front(), {{"snapshots", c.inputs}, {"reference", c.reference}});
  out.output("fields", c.output);
  out.output("xdmf", xdmf_sidecar_of(c.output));
  out.n_particles(first.particles.size());
  out["parameters"] = params;
  out["grid"] = s.grid.kind == GridSpec::Kind::full ? "full" : s.grid.kind == GridSpec::Kind::slice ? "slice" : "profile";
  out["dims"] = f.dims;
  out["n_points"] = f.points.size();
  out["kernel"] = s.kernel.name();
  out["width_m"] = s.width;
  out["width_mean_diameters"] = s.width / s.mean_d;
  out["cutoff_m"] = s.kernel.cutoff;
  out["mean_diameter_m"] = s.mean_d;
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
