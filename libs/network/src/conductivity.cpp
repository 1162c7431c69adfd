#include "tomodem/network/conductivity.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "tomodem/core/error.hpp"
#include "tomodem/spatial/clusters.hpp"

namespace tomodem::network {

namespace {
using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }
constexpr double kPi = 3.14159265358979323846;

double thickness(const Mat3& hinv, int k) {
  return 1.0 / std::sqrt(hinv(k, 0) * hinv(k, 0) + hinv(k, 1) * hinv(k, 1) + hinv(k, 2) * hinv(k, 2));
}

void fill_fractions(const Network& net, const std::vector<uint8_t>& perc, const std::vector<uint8_t>& backbone,
                    AxisResult& res) {
  std::map<int32_t, std::array<double, 4>> acc;  // total, percolating, dead end, backbone
  double total = 0, p_all = 0, d_all = 0;
  for (std::size_t v = 0; v < net.n_nodes(); ++v) {
    const double vol = 4.0 / 3.0 * kPi * std::pow(net.radius[v], 3);
    auto& a = acc[net.phase[v]];
    a[0] += vol;
    total += vol;
    if (perc[v]) {
      a[1] += vol;
      p_all += vol;
      if (backbone[v]) a[3] += vol; else { a[2] += vol; d_all += vol; }
    }
  }
  for (const auto& [ph, a] : acc) {
    PhaseFractions f;
    f.percolating = a[1] / a[0];
    f.isolated = 1.0 - f.percolating;
    f.dead_end = a[2] / a[0];
    f.backbone = a[3] / a[0];
    res.phases[net.phase_names[ph]] = f;
  }
  res.percolating_fraction = total > 0 ? p_all / total : 0;
  res.dead_end_fraction = total > 0 ? d_all / total : 0;
}

}  // namespace

double volume_fraction(const Network& net, const std::vector<uint8_t>& flag) {
  double t = 0, f = 0;
  for (std::size_t v = 0; v < net.n_nodes(); ++v) {
    const double vol = std::pow(net.radius[v], 3);
    t += vol;
    if (flag[v]) f += vol;
  }
  return t > 0 ? f / t : 0;
}

AxisResult solve_electrodes(const Network& net, int axis, const ConductOptions& opt) {
  const auto t0 = Clock::now();
  if (axis < 0 || axis > 2) throw InputError("", "--axis", std::to_string(axis), "expected x, y or z");
  AxisResult res;
  res.axis = axis;
  const std::size_t n = net.n_nodes();
  const Mat3 hinv = net.cell.h.inverse();
  const double thick = thickness(hinv, axis);
  res.area = net.cell.volume() / thick;
  // Electrode particles: surface within tol·r of the face.
  res.terminal.assign(n, -1);
  double s_low = 0, s_high = 0;
  std::vector<double> s(n);
  for (std::size_t v = 0; v < n; ++v) {
    s[v] = (hinv * (net.position[v] - net.cell.origin))[axis];
    const double r = net.radius[v], tol = opt.electrode_tolerance * r;
    if (s[v] * thick - r <= tol) { res.terminal[v] = 0; ++res.n_low; s_low += s[v]; }
    else if ((1.0 - s[v]) * thick - r <= tol) { res.terminal[v] = 1; ++res.n_high; s_high += s[v]; }
  }
  if (res.n_low && res.n_high) res.length = (s_high / res.n_high - s_low / res.n_low) * thick;
  // Edges that cross the periodic boundary along the axis are cut.
  Graph sub;
  sub.n_nodes = n;
  std::vector<std::size_t> edge_of;
  for (std::size_t e = 0; e < net.n_edges(); ++e) {
    if (net.image[e][axis] != 0) continue;
    sub.add_edge(net.graph.i[e], net.graph.j[e], net.graph.g[e]);
    edge_of.push_back(e);
  }
  const std::vector<uint8_t> span = spanning_nodes(sub, res.terminal);
  res.backbone = backbone_nodes(sub, res.terminal);
  for (std::size_t v = 0; v < n; ++v) {
    res.backbone[v] &= span[v];
    res.n_solved += span[v];
  }
  fill_fractions(net, span, res.backbone, res);
  res.percolates = res.n_solved > 0;
  res.potential.assign(n, std::numeric_limits<double>::quiet_NaN());
  res.edge_current.assign(net.n_edges(), 0.0);
  if (!res.percolates) {
    res.wall_time_s = seconds_since(t0);
    return res;
  }
  std::vector<uint8_t> fixed(n, 0);
  std::vector<double> pot(n, 0.0);
  const double sl = s_low / res.n_low, sh = s_high / res.n_high;
  for (std::size_t v = 0; v < n; ++v) {
    if (res.terminal[v] >= 0) {
      fixed[v] = 1;
      pot[v] = res.terminal[v] == 0 ? opt.voltage : 0.0;
    } else {  // initial guess: linear drop between the electrode planes
      pot[v] = opt.voltage * std::clamp((sh - s[v]) / (sh - sl), 0.0, 1.0);
    }
  }
  res.solver = solve_kirchhoff(sub, span, fixed, {}, pot, opt.solver);
  for (std::size_t k = 0; k < sub.n_edges(); ++k) {
    const int32_t a = sub.i[k], b = sub.j[k];
    if (!span[a] || !span[b]) continue;
    const double I = sub.g[k] * (pot[a] - pot[b]);
    res.edge_current[edge_of[k]] = I;
    const int8_t ta = res.terminal[a], tb = res.terminal[b];
    if (ta == 0 && tb != 0) res.current_in += I;
    if (tb == 0 && ta != 0) res.current_in -= I;
    if (tb == 1 && ta != 1) res.current_out += I;
    if (ta == 1 && tb != 1) res.current_out -= I;
  }
  for (std::size_t v = 0; v < n; ++v)
    if (span[v]) res.potential[v] = pot[v];
  const double imax = std::max(std::abs(res.current_in), std::abs(res.current_out));
  res.conservation_error = imax > 0 ? std::abs(res.current_in - res.current_out) / imax : 0;
  const double I = 0.5 * (res.current_in + res.current_out);
  res.sigma_eff = res.length > 0 ? I * res.length / (res.area * opt.voltage) : 0;
  // The current balance measures the solver error directly; the residual bounds what it misses.
  res.sigma_error = std::abs(res.sigma_eff) * std::max(res.conservation_error, res.solver.residual);
  if (!opt.keep_fields) {
    res.potential.clear();
    res.edge_current.clear();
  }
  res.wall_time_s = seconds_since(t0);
  return res;
}

