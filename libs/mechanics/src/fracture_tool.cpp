// tomodem-fracture: read, check every input before any output, run the chosen methods, write the
// curve (CSV, plot), the broken-bond map (HDF5 + XDMF for ParaView) and the JSON summary.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "tomodem/core/error.hpp"
#include "tomodem/core/h5.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/packing_io.hpp"
#include "tomodem/core/plot.hpp"
#include "tomodem/core/summary.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/mechanics/fracture.hpp"
#include "tomodem/mechanics/size_effect.hpp"
#include "fields_output.hpp"

namespace tomodem::mechanics {

MeanSem mean_sem(const std::vector<double>& v) {
  const double n = double(v.size());
  MeanSem m;
  for (double x : v) m.mean += x;
  m.mean /= n;
  double ss = 0;
  for (double x : v) ss += (x - m.mean) * (x - m.mean);
  m.sd = v.size() > 1 ? std::sqrt(ss / (n - 1)) : 0.0;
  m.sem = m.sd / std::sqrt(n);
  return m;
}

using json = nlohmann::json;

namespace {

json finite(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

std::string stem_of(const std::string& path) {
  const auto slash = path.find_last_of('/');
  const auto dot = path.find_last_of('.');
  const bool ext = dot != std::string::npos && (slash == std::string::npos || dot > slash + 1);
  return ext ? path.substr(0, dot) : path;
}

std::string curve_csv(const FractureResult& r) {
  std::vector<std::vector<double>> rows;
  for (const FracturePoint& c : r.curve) rows.push_back({c.displacement, c.force, double(c.broken)});
  return csv_table({"opening_m", "force_N", "broken_bonds"}, rows);
}

/// Bond states in the map: 0 intact, 1 broken in tension, 2 broken in shear, 3 pre-crack.
void write_map(const std::string& path, const FractureSample& s, const FractureResult& r) {
  const Packing& p = s.packing;
  const std::size_t n = p.particles.size();
  std::vector<int32_t> state(p.bonds.size(), -1), order(p.bonds.size(), -1);
  std::vector<double> opening_at(p.bonds.size(), std::nan("")), force_at(p.bonds.size(), std::nan(""));
  for (std::size_t b = 0; b < p.bonds.size(); ++b) {
    if (s.bond_role[b] == BondRole::load) state[b] = 0;
    if (s.bond_role[b] == BondRole::precrack) state[b] = 3;
  }
  std::vector<int32_t> per_particle(n, 0);
  for (std::size_t e = 0; e < r.events.size(); ++e) {
    const std::size_t b = std::size_t(r.events[e].bond);
    state[b] = r.events[e].mode == dem::BondSet::shear ? 2 : 1;
    order[b] = int32_t(e);
    opening_at[b] = r.events[e].displacement;  // the loading step at which the bond broke
    force_at[b] = r.events[e].force;
    ++per_particle[std::size_t(p.bonds.i[b])];
    ++per_particle[std::size_t(p.bonds.j[b])];
  }
  std::vector<double> pos, rad, pts;
  std::vector<int32_t> role, st, ord, conn;
  std::vector<double> brad, bopen, bforce;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3& x = p.particles.position[i];
    pos.insert(pos.end(), {x.x, x.y, x.z});
    rad.push_back(p.particles.radius[i]);
    role.push_back(int32_t(s.role[i]));
  }
  for (std::size_t b = 0; b < p.bonds.size(); ++b) {
    if (state[b] < 0) continue;
    const Vec3 xi = p.particles.position[std::size_t(p.bonds.i[b])];
    const Vec3 xj = xi + bond_vector(p, s.image[b], b);  // the image of j: bonds across y stay short
    const int32_t k = int32_t(pts.size() / 3);
    pts.insert(pts.end(), {xi.x, xi.y, xi.z, xj.x, xj.y, xj.z});
    conn.insert(conn.end(), {k, k + 1});
    st.push_back(state[b]);
    ord.push_back(order[b]);
    brad.push_back(p.bonds.radius[b]);
    bopen.push_back(opening_at[b]);
    bforce.push_back(force_at[b]);
  }
  const std::string tmp = temporary_path(path);
  try {
    h5::File f(tmp, h5::File::Mode::create);
    f.write("/particles/position", pos, {n, 3}, "m");
    f.write("/particles/radius", rad, {}, "m");
    f.write("/particles/role", role);
    f.write("/particles/broken_bonds", per_particle);
    f.write("/bonds/points", pts, {pts.size() / 3, 3}, "m");
    f.write("/bonds/connectivity", conn, {conn.size() / 2, 2});
    f.write("/bonds/state", st);
    f.write("/bonds/break_order", ord);
    f.write("/bonds/radius", brad, {}, "m");
    f.write("/bonds/broken_at_opening", bopen, {}, "m");  // NaN while intact
    f.write("/bonds/force_at_break", bforce, {}, "N");
    f.set_attr("/bonds", "state_codes", "0 intact, 1 broken in tension, 2 broken in shear, 3 pre-crack");
    f.set_attr("/particles", "role_codes", "0 free, 1 bottom grip, 2 top grip, 3 not connected to a grip");
    f.set_attr("/", "method", std::string(to_string(r.method)));
    write_provenance(f);  // units = "m", tool, version, command line, time
    f.close();  // checked: a full disk shows here, before the rename
  } catch (...) {
    discard_and_rethrow(path, tmp);
  }
  commit_output(path);
  const auto slash = path.find_last_of('/');
  const std::string h5 = slash == std::string::npos ? path : path.substr(slash + 1);
  const std::string N = std::to_string(n), M = std::to_string(st.size()), P = std::to_string(pts.size() / 3);
  std::ostringstream x;
  auto item = [&](const std::string& dims, const char* type, int prec, const std::string& ds) {
    x << "        <DataItem Dimensions=\"" << dims << "\" NumberType=\"" << type << "\" Precision=\"" << prec
      << "\" Format=\"HDF\">" << h5 << ":" << ds << "</DataItem>\n";
  };
  auto attr = [&](const char* name, const char* center, const std::string& dims, const std::string& ds) {
    x << "      <Attribute Name=\"" << name << "\" AttributeType=\"Scalar\" Center=\"" << center << "\">\n";
    item(dims, "Int", 4, ds);
    x << "      </Attribute>\n";
  };
  x << "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n<Xdmf Version=\"2.0\">\n  <Domain>\n"
    << "    <Grid Name=\"particles\" GridType=\"Uniform\">\n"
    << "      <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << N << "\" NodesPerElement=\"1\"/>\n"
    << "      <Geometry GeometryType=\"XYZ\">\n";
  item(N + " 3", "Float", 8, "/particles/position");
  x << "      </Geometry>\n      <Attribute Name=\"radius\" AttributeType=\"Scalar\" Center=\"Node\">\n";
  item(N, "Float", 8, "/particles/radius");
  x << "      </Attribute>\n";
  attr("broken_bonds", "Node", N, "/particles/broken_bonds");
  attr("role", "Node", N, "/particles/role");
  x << "    </Grid>\n    <Grid Name=\"bonds\" GridType=\"Uniform\">\n"
    << "      <Topology TopologyType=\"Polyline\" NumberOfElements=\"" << M << "\" NodesPerElement=\"2\">\n";
  item(M + " 2", "Int", 4, "/bonds/connectivity");
  x << "      </Topology>\n      <Geometry GeometryType=\"XYZ\">\n";
  item(P + " 3", "Float", 8, "/bonds/points");
  x << "      </Geometry>\n";
  attr("state", "Cell", M, "/bonds/state");
  attr("break_order", "Cell", M, "/bonds/break_order");
  for (const char* a : {"radius", "broken_at_opening", "force_at_break"}) {
    x << "      <Attribute Name=\"" << a << "\" AttributeType=\"Scalar\" Center=\"Cell\">\n";
    item(M, "Float", 8, std::string("/bonds/") + a);
    x << "      </Attribute>\n";
  }
  x << "    </Grid>\n  </Domain>\n</Xdmf>\n";
  write_text_atomic(stem_of(path) + ".xdmf", x.str());
}

json result_json(const FractureResult& r, const FractureSample& s) {
  json j = {{"K_IC", r.K_IC},
            {"K_IC_error", r.K_IC_error},
            {"peak_stress", r.peak_stress},
            {"peak_force", r.peak_force},
            {"peak_opening", r.peak_displacement},
            {"broken_bonds", r.events.size()},
            {"dissipated_energy", r.dissipated_energy},
            {"broken_bond_energy", r.broken_bond_energy},
            {"crack_area", r.crack_area},
            {"energy_release_rate", r.crack_area > 0 ? finite(r.dissipated_energy / r.crack_area) : json(nullptr)},
            {"work_of_fracture", finite(r.work_of_fracture)},
            {"cut_through", r.cut_through},
            {"stop_reason", r.stop_reason},
            {"wall_time_s", r.wall_time_s}};
  if (r.method == FractureMethod::sla) {
    j["initial_stiffness"] = r.initial_stiffness;
    j["solves"] = r.solves;
    j["factorizations"] = r.factorizations;
    j["fragment_particles_removed"] = r.fragments_removed;
    j["closed_broken_bonds"] = r.closed_broken_bonds;
    j["solver"] = to_string(r.solver);
    j["failure_groups"] = r.failure_groups;
    j["active_set_solves"] = r.active_set_iterations;
    j["solver_setup_s"] = r.solver_setup_s;
    if (r.solver != SlaSolver::ldlt)
      j["cg"] = {{"iterations", r.cg_iterations},
                 {"per_solve", double(r.cg_iterations) / double(std::max(1L, r.solves))},
                 {"largest", r.cg_iterations_max},
                 {"first_cold", r.cg_iterations_fresh},
                 {"multigrid_rebuilds", r.amg_rebuilds}};
  } else {
    j["strain_rate"] = r.strain_rate;
    j["reference_strain"] = r.reference_strain;
    j["transit_time_s"] = r.transit_time;
    j["transits_to_peak"] = r.transits_to_peak;
    j["time_step_s"] = r.time_step;
    j["steps"] = r.steps;
    j["external_work"] = r.external_work;
    j["energy_balance_error"] = r.energy_balance_error;
    j["grip_force_imbalance"] = r.grip_force_imbalance;
    j["max_steps_reached"] = r.max_steps_reached;
  }
  (void)s;
  return j;
}

// Every option first: a bad value stops the run before anything is read or written. Returns the
// failure options with the criterion set.
/// --widths: at least three distinct positive widths (mean diameters).
void check_widths(const FractureConfig& c) {
  if (c.widths.empty()) return;
  std::vector<double> w = c.widths;
  std::sort(w.begin(), w.end());
  std::string text;
  for (double v : c.widths) text += (text.empty() ? "" : ",") + value_text(v);
  if (w.size() < 3 || std::unique(w.begin(), w.end()) != w.end() || !(w[0] > 0) || !std::isfinite(w.back()))
    throw InputError("", "--widths", text, "the size-effect fit needs at least three distinct widths > 0 (mean diameters)");
}

/// The widest window must fit in the network (checked before any run).
void check_widths_fit(const FractureConfig& c, const Network& net, double d) {
  if (c.widths.empty()) return;
  const double w = *std::max_element(c.widths.begin(), c.widths.end()), L = net.packing.cell.h(0, 0);
  if (w * d > L)
    throw InputError(c.input, "--widths", value_text(w), "wider than the network (" + value_text(L / d) + " mean diameters along x)");
}

/// K_IC against the width (SLA): geometrically similar windows of the network (same a/W, same
/// H/W as the largest window that fits), the two fits of size_effect.hpp.
json size_effect_study(const FractureConfig& c, const Network& net, const std::vector<dem::BondLaw>& laws,
                       const FailureOptions& fo, double d) {
  std::vector<double> widths = c.widths;
  std::sort(widths.begin(), widths.end());
  const double Hc = net.packing.cell.h(2, 2);
  const double aspect = std::min(1.0, Hc / (widths.back() * d));  // H/W of every window
  SlaOptions so = c.sla;
  so.stop_fraction = c.stop_fraction;
  std::vector<double> Wm, K, err;
  json rows = json::array();
  for (double w : widths) {
    info("size effect: width " + value_text(w) + " mean diameters");
    const FractureSample sw = make_sample(crop_network(net, w * d, aspect * w * d), c.crack, c.input);
    const FractureResult r = run_sla(sw, laws, fo, so);
    Wm.push_back(sw.W);
    K.push_back(r.K_IC);
    err.push_back(r.K_IC_error);
    rows.push_back({{"W_over_d", sw.W / d}, {"width", sw.W}, {"particles", sw.packing.particles.size()},
                    {"K_IC", r.K_IC}, {"K_IC_error", r.K_IC_error}, {"broken_bonds", r.events.size()},
                    {"wall_time_s", r.wall_time_s}});
  }
  json out = json::parse(size_effect_fits_json(Wm, K, err));
  out["samples"] = rows;
  out["height_over_width"] = aspect;
  return out;
}

/// Several cracks per sample (docs/fracture.md#several-cracks-per-sample): K_IC is the mean over
/// the cracks; its uncertainty combines the standard error of the mean from the spread between
/// cracks with the cracks' own K_IC_error (crack-tip discreteness) propagated to the mean, in
/// quadrature. Returns the `cracks` object; `K`, `rel_error` get the mean and the combined error.
json crack_statistics(const std::vector<FractureResult>& runs, CrackOrientations orientations, double& K,
                      double& rel_error) {
  const double n = double(runs.size());
  double method = 0;
  std::vector<double> values;
  json per = json::array(), per_error = json::array(), per_peak = json::array(), per_broken = json::array();
  json axes = json::array(), shifts = json::array();
  std::map<std::string, std::pair<double, int>> by_axis;  // load axis -> (sum of K_IC, cracks)
  for (std::size_t k = 0; k < runs.size(); ++k) {
    const FractureResult& r = runs[k];
    const std::string axis = crack_load_axis(int(k), orientations);
    axes.push_back(axis);
    shifts.push_back(double(k) / n);
    by_axis[axis].first += r.K_IC;
    ++by_axis[axis].second;
    values.push_back(r.K_IC);
    method += std::pow(r.K_IC_error * r.K_IC, 2);
    per.push_back(r.K_IC), per_error.push_back(r.K_IC_error), per_peak.push_back(r.peak_stress);
    per_broken.push_back(r.events.size());
  }
  const auto [mean, sd, sem] = mean_sem(values);
  const double method_sem = std::sqrt(method) / n;  // Σ (e_k K_k)² / n² : each crack's error, independent
  K = mean;
  rel_error = std::hypot(sem, method_sem) / mean;
  json axis_means = json::object();  // the anisotropy of K_IC (one value with one orientation)
  for (const auto& [axis, total] : by_axis) axis_means[axis] = total.first / total.second;
  return {{"count", runs.size()},          {"orientations", to_string(orientations)},
          {"load_axis", axes},             {"shift", shifts},
          {"mean_by_load_axis", axis_means}, {"K_IC", per},
          {"K_IC_error", per_error},       {"peak_stress", per_peak},
          {"broken_bonds", per_broken},    {"mean", mean},
          {"sd", sd},                      {"cv", sd / mean},
          {"sem", sem},                    {"sem_relative", sem / mean},
          {"method_error", method_sem / mean}, {"combined_error", rel_error}};
}

}  // namespace

std::string size_effect_fits_json(const std::vector<double>& W, const std::vector<double>& K,
                                  const std::vector<double>& rel_error) {
  json out;
  for (SizeEffectLaw law : {SizeEffectLaw::bazant, SizeEffectLaw::linear}) {
    const SizeEffectFit f = fit_size_effect(W, K, rel_error, law);
    out[law == SizeEffectLaw::bazant ? "bazant" : "linear"] = {
        {"K_inf", finite(f.K_inf)}, {"K_inf_error", finite(f.K_inf_error)},
        {law == SizeEffectLaw::bazant ? "W0" : "c", finite(f.length)}, {"length_error", finite(f.length_error)},
        {"chi2", finite(f.chi2)}, {"dof", f.dof}};
  }
  // Bažant's K∞ = 1/sqrt(intercept of 1/K² against 1/W): none when that intercept is not positive,
  // i.e. K_IC grows at least as sqrt(W) over these widths (the small-size branch of the law).
  const bool bazant = out["bazant"]["K_inf"].is_number();
  if (!bazant && W.size() >= 3) {
    const std::string why =
        "no finite large-sample K_IC from Bazant's law: the intercept 1/K_inf^2 of 1/K_IC^2 against 1/W is not "
        "positive (K_IC grows at least as sqrt(W) over these widths); K_inf is the first-order law's";
    out["bazant"]["reason"] = why;
    warn("--widths: " + why);
  }
  const json& chosen = out[bazant ? "bazant" : "linear"];
  out["K_inf"] = chosen["K_inf"];
  out["K_inf_error"] = chosen["K_inf_error"];
  out["K_inf_law"] = bazant ? "bazant" : "linear";
  return out.dump();
}

namespace {

FailureOptions check_fracture_options(const FractureConfig& c) {
  FailureOptions fo = c.failure;
  require_range("--stop-fraction", c.stop_fraction, 0, false, 1, true, "of the peak load");
  // Every option is checked whatever the method and criterion: out of range is refused, never ignored.
  // The criterion's parameters from the registry: one it does not take is refused, not ignored.
  check_failure_options(fo);
  fields::check_settings(c.fields);
  if (c.fields.requested() && c.method == FractureMethod::explicit_test)
    throw InputError("", "--fields", c.fields.output, "the fields are of the SLA's peak load: use --method sla or both");
  {
    const bool centre = c.crack.geometry == CrackGeometry::centre;
    // The geometry factor sets K_IC: beyond the range where its handbook form holds (Tada: 2a/W
    // <= 0.7 centre, a/W <= 0.6 edge, docs/fracture.md) the number would carry an unknown bias.
    const double a = c.crack.a_over_w, amax = centre ? 0.35 : 0.6;
    if (!(std::isfinite(a) && a > 0 && a <= amax))
      throw InputError("", "--a-over-w", value_text(a),
                       "a/W must lie in (0, " + value_text(amax) + "] for " +
                           (centre ? "a centre crack of length 2a (2a/W <= 0.7)" : "an edge notch") +
                           ", where the geometry factor is within 0.5 % of Tada's tables");
  }
  require_non_negative("--grip", c.crack.grip, "m; 0: one mean diameter");
  require_range("--crack-offset", c.crack.plane_offset, -0.5, true, 0.5, true, "fraction of the grip distance");
  if (c.sla.woodbury_bonds < 0 || c.sla.woodbury_bonds > 100000)
    throw InputError("", "--woodbury-bonds", std::to_string(c.sla.woodbury_bonds),
                     "must lie in [0, 100000] (breaks between factorisations)");
  if (c.sla.max_breaks < 1) throw InputError("", "--max-breaks", std::to_string(c.sla.max_breaks), "must be >= 1");
  require_range("--cg-tolerance", c.sla.cg_tolerance, 0, true, 0.01, true, "relative residual of the PCG solves");
  require_range("--event-tolerance", c.sla.event_tolerance, 0, true, 0.2, true, "of the critical opening");
  require_range("--rebuild-factor", c.sla.rebuild_factor, 1, false, 100, true, "x the iterations of a fresh multigrid");
  check_widths(c);
  if (c.cracks < 1 || c.cracks > 100)
    throw InputError("", "--cracks", std::to_string(c.cracks), "must lie in [1, 100] (pre-cracks per sample)");
  if (c.cracks > 1 && c.method == FractureMethod::explicit_test)
    throw InputError("", "--cracks", std::to_string(c.cracks), "the cracks are SLA tests: use --method sla or both");
  require_positive("--transits", c.explicit_.transits, "elastic-wave transits");
  require_non_negative("--strain-rate", c.explicit_.strain_rate, "1/s; 0: from --transits");
  check_bond_damping_ratio(c.explicit_.damping_ratio);
  require_range("--local-damping", c.explicit_.local_damping, 0, false, 1, true, "Cundall local damping");
  require_range("--timestep-fraction", c.explicit_.timestep_fraction, 0, true, 1, false, "of the critical step");
  if (c.explicit_.max_steps < 1)
    throw InputError("", "--max-steps", std::to_string(c.explicit_.max_steps), "must be >= 1");
  check_material_overrides(c.youngs_modulus, c.poisson_ratio, c.density);
  check_law_options(c.law);
  return fo;
}

// Outputs before any work: none may overwrite the input, nor two share a file.
void check_fracture_outputs(const FractureConfig& c) {
  std::vector<OutputName> outs = {{"--json", c.json}, {"--curve", c.curve_csv}};
  if (!c.curve_csv.empty() && c.method == FractureMethod::both)
    outs.push_back({"--curve (its _explicit.csv)", stem_of(c.curve_csv) + "_explicit.csv"});
  if (!c.plot.empty())
    for (const std::string& file : plot_files(c.plot))
      outs.push_back({"--plot (its " + std::filesystem::path(file).extension().string() + ")", file});
  if (!c.map.empty()) {
    outs.push_back({"--map", c.map});
    outs.push_back({"--map (its .xdmf sidecar)", stem_of(c.map) + ".xdmf"});
  }
  for (const auto& [option, path] : fields::output_names(c.fields)) outs.push_back({option, path});
  check_outputs({c.input}, outs);
}

// E and nu of the periodic network (implicit), for the check G = K^2 (1 - nu^2) / E; NaN when
// the network has none (a warning says why).
std::pair<double, double> elastic_constants(const Network& net, const std::vector<dem::BondLaw>& laws,
                                            const std::string& source) {
  try {
    ImplicitOptions io;
    io.full_tensor = false;
    io.axis = 2;
    info("elastic constants of the periodic network (implicit, for G = K^2 (1 - nu^2) / E)");
    const ImplicitResult ir = solve_implicit(net.packing, net.image, bond_stiffnesses(net.packing, laws), io, source);
    return {ir.E, ir.nu};
  } catch (const InputError& e) {
    warn(std::string("no elastic constants: ") + e.what());
  }
  return {std::nan(""), std::nan("")};
}

json sample_json(const FractureSample& s, std::size_t particles) {
  return {{"particles", particles},
          {"particles_removed", s.removed_particles},
          {"bottom_grip", s.bottom_grip},
          {"top_grip", s.top_grip},
          {"precrack_bonds", s.precrack_bonds},
          {"ligament_bonds", s.ligament_bonds},
          {"face_cut_bonds", s.face_cut_bonds},
          {"mean_bond_length", s.mean_bond_length},
          {"crack_plane_z", s.crack_z}};
}

// The results of the primary method (SLA when it ran) as the summary's top-level keys.
void primary_keys(Summary& out, const FractureResult& r, const FractureSample& s, double E, double nu) {
  const double ligament = (s.W - (s.geometry == CrackGeometry::centre ? 2 * s.a : s.a)) * s.B;
  out["geometry"] = to_string(s.geometry);
  out["a_over_W"] = s.a / s.W;
  out["crack_length"] = s.a;
  out["crack_total_length"] = s.geometry == CrackGeometry::centre ? 2 * s.a : s.a;
  out["width"] = s.W;
  out["thickness"] = s.B;
  out["height"] = s.H;
  out["ligament_area"] = ligament;
  out["Y"] = r.Y;
  out["K_IC"] = r.K_IC;
  out["K_IC_error"] = r.K_IC_error;
  out["peak_stress"] = r.peak_stress;
  out["peak_force"] = r.peak_force;
  out["broken_bonds"] = r.events.size();
  out["dissipated_energy"] = r.dissipated_energy;
  out["energy_release_rate"] = r.crack_area > 0 ? finite(r.dissipated_energy / r.crack_area) : json(nullptr);
  out["work_of_fracture"] = finite(r.work_of_fracture);
  out["E"] = finite(E);
  out["nu"] = finite(nu);
  out["G_from_K_IC"] = finite(r.K_IC * r.K_IC * (1 - nu * nu) / E);
  out.unit("K_IC", "Pa m^0.5");
  out.unit("peak_stress", "Pa (load / (W B))");
  out.unit("crack_length", "m (a in K = Y sigma sqrt(pi a))");
  out.unit("energy", "J");
  out.unit("energy_release_rate", "J/m^2");
  out.unit("K_IC_error", "relative");
  out.unit("E", "Pa");
}

// The curve (CSV, plot) and the broken-bond map, each atomic; their names go into the summary.
void write_fracture_outputs(const FractureConfig& c, const FractureSample& s, const FractureResult& sla,
                            const FractureResult& ex, const FractureResult& primary, Summary& out) {
  if (!c.curve_csv.empty()) {
    write_text_atomic(c.curve_csv, curve_csv(primary));
    out.output("curve", c.curve_csv);
    if (!sla.curve.empty() && !ex.curve.empty()) {
      write_text_atomic(stem_of(c.curve_csv) + "_explicit.csv", curve_csv(ex));
      out.output("curve_explicit", stem_of(c.curve_csv) + "_explicit.csv");
    }
  }
  if (!c.plot.empty()) {
    PlotSpec spec;
    spec.title = "tomodem-fracture: " + std::string(to_string(s.geometry)) + " crack, a/W = " + value_text(s.a / s.W);
    spec.xlabel = "grip opening (µm)";
    spec.ylabel = "load (N)";
    for (const FractureResult* r : {&sla, &ex}) {
      if (r->curve.empty()) continue;
      PlotSeries se;
      se.title = r == &sla ? "sequentially linear (SLA events)" : "explicit DEM test";
      // The SLA saw-tooth is drawn as given: each drop a vertical segment at its event opening.
      se.draw = r == &sla ? PlotDraw::lines : PlotDraw::points_and_lines;
      for (const FracturePoint& q : r->curve) se.x.push_back(q.displacement * 1e6), se.y.push_back(q.force);
      spec.series.push_back(se);
    }
    try {
      write_plot(c.plot, spec);
      out.output("plot", plot_files(c.plot));
    } catch (const RuntimeFailure& e) {
      warn(std::string("no plot: ") + e.what());
    }
  }
  if (!c.map.empty()) {
    write_map(c.map, s, primary);
    out.output("map", c.map);
    out.output("map_xdmf", stem_of(c.map) + ".xdmf");
  }
}

}  // namespace

std::string run_fracture(const FractureConfig& c) {
  FailureOptions fo = check_fracture_options(c);
  check_fracture_outputs(c);
  const bool want_sla = c.method != FractureMethod::explicit_test, want_explicit = c.method != FractureMethod::sla;

  Network net = read_network(c.input);
  Packing& p = net.packing;
  if (p.bonds.size() == 0)
    throw InputError(c.input, "/bonds", "missing", "a packing without bonds: make the network with tomodem-bond first");
  override_materials(p, c.youngs_modulus, c.poisson_ratio, c.density);
  std::vector<dem::BondLaw> laws = bond_laws(p, c.input, c.law, want_explicit);
  set_failure(laws, p, fo, c.input);
  const FractureSample s = make_sample(net, c.crack, c.input);
  std::vector<FractureSample> more_cracks;  // cracks 1 .. K-1, cut before any run: bad input stops here
  if (c.cracks > 1 && c.crack_orientations == CrackOrientations::three) {
    // Each axis becomes the load axis in turn: on a slab the turned samples are of other sizes.
    const double Lx = p.cell.h(0, 0), Ly = p.cell.h(1, 1), Lz = p.cell.h(2, 2);
    if (std::max({Lx, Ly, Lz}) > 1.5 * std::min({Lx, Ly, Lz}))
      warn("--cracks " + std::to_string(c.cracks) + " with three orientations on a " + value_text(Lx) + " x " +
           value_text(Ly) + " x " + value_text(Lz) + " m cell: the cracks loaded along x and y are samples of other "
           "width, thickness and height; --crack-orientations one keeps every crack along z");
  }
  for (int k = 1; k < c.cracks; ++k) more_cracks.push_back(make_crack_sample(net, c.crack, k, c.cracks, c.crack_orientations, c.input));
  check_widths_fit(c, net, s.mean_diameter);
  if (c.fields.requested()) check_fracture_fields(c.fields, s);  // width and grid, before any solve
  if (want_sla && !sla_uses_pcg(c.sla, long(s.packing.particles.size() - s.removed_particles)))
    // the Woodbury block K0^-1 U: 6 dofs per particle x 6 columns per broken bond, float64
    check_memory_request(6.0 * double(s.packing.particles.size()) * 6.0 * std::max(1, c.sla.woodbury_bonds) * 8.0, "",
                         "--woodbury-bonds", std::to_string(c.sla.woodbury_bonds),
                         "the low-rank update block for " + std::to_string(s.packing.particles.size()) + " particles");
  if (want_explicit) {
    // --max-steps under two records of the load measures nothing: refused before any run (the SLA too).
    ExplicitFractureOptions eo = c.explicit_;
    eo.stop_fraction = c.stop_fraction;
    check_explicit_fracture_cap(explicit_fracture_record_steps(s, laws, fo, eo), eo);
    for (std::size_t k = 0; want_sla && k < more_cracks.size(); ++k)
      check_explicit_fracture_cap(explicit_fracture_record_steps(more_cracks[k], laws, fo, eo), eo);
  }
  info("sample " + std::to_string(s.W) + " x " + std::to_string(s.B) + " x " + std::to_string(s.H) + " m, " +
       std::to_string(s.precrack_bonds) + " bonds removed for the crack, " + std::to_string(s.ligament_bonds) +
       " across the ligament");

  double E = std::nan(""), nu = std::nan("");
  if (c.elastic) std::tie(E, nu) = elastic_constants(net, laws, c.input);
  FractureResult sla, ex;
  std::vector<FractureResult> crack_runs, crack_explicit;  // cracks 2 .. K (SLA, explicit)
  if (want_sla) {
    info("sequentially linear analysis");
    SlaOptions so = c.sla;
    so.stop_fraction = c.stop_fraction;
    sla = run_sla(s, laws, fo, so);
    for (std::size_t k = 0; k < more_cracks.size(); ++k) {
      info("crack " + std::to_string(k + 2) + " of " + std::to_string(c.cracks));
      crack_runs.push_back(run_sla(more_cracks[k], laws, fo, so));
    }
  }
  if (want_explicit) {
    info("explicit quasi-static test");
    ExplicitFractureOptions eo = c.explicit_;
    eo.stop_fraction = c.stop_fraction;
    ex = run_explicit_fracture(s, laws, fo, eo);
    // With the SLA on several cracks, the explicit test runs on each as well: the two methods are
    // compared crack by crack, so that the crack-tip discreteness of one crack averages out.
    for (std::size_t k = 0; want_sla && k < more_cracks.size(); ++k) {
      info("explicit quasi-static test, crack " + std::to_string(k + 2) + " of " + std::to_string(c.cracks));
      crack_explicit.push_back(run_explicit_fracture(more_cracks[k], laws, fo, eo));
    }
  }
  const FractureResult& primary = want_sla ? sla : ex;
  Summary out("tomodem-fracture");
  out.input(c.input);
  out.n_particles(p.particles.size());
  out["method"] = to_string(c.method);
  out["criterion"] = to_string_criterion(c.failure.criterion);
  primary_keys(out, primary, s, E, nu);
  // The SLA's error (crack-tip discreteness; with --cracks also the spread between cracks) is
  // independent from one sample to the next: a report over replicas finds it in their scatter
  // (docs/pipelines.md). The explicit test's dynamic part is a rate bias: systematic.
  out["K_IC_error_kind"] = want_sla ? "random" : "systematic";
  if (c.cracks > 1) {
    crack_runs.insert(crack_runs.begin(), sla);
    double K = 0, error = 0;
    out["cracks"] = crack_statistics(crack_runs, c.crack_orientations, K, error);
    out["K_IC"] = K;
    out["K_IC_error"] = error;
    out["G_from_K_IC"] = finite(K * K * (1 - nu * nu) / E);
  }
  out["sample"] = sample_json(s, p.particles.size());
  if (want_sla) out["sla"] = result_json(sla, s);
  if (want_explicit) out["explicit"] = result_json(ex, s);
  if (want_sla && want_explicit) out["explicit_vs_sla"] = ex.K_IC / sla.K_IC - 1;
  // An explicit test stopped by --max-steps before the load fell below the stop fraction gave a
  // K_IC, but not from the test asked (exit 4; the warning names what was reached).
  // (Set where the explicit test runs; the SLA's --max-breaks is its own cap, reported in stop_reason.)
  if (want_explicit) {
    bool explicit_short = ex.max_steps_reached;
    for (const FractureResult& r : crack_explicit) explicit_short = explicit_short || r.max_steps_reached;
    out["target_reached"] = !explicit_short;
  }
  if (want_sla && want_explicit && c.cracks > 1) {
    // Paired differences K_expl/K_SLA − 1 per crack: their mean and standard error.
    crack_explicit.insert(crack_explicit.begin(), ex);
    std::vector<double> kx, d;
    for (std::size_t k = 0; k < crack_runs.size(); ++k) {
      kx.push_back(crack_explicit[k].K_IC);
      d.push_back(crack_explicit[k].K_IC / crack_runs[k].K_IC - 1);
    }
    const MeanSem paired = mean_sem(d);
    out["cracks"]["explicit_K_IC"] = kx;
    out["cracks"]["explicit_vs_sla"] = d;
    out["cracks"]["explicit_vs_sla_mean"] = paired.mean;
    out["cracks"]["explicit_vs_sla_sem"] = paired.sem;
  }
  if (!c.widths.empty()) out["size_effect"] = size_effect_study(c, net, laws, fo, s.mean_diameter);
  write_fracture_outputs(c, s, sla, ex, primary, out);
  if (c.fields.requested())
    out["fields"] = json::parse(fracture_fields(c.fields, s, laws, fo, c.sla, sla, c.input)), out.output("fields", c.fields.output);
  return out.text();
}

}  // namespace tomodem::mechanics
