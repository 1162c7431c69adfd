#include "tomodem/network/voxel.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/network/graph.hpp"

namespace tomodem::network {

namespace {
// Bytes per voxel of the cross-check: conductivity (4), up to four edges of the graph (i, j, g:
// 16 each), the percolation and solver vectors and the CSR matrix of the Kirchhoff solve (~100).
constexpr double kBytesPerVoxel = 200;
}  // namespace

void check_voxel_grid(const Packing& pk, const VoxelOptions& opt) {
  const Mat3& h = pk.cell.h;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      if (r != c && h(r, c) != 0)
        throw InputError(opt.source, "/cell/h", "non-rectangular", "the voxel cross-check (--voxel) needs a rectangular cell");
  const std::string res = std::to_string(opt.resolution);
  if (opt.resolution < 2) throw InputError("", "--voxel", res, "need at least 2 voxels along the longest edge");
  const double L[3] = {h(0, 0), h(1, 1), h(2, 2)};
  if (!(L[0] > 0 && L[1] > 0 && L[2] > 0))
    throw InputError(opt.source, "/cell/h", "diagonal " + std::to_string(L[0]) + " " + std::to_string(L[1]) + " " +
                                                std::to_string(L[2]),
                     "the voxel cross-check needs positive cell lengths");
  const double vs = std::max({L[0], L[1], L[2]}) / opt.resolution;
  double nv = 1;
  for (double l : L) nv *= std::max(1.0, std::round(l / vs));
  char count[32];
  std::snprintf(count, sizeof count, "%.3g", nv);
  check_memory_request(nv * kBytesPerVoxel, "", "--voxel", res,
                       "the voxel cross-check at " + res + " voxels along the longest edge (" + count + " voxels)");
  if (nv > 2147483645.0)
    throw InputError("", "--voxel", res,
                     std::string("a grid of ") + count + " voxels: more than the solver's 2^31 - 3 nodes; "
                     "choose a coarser resolution");
}

VoxelResult voxel_conductivity(const Packing& pk, const VoxelOptions& opt) {
  const auto t0 = std::chrono::steady_clock::now();
  const Mat3& h = pk.cell.h;
  check_voxel_grid(pk, opt);
  const std::size_t nm = pk.materials.size();
  std::vector<double> sigma_of(nm, opt.phases.empty() ? 1.0 : 0.0);
  for (std::size_t m = 0; m < nm; ++m) sigma_of[m] *= pk.materials[m].conductivity;
  for (const auto& name : opt.phases)
    for (std::size_t m = 0; m < nm; ++m)
      if (pk.materials[m].name == name) sigma_of[m] = pk.materials[m].conductivity;
  const double Lx = h(0, 0), Ly = h(1, 1), Lz = h(2, 2);
  const double vs = std::max({Lx, Ly, Lz}) / opt.resolution;
  VoxelResult res;
  const int n[3] = {std::max(1, static_cast<int>(std::lround(Lx / vs))), std::max(1, static_cast<int>(std::lround(Ly / vs))),
                    std::max(1, static_cast<int>(std::lround(Lz / vs)))};
  res.nx = n[0]; res.ny = n[1]; res.nz = n[2];
  const double d[3] = {Lx / n[0], Ly / n[1], Lz / n[2]};  // exact fit: slightly anisotropic at worst
  res.voxel_size = vs;
  const std::size_t nv = static_cast<std::size_t>(n[0]) * n[1] * n[2];
  auto id = [&](int x, int y, int z) { return (static_cast<std::size_t>(x) * n[1] + y) * n[2] + z; };
  std::vector<float> sig(nv, 0.0f);
  // Rasterise: voxel centres inside spheres (periodic directions wrap).
  for (std::size_t p = 0; p < pk.particles.size(); ++p) {
    const double s = sigma_of[pk.particles.phase[p]];
    if (!(s > 0)) continue;
    const Vec3 c = pk.particles.position[p] - pk.cell.origin;
    const double r = pk.particles.radius[p];
    int lo[3], hi[3];
    for (int k = 0; k < 3; ++k) {
      lo[k] = static_cast<int>(std::floor((c[k] - r) / d[k] - 0.5));
      hi[k] = static_cast<int>(std::ceil((c[k] + r) / d[k] - 0.5));
      if (!pk.cell.periodic[k]) { lo[k] = std::max(lo[k], 0); hi[k] = std::min(hi[k], n[k] - 1); }
    }
    for (int x = lo[0]; x <= hi[0]; ++x)
      for (int y = lo[1]; y <= hi[1]; ++y)
        for (int z = lo[2]; z <= hi[2]; ++z) {
          const double dx = (x + 0.5) * d[0] - c[0], dy = (y + 0.5) * d[1] - c[1], dz = (z + 0.5) * d[2] - c[2];
          if (dx * dx + dy * dy + dz * dz > r * r) continue;
          const int w[3] = {((x % n[0]) + n[0]) % n[0], ((y % n[1]) + n[1]) % n[1], ((z % n[2]) + n[2]) % n[2]};
          float& v = sig[id(w[0], w[1], w[2])];
          if (v == 0.0f) v = static_cast<float>(s);
        }
  }
  std::size_t solid = 0;
  for (float v : sig) solid += v > 0;
  res.solid_fraction = static_cast<double>(solid) / nv;
  // Graph: voxels + two electrode nodes (low = nv, high = nv + 1).
  Graph g;
  g.n_nodes = nv + 2;
  const int ax = opt.axis;
  const double face[3] = {d[1] * d[2], d[0] * d[2], d[0] * d[1]};
  for (int x = 0; x < n[0]; ++x)
    for (int y = 0; y < n[1]; ++y)
      for (int z = 0; z < n[2]; ++z) {
        const std::size_t a = id(x, y, z);
        const double sa = sig[a];
        if (sa <= 0) continue;
        const int q[3] = {x, y, z};
        for (int k = 0; k < 3; ++k) {
          int nb[3] = {x, y, z};
          nb[k] += 1;
          if (nb[k] >= n[k]) {
            if (!pk.cell.periodic[k] || k == ax || n[k] < 3) continue;
            nb[k] = 0;
          }
          const std::size_t b = id(nb[0], nb[1], nb[2]);
          const double sb = sig[b];
          if (sb <= 0) continue;
          g.add_edge(static_cast<int32_t>(a), static_cast<int32_t>(b), face[k] / d[k] * 2.0 * sa * sb / (sa + sb));
        }
        if (q[ax] == 0) g.add_edge(static_cast<int32_t>(nv), static_cast<int32_t>(a), face[ax] / d[ax] * 2.0 * sa);
        if (q[ax] == n[ax] - 1) g.add_edge(static_cast<int32_t>(a), static_cast<int32_t>(nv + 1), face[ax] / d[ax] * 2.0 * sa);
      }
  std::vector<int8_t> terminal(g.n_nodes, -1);
  terminal[nv] = 0;
  terminal[nv + 1] = 1;
  const std::vector<uint8_t> span = spanning_nodes(g, terminal);
  res.percolates = span[nv] != 0;
  if (res.percolates) {
    std::vector<uint8_t> fixed(g.n_nodes, 0);
    fixed[nv] = fixed[nv + 1] = 1;
    std::vector<double> pot(g.n_nodes, 0.0);
    for (int x = 0; x < n[0]; ++x)
      for (int y = 0; y < n[1]; ++y)
        for (int z = 0; z < n[2]; ++z) {
          const int q[3] = {x, y, z};
          pot[id(x, y, z)] = 1.0 - (q[ax] + 0.5) / n[ax];
        }
    pot[nv] = 1.0;
    pot[nv + 1] = 0.0;
    res.solver = solve_kirchhoff(g, span, fixed, {}, pot, opt.solver);
    double in = 0, out = 0;
    for (std::size_t e = 0; e < g.n_edges(); ++e) {
      if (!span[g.i[e]] || !span[g.j[e]]) continue;
      const double I = g.g[e] * (pot[g.i[e]] - pot[g.j[e]]);
      if (static_cast<std::size_t>(g.i[e]) == nv) in += I;
      if (static_cast<std::size_t>(g.j[e]) == nv + 1) out += I;
    }
    const double L = n[ax] * d[ax], A = face[ax] * (static_cast<double>(nv) / n[ax]);
    res.sigma_eff = 0.5 * (in + out) * L / A;
    const double imax = std::max(std::abs(in), std::abs(out));
    res.conservation_error = imax > 0 ? std::abs(in - out) / imax : 0;
  }
  res.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

double richardson(double c, double m, double f, double ratio, double* order, double* error) {
  const double d1 = m - c, d2 = f - m;
  if (d1 == 0 || d2 == 0 || (d1 > 0) != (d2 > 0) || std::abs(d2) >= std::abs(d1)) {
    if (order) *order = 0;
    if (error) *error = std::max(std::abs(d1), std::abs(d2));
    return f;
  }
  const double p = std::log(d1 / d2) / std::log(ratio);
  const double ext = f + d2 / (std::pow(ratio, p) - 1.0);
  if (order) *order = p;
  if (error) *error = std::abs(f - ext);
  return ext;
}

}  // namespace tomodem::network