TensorResult solve_periodic(const Network& net, const ConductOptions& opt) {
  const auto t0 = Clock::now();
  for (int k = 0; k < 3; ++k)
    if (!net.cell.periodic[k])
      throw InputError("", "/cell/periodic", "axis " + std::to_string(k) + " not periodic",
                       "periodic boundary conditions need a cell periodic along x, y and z");
  TensorResult out;
  const std::size_t n = net.n_nodes(), m = net.n_edges();
  // Clusters of the contact graph and the cell vectors each wraps along (libs/spatial).
  const spatial::Clusters clusters = spatial::find_clusters(n, net.graph.i, net.graph.j, net.image);
  std::vector<uint8_t> active(n, 0), fixed(n, 0), seen(clusters.size.size(), 0);
  std::array<std::vector<uint8_t>, 3> wraps_k;
  for (int k = 0; k < 3; ++k) wraps_k[k].assign(n, 0);
  for (std::size_t v = 0; v < n; ++v) {
    const std::size_t c = std::size_t(clusters.label[v]);
    const auto& w = clusters.wraps[c];
    for (int k = 0; k < 3; ++k) {
      wraps_k[k][v] = w[k];
      out.wraps[k] = out.wraps[k] || w[k];
    }
    active[v] = w[0] || w[1] || w[2];
    if (active[v] && !seen[c]) {  // pin one node per current-carrying cluster (u = 0)
      seen[c] = 1;
      fixed[v] = 1;
    }
  }
  std::vector<Vec3> b(m);
  for (std::size_t e = 0; e < m; ++e) b[e] = net.branch(e);
  const double V = net.cell.volume();
  for (int k = 0; k < 3; ++k) {
    const auto t1 = Clock::now();
    AxisResult& res = out.axes[k];
    res.axis = k;
    res.percolates = out.wraps[k];
    Vec3 E(0, 0, 0);
    E[k] = 1.0;  // V/m
    std::vector<double> src(n, 0.0), u(n, 0.0);
    for (std::size_t e = 0; e < m; ++e) {
      const double q = net.graph.g[e] * dot(E, b[e]);
      src[net.graph.i[e]] -= q;
      src[net.graph.j[e]] += q;
    }
    res.solver = solve_kirchhoff(net.graph, active, fixed, src, u, opt.solver);
    Vec3 J(0, 0, 0);
    std::vector<double> imbalance(n, 0.0);
    double isum = 0, imax = 0;
    res.edge_current.assign(m, 0.0);
    for (std::size_t e = 0; e < m; ++e) {
      const int32_t a = net.graph.i[e], c = net.graph.j[e];
      if (!active[a]) continue;
      const double I = net.graph.g[e] * (u[a] - u[c] + dot(E, b[e]));
      res.edge_current[e] = I;
      J += I * b[e];
      imbalance[a] += I;
      imbalance[c] -= I;
      isum += std::abs(I);
      imax = std::max(imax, std::abs(I));
    }
    J *= 1.0 / V;
    for (int r = 0; r < 3; ++r) out.sigma[r][k] = J[r];
    double ibad = 0;
    for (std::size_t v = 0; v < n; ++v) ibad += std::abs(imbalance[v]);
    res.conservation_error = isum > 0 ? ibad / isum : 0;
    res.sigma_eff = J[k];
    res.sigma_error = std::abs(J[k]) * std::max(res.conservation_error, res.solver.residual);
    res.length = thickness(net.cell.h.inverse(), k);
    res.area = V / res.length;
    // Dead ends: nodes of wrapping clusters whose edges all carry (almost) nothing.
    std::vector<double> node_max(n, 0.0);
    for (std::size_t e = 0; e < m; ++e) {
      const double I = std::abs(res.edge_current[e]);
      node_max[net.graph.i[e]] = std::max(node_max[net.graph.i[e]], I);
      node_max[net.graph.j[e]] = std::max(node_max[net.graph.j[e]], I);
    }
    res.backbone.assign(n, 0);
    res.potential.assign(n, std::numeric_limits<double>::quiet_NaN());
    for (std::size_t v = 0; v < n; ++v) {
      res.backbone[v] = wraps_k[k][v] && node_max[v] > 1e-9 * imax;
      res.n_solved += active[v];
      if (active[v]) res.potential[v] = u[v] - dot(E, net.position[v]);
    }
    fill_fractions(net, wraps_k[k], res.backbone, res);
    if (!opt.keep_fields) {
      res.potential.clear();
      res.edge_current.clear();
    }
    res.wall_time_s = seconds_since(t1);
  }
  out.wall_time_s = seconds_since(t0);
  return out;
}

}  // namespace tomodem::network
