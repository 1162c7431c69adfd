#include "tomodem/network/conduct_tool.hpp"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>

#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/packing_io.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/network/conductivity.hpp"
#include "tomodem/network/electrode.hpp"
#include "tomodem/network/output.hpp"
#include "tomodem/network/voxel.hpp"

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

std::string text(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// Options: NaN and infinities are always refused; the message names the option and the value.
void require_range(const std::string& option, double v, double lo, bool lo_open, double hi, bool hi_open,
                   const std::string& meaning) {
  if (std::isfinite(v) && (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi)) return;
  const std::string range =
      std::isinf(hi) ? std::string("must be finite and ") + (lo_open ? "> " : ">= ") + text(lo)
                     : std::string("must lie in ") + (lo_open ? "(" : "[") + text(lo) + ", " + text(hi) + (hi_open ? ")" : "]");
  throw InputError("", option, text(v), range + " (" + meaning + ")");
}

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ",") + x;
  return s;
}
}  // namespace

std::string run_conduct(const ConductConfig& c) {
  const auto t0 = std::chrono::steady_clock::now();
  if (c.bc != "electrodes" && c.bc != "periodic")
    throw InputError("", "--bc", c.bc, "expected 'electrodes' or 'periodic'");
  std::vector<int> axes;
  const std::string ax = c.axes == "all" ? "xyz" : c.axes;
  for (char ch : ax) {
    if (ch < 'x' || ch > 'z') throw InputError("", "--axis", c.axes, "expected letters from x, y, z or 'all'");
    axes.push_back(ch - 'x');
  }
  if (axes.empty()) throw InputError("", "--axis", c.axes, "no axis given");
  // Every option is checked here, before the packing is read: out of range is refused, never ignored.
  require_range("--tolerance", c.tolerance, 0, true, 1, true, "relative residual of the CG solve");
  require_range("--voltage", c.voltage, 0, true, INFINITY, true, "V");
  require_range("--gap-tolerance", c.gap_tolerance, 0, false, 1, false,
                "gap / R*; a gap wider than the contact radius scale is no contact");
  require_range("--min-contact-ratio", c.min_contact_ratio, 0, false, 1, false, "a / R*");
  require_range("--electrode-tolerance", c.electrode_tolerance, 0, false, 1, false, "of the particle radius");
  require_range("--charge-transfer", c.charge_transfer, 0, false, INFINITY, true, "S/m per metre of TPB");
  if (c.max_iterations < 0)
    throw InputError("", "--max-iterations", std::to_string(c.max_iterations), "must be >= 0 (0: automatic)");
  if (c.charge_transfer != 0 && c.electronic.empty() && c.ionic.empty())
    throw InputError("", "--charge-transfer", text(c.charge_transfer),
                     "applies to a composite electrode: give --electronic and --ionic too");
  for (int res : c.voxel)
    if (res < 2) throw InputError("", "--voxel", std::to_string(res), "need at least 2 voxels along the longest edge");
  check_outputs({c.input}, {{"-o", c.output}, {"-o (its .xdmf sidecar)", c.output.empty() ? "" : xdmf_sidecar_of(c.output)},
                          {"--json", c.json}});
  NetworkOptions no;
  no.phases = c.phases;
  no.use_bonds = c.bonds;
  no.use_contacts = c.contacts;
  no.gap_tolerance = c.gap_tolerance;
  no.contact_radius = parse_contact_radius(c.contact_radius);
  no.min_contact_ratio = c.min_contact_ratio;
  no.source = c.input;
  ConductOptions co;
  co.electrode_tolerance = c.electrode_tolerance;
  co.voltage = c.voltage;
  co.solver.tolerance = c.tolerance;
  co.solver.max_iterations = c.max_iterations;
  co.solver.preconditioner = parse_preconditioner(c.preconditioner);

  const Packing pk = read_packing(c.input);
  for (int res : c.voxel) {  // before the network solve: an impossible grid stops the run now
    VoxelOptions vo;
    vo.resolution = res;
    vo.source = c.input;
    check_voxel_grid(pk, vo);
  }
  const Network net = build_network(pk, no);
  if (net.n_edges() == 0)
    throw InputError(c.input, "/bonds", "0 edges",
                     "empty network: no intact bond and no contact within the gap tolerance between conducting particles");
  std::size_t nb = 0;
  for (auto k : net.kind) nb += k == EdgeKind::bond;
  json out = {{"tool", "tomodem-conduct"}, {"version", version_string()}, {"input", c.input}, {"boundary", c.bc},
              {"units", {{"sigma_eff", "S/m"}, {"wall_time_s", "s"}, {"resistance_ohm", "ohm"}}}};
  out["network"] = {{"nodes", net.n_nodes()},
                    {"edges", net.n_edges()},
                    {"bonds", nb},
                    {"contacts", net.n_edges() - nb},
                    {"phases", c.phases.empty() ? json("all") : json(c.phases)},
                    {"contact_radius", c.contact_radius}};
  out["solver"] = {{"method", "conjugate gradient"}, {"preconditioner", c.preconditioner}, {"tolerance", c.tolerance}};
  std::vector<FieldSet> fields;
  json sigma = json::object(), err = json::object(), perc = json::object(), dead = json::object(),
       per_axis = json::object();
  double residual = 0;
  int iterations = 0;
  bool any = false;
  auto record = [&](const AxisResult& a, const std::string& name) {
    sigma[name] = a.sigma_eff;
    err[name] = a.sigma_error;
    perc[name] = a.percolating_fraction;
    dead[name] = a.dead_end_fraction;
    per_axis[name] = axis_json(a);
    residual = std::max(residual, a.solver.residual);
    iterations = std::max(iterations, a.solver.iterations);
    any = any || a.percolates;
    if (!a.percolates) warn("no conducting path along " + name + ": sigma_eff = 0 reported");
    else if (!a.solver.converged) warn("solver did not reach the tolerance along " + name);
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
  out["percolating_fraction"] = perc;
  out["dead_end_fraction"] = dead;
  out["residual"] = residual;
  out["iterations"] = iterations;
  out["axes"] = per_axis;
  out["percolates"] = any;

  if (!c.electronic.empty() || !c.ionic.empty()) {
    CompositeOptions cp;
    cp.electronic = c.electronic;
    cp.ionic = c.ionic;
    cp.axis = axes.front();
    cp.charge_transfer = c.charge_transfer;
    cp.network = no;
    cp.conduct = co;
    const CompositeResult r = solve_composite(pk, cp);
    out["composite"] = {{"axis", kAxis[cp.axis]},
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
    if (!r.percolates) warn("composite electrode: no path from the current collector to the electrolyte");
  }
  if (!c.voxel.empty()) {
    json vx = json::array();
    std::vector<double> s;
    for (int res : c.voxel) {
      VoxelOptions vo;
      vo.axis = axes.front();
      vo.resolution = res;
      vo.phases = c.phases;
      vo.solver = co.solver;
      vo.source = c.input;
      const VoxelResult r = voxel_conductivity(pk, vo);
      s.push_back(r.sigma_eff);
      vx.push_back({{"resolution", res},
                    {"grid", {r.nx, r.ny, r.nz}},
                    {"voxel_size_m", r.voxel_size},
                    {"solid_fraction", r.solid_fraction},
                    {"sigma_eff", r.sigma_eff},
                    {"percolates", r.percolates},
                    {"solver", solver_json(r.solver)},
                    {"wall_time_s", r.wall_time_s}});
    }
    out["voxel"] = {{"axis", kAxis[axes.front()]}, {"runs", vx}};
    if (s.size() >= 3) {
      const std::size_t k = s.size();
      double order = 0, e = 0;
      const double ratio = static_cast<double>(c.voxel[k - 1]) / c.voxel[k - 2];
      const double ext = richardson(s[k - 3], s[k - 2], s[k - 1], ratio, &order, &e);
      out["voxel"]["extrapolated_sigma_eff"] = ext;
      out["voxel"]["observed_order"] = order;
      out["voxel"]["discretisation_error"] = e;
      if (c.bc == "electrodes" && ext != 0)
        out["voxel"]["network_minus_voxel_relative"] = (sigma[kAxis[axes.front()]].get<double>() - ext) / ext;
    }
  }
  std::ostringstream params;
  params << "phases: [" << join(c.phases) << "]\nbc: " << c.bc << "\naxes: " << ax << "\ncontact_radius: "
         << c.contact_radius << "\ngap_tolerance: " << c.gap_tolerance << "\nmin_contact_ratio: " << c.min_contact_ratio
         << "\nelectrode_tolerance: " << c.electrode_tolerance << "\ntolerance: " << c.tolerance
         << "\npreconditioner: " << c.preconditioner << "\n";
  if (!c.output.empty()) {
    write_fields(c.output, net, fields, params.str());
    out["outputs"] = {{"fields", c.output}};
  }
  out["wall_time_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const std::string text = out.dump(2) + "\n";
  if (!c.json.empty() && c.json != "-") write_text_atomic(c.json, text);
  return text;
}

}  // namespace tomodem::network
