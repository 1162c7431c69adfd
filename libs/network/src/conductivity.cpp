#include "tomodem/network/conductivity.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "tomodem/core/cell_width.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/spatial/clusters.hpp"

namespace tomodem::network {

namespace {
using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }
constexpr double kPi = 3.14159265358979323846;

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
  const double thick = cell_width(hinv, axis);
  res.area = net.cell.volume() / thick;
  // The solved graph: the network's nodes, then (plates) one terminal node per connection to a plate.
  Graph sub;
  sub.n_nodes = n;
  std::vector<int8_t> terminal(n, -1);  // of the solved graph's nodes
  std::vector<std::size_t> edge_of;     // solved edge -> network edge
  std::vector<int8_t> half_sign;        // 0: whole edge; ±1: a half, oriented along (+1) or against i -> j
  res.terminal.assign(n, -1);
  std::vector<double> s(n);
  const bool plates = net.cell.periodic[axis];
  if (plates) {
    // A periodic cell is cut by two plates on its faces (one plane, s = 0 ≡ 1, seen from its two
    // sides). A branch that crosses the plane joins each of its nodes to the plate on that node's
    // side, with the share of the edge's resistance on that side (the resistance is spread along
    // the branch, as the periodic solve's J = (1/V) Σ I b assumes): a uniform field is then exact,
    // and L is the cell's thickness. The particles near the faces are not shorted together: holding
    // whole particles at the plate potential, at depths 0 … r, moved the equipotential into the
    // sample by a fraction of a radius that L did not count (1-8 % above periodic on 500-particle
    // samples sintered to 0.9, issue 18 item 7).
    for (std::size_t v = 0; v < n; ++v) {
      const double f = (hinv * (net.position[v] - net.cell.origin))[axis];
      s[v] = f - std::floor(f);
      if (!(s[v] < 1.0)) s[v] = 0.0;  // round-off of a tiny negative f
    }
    auto join_plate = [&](int32_t v, int side, double share, double g, std::size_t e, int8_t sign) {
      if (share < 1e-9) {  // the node lies on the plane: it is the plate
        if (terminal[std::size_t(v)] < 0) terminal[std::size_t(v)] = int8_t(side);
        return;
      }
      const int32_t plate_node = static_cast<int32_t>(sub.n_nodes++);
      terminal.push_back(int8_t(side));
      sub.add_edge(v, plate_node, g / share);
      edge_of.push_back(e);
      half_sign.push_back(sign);
      if (res.terminal[std::size_t(v)] < 0) res.terminal[std::size_t(v)] = int8_t(side);
    };
    for (std::size_t e = 0; e < net.n_edges(); ++e) {
      const int32_t i = net.graph.i[e], j = net.graph.j[e];
      const double ds = (hinv * net.branch(e))[axis];
      // Planes crossed from i to j's image: an integer up to round-off.
      const long crossings = std::lround(s[std::size_t(i)] + ds - s[std::size_t(j)]);
      if (crossings == 0) {
        sub.add_edge(i, j, net.graph.g[e]);
        edge_of.push_back(e);
        half_sign.push_back(0);
      } else if (crossings == 1 || crossings == -1) {  // up through s = 1 (i to the high plate) or down through 0
        const double len = std::abs(ds);
        const double share_i = std::clamp((crossings == 1 ? 1.0 - s[std::size_t(i)] : s[std::size_t(i)]) / len, 0.0, 1.0);
        const double share_j = std::clamp((crossings == 1 ? s[std::size_t(j)] : 1.0 - s[std::size_t(j)]) / len, 0.0, 1.0);
        const int side_i = crossings == 1 ? 1 : 0;
        join_plate(i, side_i, share_i, net.graph.g[e], e, +1);
        join_plate(j, 1 - side_i, share_j, net.graph.g[e], e, -1);
      }  // a branch longer than the cell crosses twice: no edge of a sample between two plates
    }
    for (std::size_t v = 0; v < n; ++v)
      if (terminal[v] >= 0) res.terminal[v] = terminal[v];
    for (std::size_t v = 0; v < n; ++v) {
      res.n_low += res.terminal[v] == 0;
      res.n_high += res.terminal[v] == 1;
    }
    res.length = thick;
  } else {
    // An open direction (walls): the particles whose surface lies within tol·r of a wall are the
    // electrodes; they all sit at about one radius from it, and L is taken between their mean
    // centre planes. Edges that cross the cell along the axis are cut.
    double s_low = 0, s_high = 0;
    for (std::size_t v = 0; v < n; ++v) {
      s[v] = (hinv * (net.position[v] - net.cell.origin))[axis];
      const double r = net.radius[v], tol = opt.electrode_tolerance * r;
      if (s[v] * thick - r <= tol) { terminal[v] = 0; ++res.n_low; s_low += s[v]; }
      else if ((1.0 - s[v]) * thick - r <= tol) { terminal[v] = 1; ++res.n_high; s_high += s[v]; }
    }
    res.terminal = terminal;
    if (res.n_low && res.n_high) res.length = (s_high / res.n_high - s_low / res.n_low) * thick;
    for (std::size_t e = 0; e < net.n_edges(); ++e) {
      if (net.image[e][axis] != 0) continue;
      sub.add_edge(net.graph.i[e], net.graph.j[e], net.graph.g[e]);
      edge_of.push_back(e);
      half_sign.push_back(0);
    }
  }
  const std::size_t n_all = sub.n_nodes;
  const std::vector<uint8_t> span = spanning_nodes(sub, terminal);
  std::vector<uint8_t> backbone = backbone_nodes(sub, terminal);
  res.backbone.assign(n, 0);
  for (std::size_t v = 0; v < n; ++v) {
    res.backbone[v] = backbone[v] && span[v];
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
  std::vector<uint8_t> fixed(n_all, 0);
  std::vector<double> pot(n_all, 0.0);
  double sl = 0, sh = 1;  // initial guess: a linear drop between the electrode planes
  if (!plates) {
    double low = 0, high = 0;
    for (std::size_t v = 0; v < n; ++v) {
      if (terminal[v] == 0) low += s[v];
      if (terminal[v] == 1) high += s[v];
    }
    sl = low / double(res.n_low);
    sh = high / double(res.n_high);
  }
  for (std::size_t v = 0; v < n_all; ++v) {
    if (terminal[v] >= 0) {
      fixed[v] = 1;
      pot[v] = terminal[v] == 0 ? opt.voltage : 0.0;
    } else {
      pot[v] = opt.voltage * std::clamp((sh - s[v]) / (sh - sl), 0.0, 1.0);
    }
  }
  res.solver = solve_kirchhoff(sub, span, fixed, {}, pot, opt.solver);
  std::vector<uint8_t> halves(net.n_edges(), 0);
  for (std::size_t k = 0; k < sub.n_edges(); ++k) {
    const int32_t a = sub.i[k], b = sub.j[k];
    if (!span[a] || !span[b]) continue;
    const double I = sub.g[k] * (pot[a] - pot[b]);
    const std::size_t e = edge_of[k];
    if (half_sign[k] == 0) {
      res.edge_current[e] = I;
    } else {  // a cut edge reports the mean of its two halves' currents, along i -> j
      res.edge_current[e] = (res.edge_current[e] * halves[e] + half_sign[k] * I) / (halves[e] + 1);
      ++halves[e];
    }
    const int8_t ta = terminal[a], tb = terminal[b];
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
    res.length = cell_width(net.cell.h.inverse(), k);
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
