// tomodem-bond and tomodem-young: read, check, compute, write atomically, summarise in JSON.
#include "tomodem/mechanics/tools.hpp"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>

#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/summary.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/mechanics/bounds.hpp"
#include "tomodem/mechanics/isotropic.hpp"
#include "tomodem/spatial/grid.hpp"
#include "fields_output.hpp"

namespace tomodem::mechanics {

using json = nlohmann::json;

namespace {
json finite(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

int phase_index(const Packing& p, const std::string& s, const std::string& field, const std::string& value) {
  for (std::size_t k = 0; k < p.materials.size(); ++k)
    if (p.materials[k].name == s) return int(k);
  try {
    std::size_t used = 0;
    const int k = std::stoi(s, &used);
    const int n = p.materials.empty() ? 1 + (p.particles.size() ? *std::max_element(p.particles.phase.begin(),
                                                                                     p.particles.phase.end())
                                                                : 0)
                                      : int(p.materials.size());
    if (used == s.size() && k >= 0 && k < n) return k;
  } catch (const std::exception&) {
  }
  throw InputError("", field, value, "unknown phase '" + s + "' (a material name or a phase index)");
}

std::pair<int, int> phase_pair(const Packing& p, const std::string& text, const std::string& field) {
  const auto colon = text.find(':');
  if (colon == std::string::npos) throw InputError("", field, text, "expected PHASE_A:PHASE_B");
  return {phase_index(p, text.substr(0, colon), field, text), phase_index(p, text.substr(colon + 1), field, text)};
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  return v[std::size_t(std::lround(q * double(v.size() - 1)))];
}

std::string parameters_text(const json& j) { return j.dump(); }
}  // namespace

namespace {
// Every option of tomodem-bond before anything is read or written.
BondingOptions bonding_options(const BondConfig& c) {
  if (c.output.empty()) throw InputError("", "--output", "", "an output packing is needed");
  BondingOptions o;
  o.rule = c.rule;
  require_range("--gap-tolerance", c.gap_tolerance, 0, false, 1, false,
                "gap / mean radius; a gap wider than a radius is no neck");
  require_range("--neck-ratio", c.neck_ratio, 0, true, 1, false, "a_b / R");
  require_range("--min-neck-ratio", c.min_neck_ratio, 0, true, 1, false, "a_b / R");
  if (o.rule == NeckRule::density || o.rule == NeckRule::sinter)
    require_range("--target-density", c.target_density, 0, true, 1, true, "relative density, for --rule " + std::string(to_string(c.rule)));
  else if (c.target_density != 0)
    require_range("--target-density", c.target_density, 0, true, 1, true, "relative density");
  if (c.threads < 0) throw InputError("", "--threads", std::to_string(c.threads), "must be >= 0");
  // Outputs before any work: none may overwrite an input, nor two share a file.
  check_outputs({c.input, c.sinter_config}, {{"-o", c.output},
                                             {"-o (its .xdmf sidecar)", xdmf_sidecar_of(c.output)},
                                             {"--json", c.json}});
  if (o.rule == NeckRule::sinter && c.sinter_config.empty())
    throw InputError("", "--sinter-config", "", "rule sinter needs a sintering settings file (docs/sintering.md)");
  o.sinter_file = c.sinter_config;
  o.source = c.input;
  o.threads = c.threads > 0 ? c.threads : all_threads();
  o.gap_tolerance = c.gap_tolerance;
  o.neck_ratio = c.neck_ratio;
  o.min_neck_ratio = c.min_neck_ratio;
  o.target_density = c.target_density;
  return o;
}

// --exclude and --pair-ratio name phases, so they are read once the packing is.
void phase_options(const BondConfig& c, const Packing& p, BondingOptions& o) {
  for (const std::string& e : c.exclude) o.excluded.push_back(phase_pair(p, e, "--exclude"));
  for (const std::string& e : c.pair_ratio) {
    const auto eq = e.find('=');
    if (eq == std::string::npos) throw InputError("", "--pair-ratio", e, "expected PHASE_A:PHASE_B=RATIO");
    double r = 0;
    try {
      r = std::stod(e.substr(eq + 1));
    } catch (const std::exception&) {
      throw InputError("", "--pair-ratio", e, "the ratio is not a number");
    }
    if (!(r > 0 && r <= 1)) throw InputError("", "--pair-ratio", e, "the ratio must lie in (0, 1]");
    o.pair_ratio.push_back({phase_pair(p, e.substr(0, eq), "--pair-ratio"), r});
  }
}

json neck_ratio_json(const std::vector<double>& ratio) {
  std::vector<double> hist(10, 0);
  double amin = 1e300, amax = 0, amean = 0;
  for (double a : ratio) {
    amin = std::min(amin, a);
    amax = std::max(amax, a);
    amean += a;
  }
  amean /= double(ratio.size());
  const double width = (amax - amin) / 10;
  for (double a : ratio) hist[std::min<std::size_t>(9, width > 0 ? std::size_t((a - amin) / width) : 0)] += 1;
  return {{"definition", "a_b / R, R = 2 R_i R_j / (R_i + R_j)"},
          {"min", amin},
          {"mean", amean},
          {"max", amax},
          {"p10", quantile(ratio, 0.1)},
          {"p50", quantile(ratio, 0.5)},
          {"p90", quantile(ratio, 0.9)},
          {"histogram", {{"lower", amin}, {"upper", amax}, {"counts", hist}}}};
}

json clusters_json(const Clusters& cl, bool spans) {
  long other_clusters = 0;
  for (std::size_t k = 0; k < cl.size.size(); ++k)
    if (int(k) != cl.main && cl.size[k] > 1) ++other_clusters;
  return {{"count", cl.size.size()},
          {"main_size", cl.main >= 0 ? cl.size[cl.main] : 0},
          {"main_spans_cell", spans},
          {"main_wrap_rank", cl.main >= 0 ? cl.wrap_rank[cl.main] : 0},
          {"spanning_clusters", cl.spanning_clusters},
          {"other_clusters", other_clusters},
          {"isolated_particles", cl.isolated},
          {"particles_outside_main", cl.outside_main}};
}

// The bonded packing's own results and provenance (HDF5 attributes).
void stamp_bonded(Packing& p, const BondConfig& c, const BondingReport& rep, const json& params, bool sinter) {
  p.results = Results{};
  p.results.scalars = {{"n_bonds", double(rep.n_bonds)},
                       {"bonds_per_particle", rep.bonds_per_particle},
                       {"relative_density", rep.relative_density},
                       {"particles_outside_main_cluster", double(rep.clusters.outside_main)}};
  for (const auto& [k, v] : p.results.scalars) p.results.units[k] = "1";
  p.provenance.tool = "tomodem-bond";
  p.provenance.version = version_string();
  p.provenance.parameters = parameters_text(params);
  p.provenance.input_hashes = {{c.input, file_hash(c.input)}};
  if (sinter) p.provenance.input_hashes[c.sinter_config] = file_hash(c.sinter_config);
  p.provenance.created_utc = utc_now();
  p.provenance.wall_time_s = process_wall_time_s();
}
}  // namespace

std::string run_bond(const BondConfig& c) {
  BondingOptions o = bonding_options(c);
  Network net = read_network(c.input);
  Packing& p = net.packing;
  if (p.particles.size() < 2) throw InputError(c.input, "/particles/radius", std::to_string(p.particles.size()), "needs at least two particles");
  // Coincident particles, or one inside another, would get a bond of no length (the hostile
  // review). Deep overlaps alone are legitimate here: the grain spheres of a segmented scan
  // (tomodem-segment --packing) overlap by up to 0.7 of the smaller radius.
  spatial::check_start_overlaps(p.particles.position, p.particles.radius, p.cell, c.input, &p.bonds,
                                "/particles/position", 1.99);
  phase_options(c, p, o);
  if (p.bonds.size()) warn("replacing the " + std::to_string(p.bonds.size()) + " bonds of " + c.input);
  const BondingReport rep = bond_network(net, o);
  if (rep.n_bonds == 0)
    throw InputError(c.input, "/particles", std::to_string(p.particles.size()) + " particles",
                     "no pair is in contact or within the gap tolerance: no bond made (raise --gap-tolerance?)");
  const Clusters& cl = rep.clusters;
  const bool spans = cl.main >= 0 && cl.wrap_rank[cl.main] == 3;
  if (!c.allow_disconnected && !spans)
    throw InputError(c.input, "/bonds", "largest cluster wraps along " + std::to_string(cl.wrap_rank[cl.main]) + " directions",
                     "no bonded cluster spans the periodic cell (--require-spanning)");
  const bool sinter = o.rule == NeckRule::sinter;
  json params = {{"rule", to_string(c.rule)},          {"gap_tolerance", c.gap_tolerance}, {"neck_ratio", c.neck_ratio},
                 {"min_neck_ratio", c.min_neck_ratio}, {"target_density", c.target_density},
                 {"exclude", c.exclude},    {"pair_ratio", c.pair_ratio}};
  if (sinter) params["sinter_config"] = c.sinter_config;
  stamp_bonded(p, c, rep, params, sinter);
  write_network(c.output, net);

  Summary out("tomodem-bond");
  out.input(c.input);
  out.output("packing", c.output);
  out.output("xdmf", xdmf_sidecar_of(c.output));
  out.n_particles(p.particles.size());
  out["parameters"] = params;
  out["n_bonds"] = rep.n_bonds;
  out["bonds_per_particle"] = rep.bonds_per_particle;
  out["relative_density"] = rep.relative_density;
  out["relative_density_pairwise"] = rep.relative_density_pairwise;  // former estimate, comparison only
  out["initial_relative_density"] = rep.initial_relative_density;
  out["densification_scale"] = rep.scale;
  out["neck_ratio"] = neck_ratio_json(rep.neck_ratio);
  const NeckRange nr = neck_range(p);
  out["neck_ratio"]["g_valid_up_to"] = nr.valid_up_to;
  out["neck_ratio"]["beyond_g_range"] = nr.bonds_beyond;
  if (nr.bonds_beyond) warn(neck_range_warning(nr, rep.n_bonds));
  out["clusters"] = clusters_json(cl, spans);
  out.unit("neck_ratio", "1 (a_b / R)");
  out.unit("relative_density", "1");
  if (sinter) {
    out["sintering"] = {{"time_s", rep.sintering_time_s}, {"steps", rep.sintering_steps}};
    out.unit("sintering.time_s", "s");
  }
  return out.text();
}

namespace {
json tensor_json(const Matrix6& C, bool full) {
  json rows = json::array();
  for (int a = 0; a < 6; ++a) {
    json r = json::array();
    for (int b = 0; b < 6; ++b) r.push_back(full || b < 3 ? finite(C[a][b]) : json(nullptr));
    rows.push_back(r);
  }
  return rows;
}
}  // namespace

namespace {
// Every option of tomodem-young, whatever the method: out of range is refused, never ignored.
void check_young_options(const YoungConfig& c) {
  if (c.axis < 0 || c.axis > 2) throw InputError("", "--axis", std::to_string(c.axis), "expected x, y or z");
  require_range("--tolerance", c.implicit.tolerance, 0, true, 1, true, "relative residual");
  if (c.implicit.max_iterations < 0)
    throw InputError("", "--max-iterations", std::to_string(c.implicit.max_iterations), "must be >= 0 (0: automatic)");
  require_range("--strain", c.explicit_.strain, 0, true, 0.05, true, "a small-strain test");
  require_positive("--transits", c.explicit_.transits, "elastic-wave transits of the cell");
  check_bond_damping_ratio(c.explicit_.damping_ratio);
  require_range("--local-damping", c.explicit_.local_damping, 0, false, 1, true, "Cundall local damping");
  require_range("--relax-ratio", c.explicit_.relax_ratio, 0, true, 1, true, "unbalanced-force ratio");
  require_range("--timestep-fraction", c.explicit_.timestep_fraction, 0, true, 1, false, "of the critical step");
  if (c.explicit_.points < 2 || c.explicit_.points > 100000)
    throw InputError("", "--points", std::to_string(c.explicit_.points),
                     "must lie in [2, 100000] (at least 2 measurements are needed)");
  if (c.explicit_.max_steps < 1)
    throw InputError("", "--max-steps", std::to_string(c.explicit_.max_steps), "must be >= 1");
  check_material_overrides(c.youngs_modulus, c.poisson_ratio, c.density);
  check_law_options(c.law);
  if (!c.output_csv.empty() && c.method == YoungMethod::implicit)
    throw InputError("", "--curve", c.output_csv, "the stress-strain curve comes from --method explicit or both");
  fields::check_settings(c.fields);
  std::vector<OutputName> outs = {{"--json", c.json}, {"--curve", c.output_csv}};
  for (const auto& [option, path] : fields::output_names(c.fields)) outs.push_back({option, path});
  check_outputs({c.input}, outs);
}

json implicit_json(const ImplicitResult& ir, double tolerance) {
  return {{"E", ir.E},
          {"nu", ir.nu},
          {"E_axes", ir.E_axes},
          {"nu_axes", ir.nu_axes},
          {"E_error", ir.E_error},
          {"C", tensor_json(ir.C, ir.full_tensor)},
          {"residual", ir.residual},
          {"converged", ir.converged},
          {"solver", to_string(ir.solver)},
          {"predicted_s", {{"ldlt", ir.predicted.ldlt_s}, {"amg", ir.predicted.amg_s}, {"cg", ir.predicted.cg_s}}},
          {"tolerance", tolerance},
          {"iterations", ir.iterations},
          {"multigrid_levels", ir.levels},
          {"operator_complexity", ir.operator_complexity},
          {"setup_s", ir.setup_s},
          {"dofs", ir.dofs},
          {"particles_used", ir.particles_used},
          {"particles_removed", ir.particles_removed},
          {"bonds_used", ir.bonds_used},
          {"bonds_removed", ir.bonds_removed},
          {"prestressed_bonds", ir.prestress_bonds},
          {"assembly_s", ir.assembly_s},
          {"solve_s", ir.solve_s},
          {"wall_time_s", ir.wall_time_s}};
}

json explicit_json(const ExplicitResult& er, const ExplicitOptions& eo) {
  return {{"E", er.E},
          {"nu", er.nu},
          {"E_error", er.E_error},
          {"E_error_spread", er.E_error_spread},
          {"E_error_rate", er.E_error_rate},
          {"E_error_strain", er.E_error_strain},
          {"E_half_time", er.E_half_time},
          {"rate_check", eo.rate_check},
          {"nu_error", er.nu_error},
          {"E_error_lateral", er.E_error_lateral},
          {"nu_error_lateral", er.nu_error_lateral},
          {"nu_error_rate", er.nu_error_rate},
          {"loading", to_string(eo.loading)},
          {"protocol", to_string(eo.protocol)},
          {"strain", eo.strain},
          {"strain_rate", er.strain_rate},
          {"transits", eo.transits},
          {"transit_time_s", er.transit_time},
          {"time_step_s", er.time_step},
          {"steps", er.steps},
          {"max_steps", eo.max_steps},
          {"max_steps_reached", er.max_steps_reached},
          {"inertial_number", er.inertial_number},
          {"unbalanced_force_ratio", er.unbalanced_force_ratio},
          {"lateral_stress_ratio", er.lateral_stress_ratio},
          {"broken_bonds", er.broken_bonds},
          {"curve", {{"strain", er.strain}, {"stress_Pa", er.stress}, {"lateral_strain", er.lateral_strain}}},
          {"wall_time_s", er.wall_time_s}};
}
// The isotropic part of the measured tensor (docs/young.md#isotropic-estimate): Hill's average of
// the six strain cases, or the mean over the three axes with --no-tensor. Its error is E's, the
// largest relative residual of the cases used. Returns E_iso.
double write_isotropic(Summary& out, const ImplicitResult& ir) {
  const AxisAverages ax = axis_averages(ir.C);
  json anisotropy = {{"E_axes_spread", ax.E_spread}, {"A_U", nullptr}};
  double E = ax.E, nu = ax.nu;
  if (ir.full_tensor) {
    const IsotropicAverages h = isotropic_averages(ir.C);
    E = h.E_hill;
    nu = h.nu_hill;
    out["E_voigt"] = finite(h.E_voigt);
    out["E_reuss"] = finite(h.E_reuss);
    out["K_iso"] = finite(h.K_hill);
    out["G_iso"] = finite(h.G_hill);
    anisotropy["A_U"] = finite(h.universal_anisotropy);
    out.unit("E_voigt", "Pa");
    out.unit("E_reuss", "Pa");
    out.unit("K_iso", "Pa");
    out.unit("G_iso", "Pa");
  }
  out["E_iso"] = finite(E);
  out["nu_iso"] = finite(nu);
  out["iso_method"] = ir.full_tensor ? "hill" : "axes";
  out["E_iso_error"] = ir.E_error;
  out["nu_iso_error"] = ir.E_error;  // the relative residual, as E_iso_error
  out.unit("nu_iso_error", "relative");
  out["anisotropy"] = anisotropy;
  out.unit("E_iso", "Pa");
  return E;
}
}  // namespace

std::string run_young(const YoungConfig& c) {
  check_young_options(c);
  const int axis = c.axis;
  Network net = read_network(c.input);
  Packing& p = net.packing;
  if (p.bonds.size() == 0)
    throw InputError(c.input, "/bonds", "missing", "a packing without bonds: make the network with tomodem-bond first");
  override_materials(p, c.youngs_modulus, c.poisson_ratio, c.density);  // every phase
  if (c.fields.requested()) fields::make_setup(c.fields, p.cell, fields::mean_diameter(p));  // before any solve
  const bool want_explicit = c.method != YoungMethod::implicit, want_implicit = c.method != YoungMethod::explicit_test;
  const std::vector<dem::BondLaw> laws = bond_laws(p, c.input, c.law, want_explicit);
  Summary out("tomodem-young");
  out.input(c.input);
  out.n_particles(p.particles.size());
  out["method"] = to_string(c.method);
  out["axis"] = name_of(kAxisNames, c.axis);
  out["n_bonds"] = p.bonds.size();
  ImplicitResult ir;
  ExplicitResult er;
  // One set of bond stiffnesses for the solve, the fields and the summary's neck-law counts.
  const BondStiffnesses stiffness = bond_stiffnesses(p, laws);
  const bool face_cap = std::any_of(laws.begin(), laws.end(), [](const dem::BondLaw& l) { return l.face_cap; });
  out["neck_law"] = {{"law", face_cap ? "face_capped" : "isolated_necks"},
                     {"face_capped_bonds", stiffness.face_capped},
                     {"bonds_without_face", stiffness.no_face}};
  if (want_implicit) {
    ImplicitOptions io = c.implicit;
    io.axis = axis;
    info("implicit: assembling and solving (" + std::string(to_string(io.solver)) + ")");
    ir = solve_implicit(p, net.image, stiffness, io, c.input);
    out["implicit"] = implicit_json(ir, c.implicit.tolerance);
  }
  if (want_explicit) {
    ExplicitOptions eo = c.explicit_;
    eo.axis = axis;
    info("explicit: quasi-static " + std::string(to_string(eo.loading)) + " test (" + to_string(eo.protocol) + ")");
    er = run_explicit(p, net.image, laws, eo, c.input);
    out["explicit"] = explicit_json(er, eo);
    if (!c.output_csv.empty()) {
      std::vector<std::vector<double>> rows;
      for (std::size_t k = 0; k < er.strain.size(); ++k) rows.push_back({er.strain[k], er.lateral_strain[k], er.stress[k]});
      write_text_atomic(c.output_csv, csv_table({"axial_strain", "lateral_strain", "axial_stress_Pa"}, rows));
      out.output("curve", c.output_csv);
    }
  }
  if (c.fields.requested()) {
    out["fields"] = json::parse(young_fields(c.fields, p, net.image, stiffness, c.implicit, axis,
                                             c.explicit_.strain, c.input));
    out.output("fields", c.fields.output);
  }
  const double E = want_implicit ? ir.E : er.E, nu = want_implicit ? ir.nu : er.nu;
  // A modulus that overflowed (constants near the limits of a double) is no result: a summary
  // with E null and E_error 0 would read as an exact answer.
  if (!std::isfinite(E) || !std::isfinite(nu))
    throw NumericalError("young: E = " + value_text(E) + " Pa, nu = " + value_text(nu) + " from " + c.input +
                         ": not finite (material constants or neck sizes beyond what a double can carry?)");
  out["E"] = E;
  out["nu"] = nu;
  out["E_error"] = want_implicit ? ir.E_error : er.E_error;
  out["nu_error"] = want_implicit ? ir.E_error : er.nu_error;  // implicit: the relative residual, as for E
  // The unit tells the report how to combine it: the explicit test's error of nu is absolute.
  out.unit("nu_error", want_implicit ? "relative" : "absolute");
  out["C"] = want_implicit ? tensor_json(ir.C, ir.full_tensor) : json(nullptr);
  if (want_implicit && want_explicit) out["explicit_vs_implicit"] = (er.E - ir.E) / ir.E;
  // E against the Hashin–Shtrikman upper bound at the union-volume density (docs/physics.md#bounds).
  const StiffnessBoundCheck bc = check_stiffness_bound(p, want_implicit ? ir.E : er.E);
  out["relative_density"] = bc.relative_density;
  out["E_over_Es"] = bc.E_over_Es;
  out["hs_upper_E_over_Es"] = bc.hs_upper_E_over_Es;
  out["voigt_E_over_Es"] = bc.voigt_E_over_Es;
  // E_iso against the same bound: it is the estimate the bound is for (an isotropic body).
  const double E_iso = want_implicit ? write_isotropic(out, ir) : std::nan("");
  const double E_iso_over_Es = bc.E_s > 0 ? E_iso / bc.E_s : std::nan("");
  const bool iso_exceeded = E_iso_over_Es > bc.hs_upper_E_over_Es;
  if (want_implicit) out["E_iso_over_Es"] = finite(E_iso_over_Es);
  // Poisson's ratio of a stable isotropic solid lies in [-1, 0.5]; the explicit test can leave it
  // (an overdamped or too fast run), and then it is no answer either.
  const bool nu_outside = nu < -1 || nu > 0.5;
  out["nu_outside_bounds"] = nu_outside;
  if (nu_outside)
    warn("nu = " + value_text(nu) + " lies outside [-1, 0.5], the range of a stable isotropic solid" +
         (want_implicit ? std::string() : ": the explicit test was not quasi-static (see --damping-ratio, --transits)"));
  out["bound_exceeded"] = bc.exceeded || iso_exceeded || nu_outside;
  // An iterative solve stopped by its cap, or an explicit test by --max-steps, gave numbers, but
  // not what was asked (exit 4).
  out["target_reached"] = (!want_implicit || ir.converged) && (!want_explicit || !er.max_steps_reached);
  const NeckRange nr = neck_range(p);
  out["neck_correction"] = {{"valid_up_to", nr.valid_up_to}, {"max_neck_ratio", nr.max_ratio}, {"bonds_beyond", nr.bonds_beyond}};
  if (nr.bonds_beyond) warn(neck_range_warning(nr, long(p.bonds.size())));
  const auto bound_warning = [&](const std::string& name, double over_Es) {
    warn(name + "/E_s = " + value_text(over_Es) + " exceeds the Hashin-Shtrikman upper bound " +
         value_text(bc.hs_upper_E_over_Es) + " of an isotropic porous solid at relative density " +
         value_text(bc.relative_density) + " (docs/young.md#bounds)");
  };
  if (bc.exceeded) bound_warning("E", bc.E_over_Es);
  if (iso_exceeded) bound_warning("E_iso", E_iso_over_Es);
  out.unit("E", "Pa");
  out.unit("C", "Pa (Voigt xx, yy, zz, yz, xz, xy; engineering shear strains)");
  return out.text();
}

}  // namespace tomodem::mechanics
