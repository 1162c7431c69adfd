#include "tomodem/network/conduct_tool.hpp"

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>

#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/packing_io.hpp"
#include "tomodem/core/summary.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/network/conductivity.hpp"
#include "tomodem/network/electrode.hpp"
#include "tomodem/network/image_transport.hpp"
#include "tomodem/network/output.hpp"
#include "tomodem/network/voxel.hpp"
#include "tomodem/spatial/union_volume.hpp"

namespace tomodem::network {

namespace {
using json = nlohmann::json;
const char* kAxis[3] = {"x", "y", "z"};

json solver_json(const SolverReport& r) {
  json j = {{"unknowns", r.unknowns},         {"nonzeros", r.nonzeros},
            {"iterations", r.iterations},     {"residual", r.residual},
            {"converged", r.converged},       {"assemble_time_s", r.assemble_time_s},
            {"setup_time_s", r.setup_time_s}, {"solve_time_s", r.solve_time_s},
            {"memory_bytes", r.memory_bytes}};
  if (r.levels > 0) j["multigrid"] = {{"levels", r.levels}, {"operator_complexity", r.operator_complexity}};
  return j;
}
json finite(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json axis_json(const AxisResult& a) {
  json ph = json::object();
  for (const auto& [name, f] : a.phases)
    ph[name] = {{"percolating", f.percolating}, {"isolated", f.isolated}, {"dead_end", f.dead_end},
                {"backbone", f.backbone}};
  return {{"percolates", a.percolates},         {"sigma_eff", a.sigma_eff},
          {"sigma_eff_error", a.sigma_error},   {"current_in_A", a.current_in},
          {"current_out_A", a.current_out},     {"conservation_error", a.conservation_error},
          {"length_m", a.length},               {"area_m2", a.area},
          {"electrode_particles", {a.n_low, a.n_high}},
          {"solved_nodes", a.n_solved},         {"percolating_fraction", a.percolating_fraction},
          {"dead_end_fraction", a.dead_end_fraction}, {"phases", ph},
          {"solver", solver_json(a.solver)},    {"wall_time_s", a.wall_time_s}};
}

// All three axes (or the tensor's diagonal): their mean is the isotropic estimate, much less
// scattered between samples than one axis (docs/conduct.md). Its error bounds that of the mean:
// the mean of the axes' errors, over the mean with --image (sigma over sigma0, relative errors).
void write_sigma_iso(Summary& out, const json& sigma, const json& err, bool relative_units) {
  if (sigma.size() != 3) return;
  double mean = 0, mean_error = 0;
  for (const char* a : kAxis) {
    const double s = sigma[a].get<double>(), e = err[a].get<double>();
    mean += s / 3;
    mean_error += (relative_units ? e * s : e) / 3;
  }
  out["sigma_iso"] = mean;
  out["sigma_iso_error"] = relative_units ? (mean > 0 ? json(mean_error / mean) : json(nullptr)) : json(mean_error);
  out.unit("sigma_iso", relative_units ? "relative to sigma0 (the largest conductivity given)" : "S/m");
  out.unit("sigma_iso_error", relative_units ? "relative" : "S/m");
}

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ",") + x;
  return s;
}

// --phase-conductivity "1:1.0,2:0.3": label (0..255) : conductivity (finite, >= 0), at least one > 0.
std::array<double, 256> parse_phase_table(const std::string& t) {
  std::array<double, 256> table{};
  std::set<long> seen;
  std::stringstream ss(t);
  std::string item;
  bool any = false;
  while (std::getline(ss, item, ',')) {
    const auto colon = item.find(':');
    char* end = nullptr;
    if (colon == std::string::npos)
      throw InputError("", "--phase-conductivity", t, "entry '" + item + "' is not LABEL:CONDUCTIVITY (e.g. 1:1.0,2:0.3)");
    const std::string ls = item.substr(0, colon), vs = item.substr(colon + 1);
    const long label = std::strtol(ls.c_str(), &end, 10);
    if (ls.empty() || *end != '\0' || label < 0 || label > 255)
      throw InputError("", "--phase-conductivity", t, "label '" + ls + "' must be an integer in [0, 255]");
    const double v = std::strtod(vs.c_str(), &end);
    if (vs.empty() || *end != '\0' || !std::isfinite(v) || v < 0)
      throw InputError("", "--phase-conductivity", t, "conductivity '" + vs + "' of label " + ls + " must be finite and >= 0");
    if (!seen.insert(label).second)
      throw InputError("", "--phase-conductivity", t, "label " + ls + " given twice");
    table[label] = v;
    any = any || v > 0;
  }
  if (!any) throw InputError("", "--phase-conductivity", t, "no label conducts (every conductivity is 0 or none given)");
  return table;
}

json image_axis_json(const ImageAxisResult& a) {
  return {{"percolates", a.percolates},
          {"sigma_eff", a.sigma_eff},
          {"porosity", a.porosity},
          {"tortuosity", finite(a.tortuosity)},
          {"sigma_eff_error", a.sigma_eff_error},
          {"flux_imbalance", a.flux_imbalance},
          {"residual", a.residual},
          {"current_in_A_per_V", a.current_in},
          {"current_out_A_per_V", a.current_out},
          {"spanning_fraction", a.spanning_fraction},
          {"dead_end_fraction", a.dead_end_fraction},
          {"isolated_fraction", a.isolated_fraction},
          {"solver", {{"unknowns", a.unknowns}, {"nonzeros", a.nonzeros}, {"iterations", a.iterations},
                      {"converged", a.converged}, {"multigrid", {{"levels", a.levels}, {"operator_complexity", a.operator_complexity}}},
                      {"setup_time_s", a.setup_time_s}, {"solve_time_s", a.solve_time_s}}},
          {"wall_time_s", a.wall_time_s}};
}

// --axis: "x", "xz", "all"; `unique` drops repeated letters.
std::vector<int> parse_axes(const std::string& text, bool unique) {
  std::vector<int> axes;
  const std::string ax = text == "all" ? "xyz" : text;
  for (char ch : ax) {
    if (ch < 'x' || ch > 'z') throw InputError("", "--axis", text, "expected letters from x, y, z or 'all'");
    if (!unique || std::find(axes.begin(), axes.end(), ch - 'x') == axes.end()) axes.push_back(ch - 'x');
  }
  if (axes.empty()) throw InputError("", "--axis", text, "no axis given");
  return axes;
}

// --image: every option before the volume is read; returns the conductivity of each label.
// The error reported is sigma * max(conservation, residual): a residual, not a bound. Looser
// than 1e-3 it stops failing to bound the error: the linear starting potential alone has a
// relative residual below 1e-2 on the cathode example, so CG stops at once and sigma is 3x too
// high against a reported 11 % (docs/conduct.md).
constexpr double kLoosestTolerance = 1e-3;
constexpr const char* kToleranceMeaning = "relative residual of the CG solve; looser gives no error estimate";

std::array<double, 256> check_image_options(const ConductConfig& c) {
  if (!c.input.empty())
    throw InputError("", "--image", c.image, "give either a packing (positional input '" + c.input + "') or --image, not both");
  if (!c.voxel.empty()) throw InputError("", "--voxel-check", std::to_string(c.voxel.front()), "applies to a packing, not to --image");
  if (!c.electronic.empty() || !c.ionic.empty())
    throw InputError("", c.electronic.empty() ? "--ionic" : "--electronic", join(c.electronic.empty() ? c.ionic : c.electronic),
                     "applies to a packing; with --image give --phase-conductivity");
  if (c.bc != "electrodes") throw InputError("", "--bc", c.bc, "applies to a packing; with --image use --sides noflux|periodic");
  if (c.sides != "noflux" && c.sides != "periodic")
    throw InputError("", "--sides", c.sides, "expected 'noflux' or 'periodic'");
  require_range("--tolerance", c.tolerance, 0, true, kLoosestTolerance, false, kToleranceMeaning);
  if (c.max_iterations < 0)
    throw InputError("", "--max-iterations", std::to_string(c.max_iterations), "must be >= 0 (0: automatic)");
  std::array<double, 256> table{};
  if (c.phase >= 0 && !c.phase_conductivity.empty())
    throw InputError("", "--phase", std::to_string(c.phase), "give --phase or --phase-conductivity, not both");
  if (!c.phase_conductivity.empty()) {
    table = parse_phase_table(c.phase_conductivity);
  } else if (c.phase == -1) {
    throw InputError("", "--image", c.image, "give the conducting phase: --phase N or --phase-conductivity N:S,...");
  } else if (c.phase < 0 || c.phase > 255) {
    throw InputError("", "--phase", std::to_string(c.phase), "must be a label in [0, 255]");
  } else {
    table[c.phase] = 1.0;
  }
  check_outputs({c.image}, {{"-o", c.output}, {"-o (its .xdmf sidecar)", c.output.empty() ? "" : xdmf_sidecar_of(c.output)},
                          {"--json", c.json}});
  return table;
}

// Refuses a volume too large for the machine, before it is read.
void check_image_memory(const ConductConfig& c, std::size_t n_axes) {
  const auto shape = label_image_shape(c.image);
  const double nv = static_cast<double>(shape[0]) * shape[1] * shape[2];
  char count[64];
  std::snprintf(count, sizeof count, "%zux%zux%zu voxels", shape[0], shape[1], shape[2]);
  check_memory_request(nv * image_transport_bytes_per_voxel(!c.output.empty()) +
                           (c.output.empty() ? 0.0 : nv * 8.0 * (n_axes - 1)),
                       c.image, "/labels", count, "the transport solve of " + std::string(count));
}

// Refuses a conducting phase the volume does not hold, naming the labels it does.
void check_phases_present(const ConductConfig& c, const LabelImage& im, const std::array<double, 256>& table) {
  std::array<std::size_t, 256> hist{};
  for (uint8_t v : im.v) ++hist[v];
  std::string present;
  std::size_t conducting = 0;
  for (int l = 0; l < 256; ++l) {
    if (hist[l]) present += (present.empty() ? "" : ", ") + std::to_string(l);
    if (table[l] > 0) conducting += hist[l];
  }
  if (conducting == 0)
    throw InputError(c.image, "/labels",
                     c.phase >= 0 ? "phase " + std::to_string(c.phase) : "phases " + c.phase_conductivity,
                     "absent from the volume (labels present: " + present + ")");
}

// tomodem-conduct --image: transport in a segmented label volume (image_transport.hpp).
std::string run_image_conduct(const ConductConfig& c) {
  const std::array<double, 256> table = check_image_options(c);
  const std::vector<int> axes = parse_axes(c.axes, true);
  check_image_memory(c, axes.size());
  const LabelImage im = read_label_image(c.image);
  check_phases_present(c, im, table);

  Summary out("tomodem-conduct");
  out.input(c.image, {{"dataset", "/labels"}, {"grid", {im.nx, im.ny, im.nz}}, {"spacing_m", im.spacing}});
  out["sides"] = c.sides;
  out.unit("sigma_eff", "relative to sigma0 (the largest conductivity given)");
  out.unit("sigma_eff_error", "relative");
  if (c.phase >= 0) out["phase"] = c.phase;
  json tab = json::object();
  for (int l = 0; l < 256; ++l)
    if (table[l] > 0) tab[std::to_string(l)] = table[l];
  out["phase_conductivity"] = tab;
  out["solver"] = {{"method", "conjugate gradient"}, {"preconditioner", "amg"}, {"tolerance", c.tolerance}};
  ImageTransportOptions io;
  io.conductivity = table;
  io.periodic_sides = c.sides == "periodic";
  io.tolerance = c.tolerance;
  io.max_iterations = c.max_iterations;
  io.fields = !c.output.empty();
  std::vector<ImageAxisResult> results;
  json sigma = json::object(), tau = json::object(), err = json::object(), per_axis = json::object();
  bool reached = true;
  for (int k : axes) {
    io.axis = k;
    info(std::string("solving along ") + kAxis[k]);
    results.push_back(image_conductivity(im, io));
    const ImageAxisResult& r = results.back();
    sigma[kAxis[k]] = r.sigma_eff;
    tau[kAxis[k]] = finite(r.tortuosity);
    err[kAxis[k]] = r.sigma_eff_error;
    per_axis[kAxis[k]] = image_axis_json(r);
    if (!r.percolates)
      warn(std::string("no spanning path of the conducting phase along ") + kAxis[k] +
           ": sigma_eff = 0, tortuosity = inf (null in the JSON)");
    else if (!r.converged)
      warn(std::string("solver did not reach the tolerance along ") + kAxis[k]);
    reached = reached && (!r.percolates || r.converged);
    if (!io.fields) results.back() = ImageAxisResult{};
  }
  out["target_reached"] = reached;  // false: a solve stopped at its iteration cap (exit 4)
  out["porosity"] = results.empty() ? 0.0 : per_axis[kAxis[axes.front()]]["porosity"].get<double>();
  out["sigma_eff"] = sigma;
  out["tortuosity"] = tau;
  out["sigma_eff_error"] = err;
  write_sigma_iso(out, sigma, err, true);
  out["axes"] = per_axis;
  if (!c.output.empty()) {
    std::ostringstream params;
    params << "image: " << c.image << "\nphase_conductivity: " << tab.dump() << "\nsides: " << c.sides
           << "\naxes: " << c.axes << "\ntolerance: " << c.tolerance << "\n";
    write_image_fields(c.output, im, results, params.str());
    out.output("fields", c.output);
    out.output("xdmf", xdmf_sidecar_of(c.output));
  }
  return out.text();
}

// --voxel-box "3d" (mean conducting diameters, `diameter` m each) or "1.3e-6" (m): the edge in m.
double voxel_box_edge(const ConductConfig& c, double diameter) {
  const bool d = !c.voxel_box.empty() && (c.voxel_box.back() == 'd' || c.voxel_box.back() == 'D');
  const std::string digits = d ? c.voxel_box.substr(0, c.voxel_box.size() - 1) : c.voxel_box;
  char* end = nullptr;
  const double v = std::strtod(digits.c_str(), &end);
  if (digits.empty() || *end != '\0' || !std::isfinite(v) || !(v > 0))
    throw InputError("", "--voxel-box", c.voxel_box, "expected a positive edge in mean diameters (3d) or in m (1.5e-6)");
  return d ? v * diameter : v;
}

// The cube of --voxel-box in the packing: lower corner at --voxel-box-corner (fractions of the
// cell), or centred.
Packing voxel_box_packing(const ConductConfig& c, const Packing& pk) {
  const double edge = voxel_box_edge(c, conducting_mean_diameter(pk, c.phases));
  Vec3 lower;
  for (int k = 0; k < 3; ++k) {
    const double L = pk.cell.h(k, k);
    lower[k] = pk.cell.origin[k] + (c.voxel_box_corner.empty() ? 0.5 * (L - edge) : c.voxel_box_corner[k] * L);
  }
  return packing_box(pk, lower, Vec3(edge, edge, edge), "--voxel-box");
}

// A packing: every option is checked before the packing is read; out of range is refused, never ignored.
void check_packing_options(const ConductConfig& c) {
  if (c.input.empty()) throw InputError("", "input", "", "give a packing (.h5) or --image LABELS.h5");
  if (c.phase >= 0 || !c.phase_conductivity.empty() || c.sides != "noflux")
    throw InputError("", c.phase >= 0 ? "--phase" : !c.phase_conductivity.empty() ? "--phase-conductivity" : "--sides",
                     c.phase >= 0 ? std::to_string(c.phase) : !c.phase_conductivity.empty() ? c.phase_conductivity : c.sides,
                     "applies to --image; a packing takes --phases and --bc");
  if (c.bc != "electrodes" && c.bc != "periodic")
    throw InputError("", "--bc", c.bc, "expected 'electrodes' or 'periodic'");
  require_range("--tolerance", c.tolerance, 0, true, kLoosestTolerance, false, kToleranceMeaning);
  require_range("--voltage", c.voltage, 0, true, INFINITY, true, "V");
  require_range("--gap-tolerance", c.gap_tolerance, 0, false, 1, false,
                "gap / R*; a gap wider than the contact radius scale is no contact");
  require_range("--min-contact-ratio", c.min_contact_ratio, 0, false, 1, false, "a / R*");
  if (c.neck_law != "flux_tube" && c.neck_law != "face_capped" && c.neck_law != "isolated")
    throw InputError("", "--neck-law", c.neck_law, "expected flux_tube, face_capped or isolated");
  if (c.isolated_necks && c.neck_law != "flux_tube" && c.neck_law != "isolated")
    throw InputError("", "--isolated-necks", "", "means --neck-law isolated; it contradicts --neck-law " + c.neck_law);
  require_range("--electrode-tolerance", c.electrode_tolerance, 0, false, 1, false, "of the particle radius");
  require_range("--charge-transfer", c.charge_transfer, 0, false, INFINITY, true, "S/m per metre of TPB");
  if (c.max_iterations < 0)
    throw InputError("", "--max-iterations", std::to_string(c.max_iterations), "must be >= 0 (0: automatic)");
  if (c.charge_transfer != 0 && c.electronic.empty() && c.ionic.empty())
    throw InputError("", "--charge-transfer", value_text(c.charge_transfer),
                     "applies to a composite electrode: give --electronic and --ionic too");
  if (!c.voxel_box.empty() || !c.voxel_box_corner.empty()) {
    const std::string opt = c.voxel_box.empty() ? "--voxel-box-corner" : "--voxel-box";
    if (c.voxel.empty()) throw InputError("", opt, c.voxel_box, "applies to the voxel cross-check: give --voxel-check too");
    if (c.bc != "electrodes") throw InputError("", opt, c.voxel_box, "the box is solved between electrodes: use --bc electrodes");
    if (c.voxel_box.empty()) throw InputError("", "--voxel-box-corner", "", "give the box edge too: --voxel-box 3d");
    voxel_box_edge(c, 1.0);
    if (!c.voxel_box_corner.empty() && c.voxel_box_corner.size() != 3)
      throw InputError("", "--voxel-box-corner", std::to_string(c.voxel_box_corner.size()) + " values",
                       "expected three fractions of the cell edges (x,y,z)");
    for (double f : c.voxel_box_corner)
      if (!(f >= 0 && f < 1)) throw InputError("", "--voxel-box-corner", value_text(f), "a fraction of the cell edge in [0, 1)");
  }
  for (int res : c.voxel)
    if (res < 2)
      throw InputError("", "--voxel-check", std::to_string(res) + (c.voxel_per_diameter ? "d" : ""),
                       c.voxel_per_diameter ? "need at least 2 voxels per diameter" : "need at least 2 voxels along the longest edge");
  check_outputs({c.input}, {{"-o", c.output}, {"-o (its .xdmf sidecar)", c.output.empty() ? "" : xdmf_sidecar_of(c.output)},
                          {"--json", c.json}});
}

NetworkOptions network_options(const ConductConfig& c) {
  NetworkOptions no;
  no.phases = c.phases;
  no.use_bonds = c.bonds;
  no.use_contacts = c.contacts;
  no.gap_tolerance = c.gap_tolerance;
  no.contact_radius = parse_contact_radius(c.contact_radius);
  no.min_contact_ratio = c.min_contact_ratio;
  const std::string law = c.isolated_necks ? "isolated" : c.neck_law;
  no.face_cap = law != "isolated";
  no.flux_tube = law == "flux_tube";
  no.source = c.input;
  return no;
}

ConductOptions conduct_options(const ConductConfig& c) {
  ConductOptions co;
  co.electrode_tolerance = c.electrode_tolerance;
  co.voltage = c.voltage;
  co.solver.tolerance = c.tolerance;
  co.solver.max_iterations = c.max_iterations;
  co.solver.preconditioner = parse_preconditioner(c.preconditioner);
  return co;
}

json composite_json(const CompositeResult& r, int axis) {
  return {{"axis", kAxis[axis]},
          {"percolates", r.percolates},
          {"resistance_ohm", finite(r.resistance_ohm)},
          {"asr_ohm_m2", finite(r.asr_ohm_m2)},
          {"current_A", r.current},
          {"conservation_error", r.conservation_error},
          {"tpb_length_m", r.tpb_length_m},
          {"tpb_density_m_per_m3", r.tpb_density_m_per_m3},
          {"tpb_active_density_m_per_m3", r.tpb_active_density_m_per_m3},
          {"tpb_contacts", r.n_tpb_contacts},
          {"electronic_percolating_fraction", r.electronic_percolating_fraction},
          {"ionic_percolating_fraction", r.ionic_percolating_fraction},
          {"solver", solver_json(r.solver)},
          {"wall_time_s", r.wall_time_s}};
}

// The network's conductivity along the axes (electrodes) or the tensor (periodic).
void solve_network(const ConductConfig& c, const Network& net, const ConductOptions& co, const std::vector<int>& axes,
                   Summary& out, std::vector<FieldSet>& fields) {
  json sigma = json::object(), err = json::object(), perc = json::object(), dead = json::object(),
       per_axis = json::object();
  double residual = 0;
  int iterations = 0;
  bool any = false, reached = true;
  auto record = [&](const AxisResult& a, const std::string& name) {
    // Without a spanning path σ is 0 exactly: the periodic solve's round-off (2.4e-14 S/m beside
    // a warning saying 0, the hostile review) is not reported as a value.
    sigma[name] = a.percolates ? a.sigma_eff : 0.0;
    err[name] = a.percolates ? a.sigma_error : 0.0;
    perc[name] = a.percolating_fraction;
    dead[name] = a.dead_end_fraction;
    per_axis[name] = axis_json(a);
    residual = std::max(residual, a.solver.residual);
    iterations = std::max(iterations, a.solver.iterations);
    any = any || a.percolates;
    if (!a.percolates) warn("no conducting path along " + name + ": sigma_eff = 0 reported");
    else if (!a.solver.converged) warn("solver did not reach the tolerance along " + name);
    reached = reached && (!a.percolates || a.solver.converged);
    fields.push_back({name, a.potential, a.edge_current});
  };
  if (c.bc == "periodic") {
    const TensorResult t = solve_periodic(net, co);
    for (int k = 0; k < 3; ++k) record(t.axes[k], kAxis[k]);
    out["sigma_tensor"] = t.sigma;
  } else {
    for (int k : axes) record(solve_electrodes(net, k, co), kAxis[k]);
  }
  out["sigma_eff"] = sigma;
  out["sigma_eff_error"] = err;
  write_sigma_iso(out, sigma, err, false);
  out["percolating_fraction"] = perc;
  out["dead_end_fraction"] = dead;
  out["residual"] = residual;
  out["iterations"] = iterations;
  out["axes"] = per_axis;
  out["percolates"] = any;
  out["target_reached"] = reached;  // false: a solve stopped at its iteration cap (exit 4)
}

// σ_eff against the bounds of a conductor with insulating pores (docs/conduct.md#bounds): the
// Hashin–Shtrikman upper bound 2φ/(3 − φ) for the mean over the axes solved, Voigt's φ for each
// axis, φ the union-volume density of the network's particles and σ_s the largest conductivity
// among them (raising every phase to it only raises σ_eff, so the two-phase bound covers them all).
// The HS bound is for an isotropic body: one axis of a small, anisotropic cell may pass it by
// a little, so the mean is what is flagged.
json conductivity_bounds(const Packing& pk, const Network& net, const json& sigma) {
  std::vector<Vec3> x;
  std::vector<double> r;
  double sigma_s = 0;
  for (std::size_t n = 0; n < net.n_nodes(); ++n) {
    x.push_back(pk.particles.position[std::size_t(net.particle[n])]);
    r.push_back(net.radius[n]);
    sigma_s = std::max(sigma_s, net.node_conductivity[n]);
  }
  if (!(sigma_s > 0)) return nullptr;
  const double phi = std::clamp(spatial::union_relative_density(x, r, pk.cell), 0.0, 1.0);
  const double hs = 2 * phi / (3 - phi);
  json ratio = json::object();
  double mean = 0;
  bool voigt_exceeded = false;
  for (auto it = sigma.begin(); it != sigma.end(); ++it) {
    const double s = it.value().get<double>() / sigma_s;
    ratio[it.key()] = s;
    mean += s / double(sigma.size());
    // Relative 1e-9: the union volume and the solve are exact to round-off, not to this.
    voigt_exceeded = voigt_exceeded || s > phi * (1 + 1e-9);
  }
  const bool hs_exceeded = mean > hs * (1 + 1e-9);
  if (hs_exceeded)
    warn("sigma_eff/sigma_s = " + value_text(mean) + " (mean over the axes) exceeds the Hashin-Shtrikman upper bound " +
         value_text(hs) + " of a conductor with insulating pores at relative density " + value_text(phi) +
         " (docs/conduct.md#bounds)");
  if (voigt_exceeded)
    warn("sigma_eff/sigma_s exceeds the Voigt bound " + value_text(phi) + " along an axis (docs/conduct.md#bounds)");
  json b = {{"relative_density", phi},
            {"sigma_s", sigma_s},
            {"sigma_over_sigma_s", ratio},
            {"mean_sigma_over_sigma_s", mean},
            {"hs_upper_sigma_over_sigma_s", hs},
            {"voigt_sigma_over_sigma_s", phi},
            {"bound_exceeded", hs_exceeded || voigt_exceeded}};
  if (sigma.size() == 3) b["sigma_iso_over_sigma_s"] = mean;  // the mean checked above is sigma_iso's
  return b;
}

// The voxel cross-check at each --voxel-check resolution, then its convergence (Richardson).
json voxel_check(const ConductConfig& c, const Packing& pk, const Network& net, const ConductOptions& co, int axis,
                 double network_sigma, double diameter) {
  json vx = json::array();
  std::vector<double> s, q;
  VoxelResult last;
  for (int res : c.voxel) {
    VoxelOptions vo;
    vo.axis = axis;
    vo.resolution = res;
    vo.per_diameter = c.voxel_per_diameter;
    vo.diameter = diameter;
    vo.bonds = c.bonds;
    vo.phases = c.phases;
    vo.solver = co.solver;
    vo.source = c.input;
    vo.neck_radii = net.contact_radius;
    for (std::size_t e = 0; e < net.n_edges(); ++e) {
      const double ri = net.radius[net.graph.i[e]], rj = net.radius[net.graph.j[e]];
      vo.neck_reduced_radii.push_back(ri * rj / (ri + rj));
    }
    last = voxel_conductivity(pk, vo);
    const VoxelResult& r = last;
    s.push_back(r.sigma_eff);
    q.push_back(r.neck_resolution_median);
    vx.push_back({{"resolution", res},
                  {"grid", {r.nx, r.ny, r.nz}},
                  {"voxels_per_longest_edge", r.resolution_per_longest_edge},
                  {"voxel_size_m", r.voxel_size},
                  {"voxels_per_diameter", r.voxels_per_diameter},
                  {"neck_min_voxels", r.neck_min_voxels},
                  {"neck_median_voxels", r.neck_median_voxels},
                  {"neck_resolution_min", r.neck_resolution_min},
                  {"neck_resolution_median", r.neck_resolution_median},
                  {"solid_fraction", r.solid_fraction},
                  {"sigma_eff", r.sigma_eff},
                  {"percolates", r.percolates},
                  {"conservation_error", r.conservation_error},
                  {"solver", solver_json(r.solver)},
                  {"wall_time_s", r.wall_time_s}});
  }
  json out = {{"axis", kAxis[axis]},
              {"runs", vx},
              {"sigma_eff_per_resolution", s},
              {"resolutions", c.voxel},
              {"resolution_unit", c.voxel_per_diameter ? "voxels per mean diameter" : "voxels along the longest edge"},
              {"rasterisation", "partial volume, 4x4x4 samples in voxels cut by a surface; bonds as cylinders of radius a_b"},
              {"neck_resolution_needed", kNeckResolution}};
  std::vector<std::string> problems;
  // Of the finest grid (the last one given).
  if (!last.necks_resolved) {
    char msg[560];
    std::snprintf(msg, sizeof msg,
                  "the voxel grid does not resolve the necks: the median neck has a^2/(R* h) = %.2g on the finest grid "
                  "(a %.2g voxels across; need >= %.0f: the gap beside a neck is thinner than a voxel out to "
                  "sqrt(a^2 + 2 R* h), which the image fills); --voxel-check must reach %ld%s for the median neck (%ld for "
                  "the smallest); until then the voxel answer is not converged",
                  last.neck_resolution_median, last.neck_median_voxels, kNeckResolution, long(last.required_resolution_median),
                  c.voxel_per_diameter ? " voxels per diameter" : " voxels per longest edge", long(last.required_resolution_min));
    problems.push_back(msg);
  }
  if (s.size() >= 3) {
    const std::size_t k = s.size();
    double order = 0, e = 0;
    const double ratio = static_cast<double>(c.voxel[k - 1]) / c.voxel[k - 2];
    const double ratio0 = static_cast<double>(c.voxel[k - 2]) / c.voxel[k - 3];
    const double ext = richardson(s[k - 3], s[k - 2], s[k - 1], ratio, &order, &e);
    const bool same_ratio = std::abs(ratio - ratio0) <= 1e-9 * ratio;
    // Converging: differences shrinking at an order above 0.3. Bridges over the gaps beside point
    // contacts vanish at order 1/2, approached from below (0.35-0.39 measured on touching spheres,
    // Voxel.PointContactsVanishAsTheSquareRootOfTheVoxel); resolved necks at order 1.
    const bool converging = same_ratio && order > 0.3;
    // The observed order is the asymptotic one only when the coarsest grid of the triple resolves
    // the median neck: on the bonded lattice (docs/conduct.md) the triple at q = 1, 2, 4 gave order
    // 1.6 and an extrapolation 5 % short, while the finest grid was within 0.5 %. Before that the
    // error estimate is widened to the last difference, which covered both there.
    const bool asymptotic = q[k - 3] >= kNeckResolution;
    if (!asymptotic) e = std::max(e, std::abs(s[k - 1] - s[k - 2]));
    out["extrapolated_sigma_eff"] = ext;
    out["observed_order"] = order;
    out["discretisation_error"] = e;
    out["converging"] = converging;
    out["asymptotic"] = asymptotic;
    // With four grids or more, the order of the previous triple too: an order that moves by more
    // than 0.5 from one triple to the next is not settled (necks crossing q ~ 1 at different
    // grids, gap bridges vanishing), and the extrapolation is not trusted.
    bool settled = true;
    if (k >= 4 && std::abs(static_cast<double>(c.voxel[k - 3]) / c.voxel[k - 4] - ratio) <= 1e-9 * ratio) {
      double order_previous = 0, e_previous = 0;
      richardson(s[k - 4], s[k - 3], s[k - 2], ratio, &order_previous, &e_previous);
      out["observed_order_previous"] = order_previous;
      settled = std::abs(order - order_previous) <= 0.5;
      out["order_settled"] = settled;
    }
    if (!same_ratio) problems.push_back("the last three --voxel-check resolutions are not refined by one factor: no Richardson extrapolation");
    else if (!converging) {
      char msg[200];
      std::snprintf(msg, sizeof msg, "the voxel answers %.4g, %.4g, %.4g do not converge (observed order %.2f <= 0.3): "
                    "the extrapolated value is the finest result, not a converged one", s[k - 3], s[k - 2], s[k - 1], order);
      problems.push_back(msg);
    }
    else if (!settled) {
      char msg[300];
      std::snprintf(msg, sizeof msg, "the observed order is not settled: %.2f on the last three grids, %.2f on the three "
                    "before; the extrapolation is not a converged value", order, out["observed_order_previous"].get<double>());
      problems.push_back(msg);
    } else if (last.necks_resolved && !asymptotic) {
      char msg[320];
      std::snprintf(msg, sizeof msg, "the coarsest grid of the extrapolation (%d) has a median neck a^2/(R* h) = %.2g < %.0f: "
                    "the observed order %.2f is not the asymptotic one; the error estimate is the last difference",
                    c.voxel[k - 3], q[k - 3], kNeckResolution, order);
      problems.push_back(msg);
    }
    // Without a converging, settled order there is no converged value: the finest answer stands
    // for it and its error is unknown (null).
    const bool trusted = same_ratio && converging && settled;
    if (!trusted) {
      out["extrapolated_sigma_eff"] = s[k - 1];
      out["discretisation_error"] = nullptr;
    }
    if (c.bc == "electrodes") {
      const double v = trusted ? ext : s[k - 1];
      out["network_sigma_eff"] = network_sigma;
      out["network_minus_voxel_relative"] = v != 0 ? finite((network_sigma - v) / v) : json(nullptr);
      // From the voxel error alone.
      out["network_minus_voxel_uncertainty"] = trusted && v != 0 ? json(network_sigma * e / (v * v)) : json(nullptr);
    }
  } else {
    problems.push_back("fewer than three --voxel-check resolutions: no observed order, no extrapolation");
  }
  std::string message;
  for (const auto& p : problems) {
    warn(p);
    message += (message.empty() ? "" : "; ") + p;
  }
  out["necks_resolved"] = last.necks_resolved;
  out["required_resolution_smallest_neck"] = last.required_resolution_min;
  out["required_resolution_median_neck"] = last.required_resolution_median;
  out["warning"] = !problems.empty();
  out["warning_message"] = message;
  return out;
}

std::string parameters_text(const ConductConfig& c) {
  std::ostringstream params;
  params << "phases: [" << join(c.phases) << "]\nbc: " << c.bc << "\naxes: " << c.axes << "\ncontact_radius: "
         << c.contact_radius << "\nneck_law: " << neck_law_name(network_options(c))
         << "\ngap_tolerance: " << c.gap_tolerance << "\nmin_contact_ratio: " << c.min_contact_ratio
         << "\nelectrode_tolerance: " << c.electrode_tolerance << "\ntolerance: " << c.tolerance
         << "\npreconditioner: " << c.preconditioner << "\n";
  return params.str();
}
}  // namespace

