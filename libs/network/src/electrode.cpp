#include "tomodem/network/electrode.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

#include "tomodem/core/error.hpp"

namespace tomodem::network {

namespace {
constexpr double kPi = 3.14159265358979323846;
}

CompositeResult solve_composite(const Packing& pk, const CompositeOptions& opt) {
  const auto t0 = std::chrono::steady_clock::now();
  if (opt.electronic.empty()) throw InputError("", "--electronic", "", "name at least one electronic phase");
  if (opt.ionic.empty()) throw InputError("", "--ionic", "", "name at least one ionic phase");
  for (const auto& e : opt.electronic)
    if (std::find(opt.ionic.begin(), opt.ionic.end(), e) != opt.ionic.end())
      throw InputError("", "--ionic", e, "a phase cannot be both electronic and ionic");
  if (!(opt.charge_transfer > 0 && std::isfinite(opt.charge_transfer)))
    throw InputError("", "--charge-transfer", [&] {
      std::ostringstream t;
      t << opt.charge_transfer;
      return t.str();
    }(),
                     "the charge-transfer conductance per TPB length must be positive (S/m)");
  NetworkOptions no = opt.network;
  no.phases = opt.electronic;
  no.phases.insert(no.phases.end(), opt.ionic.begin(), opt.ionic.end());
  CompositeResult res;
  res.net = build_network(pk, no);
  Network& net = res.net;
  std::vector<uint8_t> ionic_phase(net.phase_names.size(), 0);
  for (const auto& name : opt.ionic)
    ionic_phase[std::find(net.phase_names.begin(), net.phase_names.end(), name) - net.phase_names.begin()] = 1;
  const std::size_t n = net.n_nodes(), m = net.n_edges();
  std::vector<uint8_t> is_ionic(n);
  for (std::size_t v = 0; v < n; ++v) is_ionic[v] = ionic_phase[net.phase[v]];
  std::vector<uint8_t> is_ct(m, 0);
  for (std::size_t e = 0; e < m; ++e) {
    if (is_ionic[net.graph.i[e]] == is_ionic[net.graph.j[e]]) continue;
    is_ct[e] = 1;
    const double tpb = 2.0 * kPi * net.contact_radius[e];
    res.tpb_length_m += tpb;
    ++res.n_tpb_contacts;
    net.graph.g[e] = opt.charge_transfer * tpb;
  }
  // Faces.
  const int axis = opt.axis;
  if (axis < 0 || axis > 2) throw InputError("", "--axis", std::to_string(axis), "expected x, y or z");
  const Mat3 hinv = net.cell.h.inverse();
  const double thick =
      1.0 / std::sqrt(hinv(axis, 0) * hinv(axis, 0) + hinv(axis, 1) * hinv(axis, 1) + hinv(axis, 2) * hinv(axis, 2));
  const double area = net.cell.volume() / thick;
  std::vector<int8_t> terminal(n, -1);
  for (std::size_t v = 0; v < n; ++v) {
    const double s = (hinv * (net.position[v] - net.cell.origin))[axis];
    const double r = net.radius[v], tol = opt.conduct.electrode_tolerance * r;
    if (!is_ionic[v] && s * thick - r <= tol) { terminal[v] = 0; ++res.n_collector; }
    else if (is_ionic[v] && (1.0 - s) * thick - r <= tol) { terminal[v] = 1; ++res.n_electrolyte; }
  }
  Graph sub;
  sub.n_nodes = n;
  std::vector<std::size_t> edge_of;
  for (std::size_t e = 0; e < m; ++e)
    if (net.image[e][axis] == 0) {
      sub.add_edge(net.graph.i[e], net.graph.j[e], net.graph.g[e]);
      edge_of.push_back(e);
    }
  const std::vector<uint8_t> span = spanning_nodes(sub, terminal);
  std::vector<uint8_t> el(n), io(n);
  for (std::size_t v = 0; v < n; ++v) { el[v] = span[v] && !is_ionic[v]; io[v] = span[v] && is_ionic[v]; }
  {
    std::vector<uint8_t> all_el(n), all_io(n);
    double vel = 0, vio = 0, pel = 0, pio = 0;
    for (std::size_t v = 0; v < n; ++v) {
      const double vol = std::pow(net.radius[v], 3);
      (is_ionic[v] ? vio : vel) += vol;
      if (span[v]) (is_ionic[v] ? pio : pel) += vol;
    }
    res.electronic_percolating_fraction = vel > 0 ? pel / vel : 0;
    res.ionic_percolating_fraction = vio > 0 ? pio / vio : 0;
  }
  double active_tpb = 0;
  for (std::size_t e = 0; e < m; ++e)
    if (is_ct[e] && span[net.graph.i[e]]) active_tpb += 2.0 * kPi * net.contact_radius[e];
  res.tpb_density_m_per_m3 = res.tpb_length_m / net.cell.volume();
  res.tpb_active_density_m_per_m3 = active_tpb / net.cell.volume();
  res.potential.assign(n, std::numeric_limits<double>::quiet_NaN());
  res.edge_current.assign(m, 0.0);
  res.percolates = std::any_of(span.begin(), span.end(), [](uint8_t f) { return f != 0; });
  if (res.percolates) {
    std::vector<uint8_t> fixed(n, 0);
    std::vector<double> pot(n, 0.5 * opt.conduct.voltage);
    for (std::size_t v = 0; v < n; ++v)
      if (terminal[v] >= 0) {
        fixed[v] = 1;
        pot[v] = terminal[v] == 0 ? opt.conduct.voltage : 0.0;
      }
    res.solver = solve_kirchhoff(sub, span, fixed, {}, pot, opt.conduct.solver);
    double in = 0, out = 0, ct = 0;
    for (std::size_t k = 0; k < sub.n_edges(); ++k) {
      const int32_t a = sub.i[k], b = sub.j[k];
      if (!span[a] || !span[b]) continue;
      const double I = sub.g[k] * (pot[a] - pot[b]);
      res.edge_current[edge_of[k]] = I;
      if (is_ct[edge_of[k]]) ct += std::abs(I);
      if (terminal[a] == 0 && terminal[b] != 0) in += I;
      if (terminal[b] == 0 && terminal[a] != 0) in -= I;
      if (terminal[b] == 1 && terminal[a] != 1) out += I;
      if (terminal[a] == 1 && terminal[b] != 1) out -= I;
    }
    for (std::size_t v = 0; v < n; ++v)
      if (span[v]) res.potential[v] = pot[v];
    res.current = 0.5 * (in + out);
    const double imax = std::max(std::abs(in), std::abs(out));
    res.conservation_error = imax > 0 ? std::abs(in - out) / imax : 0;
    res.resistance_ohm = res.current > 0 ? opt.conduct.voltage / res.current : std::numeric_limits<double>::infinity();
    res.asr_ohm_m2 = res.resistance_ohm * area;
    res.charge_transfer_current_fraction = res.current > 0 ? ct / res.current : 0;
  } else {
    res.resistance_ohm = std::numeric_limits<double>::infinity();
    res.asr_ohm_m2 = std::numeric_limits<double>::infinity();
  }
  res.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

}  // namespace tomodem::network