void parse_voxel_resolutions(const std::vector<std::string>& values, ConductConfig& c) {
  std::string all;
  for (const auto& v : values) all += (all.empty() ? "" : ",") + v;
  c.voxel.clear();
  int suffixed = 0;
  for (const auto& v : values) {
    const bool d = !v.empty() && (v.back() == 'd' || v.back() == 'D');
    const std::string digits = d ? v.substr(0, v.size() - 1) : v;
    char* end = nullptr;
    const long n = std::strtol(digits.c_str(), &end, 10);
    if (digits.empty() || *end != '\0' || n > 1000000000L)
      throw InputError("", "--voxel-check", all,
                       "'" + v + "' is not a whole number of voxels along the longest edge (64) or per diameter (8d)");
    c.voxel.push_back(static_cast<int>(n));
    suffixed += d;
  }
  if (suffixed != 0 && suffixed != static_cast<int>(values.size()))
    throw InputError("", "--voxel-check", all, "give every resolution per diameter (8d,16d,32d) or none");
  c.voxel_per_diameter = suffixed > 0;
}

std::string run_conduct(const ConductConfig& c) {
  if (!c.image.empty()) return run_image_conduct(c);
  check_packing_options(c);
  const std::vector<int> axes = parse_axes(c.axes, false);
  const NetworkOptions no = network_options(c);
  const ConductOptions co = conduct_options(c);

  const Packing pk = read_packing(c.input);
  // --voxel-box: the cross-check runs on a cube cut from the packing (network and image alike);
  // per-diameter resolutions keep the whole packing's mean diameter.
  const Packing boxed = c.voxel_box.empty() ? Packing{} : voxel_box_packing(c, pk);
  const double diameter = conducting_mean_diameter(pk, c.phases);
  for (int res : c.voxel) {  // before the network solve: an impossible grid stops the run now
    VoxelOptions vo;
    vo.resolution = res;
    vo.per_diameter = c.voxel_per_diameter;
    vo.diameter = diameter;
    vo.phases = c.phases;
    vo.source = c.input;
    check_voxel_grid(c.voxel_box.empty() ? pk : boxed, vo);
  }
  const Network net = build_network(pk, no);
  if (net.n_edges() == 0)
    throw InputError(c.input, "/bonds", "0 edges",
                     "empty network: no intact bond and no contact within the gap tolerance between conducting particles");
  std::size_t nb = 0;
  for (auto k : net.kind) nb += k == EdgeKind::bond;
  Summary out("tomodem-conduct");
  out.input(c.input);
  out.n_particles(pk.particles.size());
  out["boundary"] = c.bc;
  out.unit("sigma_eff", "S/m");
  out.unit("sigma_eff_error", "S/m");
  out.unit("resistance_ohm", "ohm");
  out["network"] = {{"nodes", net.n_nodes()},
                    {"edges", net.n_edges()},
                    {"bonds", nb},
                    {"contacts", net.n_edges() - nb},
                    {"phases", c.phases.empty() ? json("all") : json(c.phases)},
                    {"contact_radius", c.contact_radius}};
  out["neck_law"] = {{"law", neck_law_name(no)},
                     {"face_capped_edges", net.face_capped},
                     {"edges_without_face", net.no_face}};
  out["solver"] = {{"method", "conjugate gradient"}, {"preconditioner", c.preconditioner}, {"tolerance", c.tolerance}};
  std::vector<FieldSet> fields;
  solve_network(c, net, co, axes, out, fields);
  out["bounds"] = conductivity_bounds(pk, net, out["sigma_eff"]);

  if (!c.electronic.empty() || !c.ionic.empty()) {
    CompositeOptions cp;
    cp.electronic = c.electronic;
    cp.ionic = c.ionic;
    cp.axis = axes.front();
    cp.charge_transfer = c.charge_transfer;
    cp.network = no;
    cp.conduct = co;
    const CompositeResult r = solve_composite(pk, cp);
    out["composite"] = composite_json(r, cp.axis);
    if (!r.percolates) warn("composite electrode: no path from the current collector to the electrolyte");
  }
  if (!c.voxel.empty() && c.voxel_box.empty())
    out["voxel"] = voxel_check(c, pk, net, co, axes.front(), out["sigma_eff"][kAxis[axes.front()]].get<double>(), diameter);
  if (!c.voxel.empty() && !c.voxel_box.empty()) {
    // The network of the box between electrodes on its faces normal to the axis, as the image.
    const Network box_net = build_network(boxed, no);
    const AxisResult a = box_net.n_edges() ? solve_electrodes(box_net, axes.front(), co) : AxisResult{};
    if (!a.percolates) warn("--voxel-box: the network of the box does not percolate along " + std::string(kAxis[axes.front()]));
    json v = voxel_check(c, boxed, box_net, co, axes.front(), a.percolates ? a.sigma_eff : 0.0, diameter);
    const Vec3 lo = boxed.cell.origin;
    v["box"] = {{"lower_m", {lo[0], lo[1], lo[2]}},
                {"edge_m", boxed.cell.h(0, 0)},
                {"edge_diameters", boxed.cell.h(0, 0) / diameter},
                {"particles", boxed.particles.size()},
                {"network_edges", box_net.n_edges()},
                {"network_sigma_eff", a.percolates ? a.sigma_eff : 0.0},
                {"network_percolates", a.percolates}};
    out["voxel"] = v;
  }
  if (!c.output.empty()) {
    write_fields(c.output, net, fields, parameters_text(c));
    out.output("fields", c.output);
    out.output("xdmf", xdmf_sidecar_of(c.output));
  }
  return out.text();
}

}  // namespace tomodem::network
