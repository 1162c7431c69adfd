#include "tomodem/network/image_transport.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <fstream>

#include "image_multigrid.hpp"
#include "tomodem/linalg/amg.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/h5.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/packing_io.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/core/uniform_grid.hpp"

namespace tomodem::network {

namespace {
using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }
const char* kAxis[3] = {"x", "y", "z"};

// TOMODEM_IMAGE_DEBUG=1: the resident and peak memory after each stage of a solve (how the
// bytes per voxel of image_transport_bytes_per_voxel were measured).
void stage(const char* what) {
  static const bool on = std::getenv("TOMODEM_IMAGE_DEBUG") != nullptr;
  if (!on) return;
  std::ifstream f("/proc/self/status");
  std::string line, rss, hwm;
  while (std::getline(f, line)) {
    if (line.rfind("VmRSS:", 0) == 0) rss = line.substr(6);
    if (line.rfind("VmHWM:", 0) == 0) hwm = line.substr(6);
  }
  std::fprintf(stderr, "  image %-28s RSS %s, peak %s\n", what, rss.c_str(), hwm.c_str());
}
}  // namespace

std::array<std::size_t, 3> label_image_shape(const std::string& path, const std::string& dataset) {
  const h5::File f(path, h5::File::Mode::read);
  if (!f.exists(dataset))
    throw InputError(path, dataset, "missing", "not a label volume written by tomodem-segment (no dataset " + dataset + ")");
  const auto s = f.shape(dataset);
  if (s.size() != 3 || s[0] == 0 || s[1] == 0 || s[2] == 0) {
    std::string t;
    for (auto d : s) t += (t.empty() ? "" : "x") + std::to_string(d);
    throw InputError(path, dataset, "shape " + (t.empty() ? std::string("scalar") : t),
                     "expected a non-empty 3-D label volume (z, y, x)");
  }
  return {s[2], s[1], s[0]};
}

LabelImage read_label_image(const std::string& path, const std::string& dataset) {
  const auto n = label_image_shape(path, dataset);
  const h5::File f(path, h5::File::Mode::read);
  const double unit = h5_length_unit(f, false);  // metres per unit of spacing and origin (m when unstated)
  LabelImage im;
  im.nx = n[0];
  im.ny = n[1];
  im.nz = n[2];
  if (f.has_attr(dataset, "spacing")) {
    const auto sp = f.attr_doubles(dataset, "spacing");
    if (sp.size() != 3) throw InputError(path, dataset + "@spacing", std::to_string(sp.size()) + " values", "expected x, y, z (m)");
    for (int k = 0; k < 3; ++k) {
      if (!(std::isfinite(sp[k]) && sp[k] > 0))
        throw InputError(path, dataset + "@spacing", value_text(sp[k]),
                         std::string("the ") + kAxis[k] + " voxel size must be finite and > 0 (m)");
      im.spacing[k] = sp[k] * unit;
    }
  } else {
    warn(path + ": " + dataset + " has no spacing attribute: 1 m voxels assumed (sigma_eff and tortuosity do not "
         "depend on the voxel size when it is the same along x, y and z)");
  }
  if (f.has_attr(dataset, "origin")) {
    const auto o = f.attr_doubles(dataset, "origin");
    if (o.size() == 3 && std::isfinite(o[0]) && std::isfinite(o[1]) && std::isfinite(o[2]))
      im.origin = {o[0] * unit, o[1] * unit, o[2] * unit};
  }
  im.v = f.read_uint8(dataset);
  if (im.v.size() != im.size())
    throw InputError(path, dataset, std::to_string(im.v.size()) + " values", "does not match its shape");
  return im;
}

// Matrix-free path, per voxel: the labels (1), the reach marks or the unknown index (4). Per
// unknown: the solution and the CG vectors r, p, w and the cycle's scratch (40), the inverse
// diagonal (4, float), the map to the first coarse level (4), the coarse levels (~1/7 of a fine
// row each as compressed rows: ~16). Measured peak RSS: 162 MB for a 128³ phantom (2.03 M
// unknowns), 1.20 GB at 256³ (16.3 M): ~72 bytes per voxel; 80 is used. The assembled reference
// path (ImageTransportOptions::assembled) needs ~420. Fields: two floats per voxel and a double
// while writing.
double image_transport_bytes_per_voxel(bool fields) { return 80 + (fields ? 8 + 8 : 0); }

namespace {
/// The voxel grid of one solve: sizes, spacing, the axis of the potential drop and the sides.
struct Grid {
  const LabelImage& im;
  const ImageTransportOptions& opt;
  int ax;
  std::size_t nv;
  long n[3], stride[3];
  double h[3], area[3];

  Grid(const LabelImage& image, const ImageTransportOptions& options)
      : im(image), opt(options), ax(options.axis), nv(image.size()),
        n{static_cast<long>(image.nx), static_cast<long>(image.ny), static_cast<long>(image.nz)},
        stride{1, n[0], n[0] * n[1]},
        h{image.spacing[0], image.spacing[1], image.spacing[2]},
        area{h[1] * h[2], h[0] * h[2], h[0] * h[1]} {}
  double sig(std::size_t i) const { return opt.conductivity[im.v[i]]; }
  // The neighbour of voxel i (coordinates c) across its face (k, dir); -1 when there is none.
  long neighbour(long i, const long* c, int k, int dir) const {
    const long q = c[k] + dir;
    if (q >= 0 && q < n[k]) return i + dir * stride[k];
    if (k == ax || !opt.periodic_sides || n[k] < 2) return -1;
    return i + (dir > 0 ? -(n[k] - 1) : (n[k] - 1)) * stride[k];
  }
  void coords(long i, long* c) const {
    c[0] = i % n[0];
    c[1] = (i / n[0]) % n[1];
    c[2] = i / (n[0] * n[1]);
  }
  // Face conductance between voxels a and b across a face normal to k (harmonic mean).
  double face_g(double sa, double sb, int k) const { return area[k] / h[k] * 2.0 * sa * sb / (sa + sb); }
  double boundary_g(double s) const { return area[ax] / h[ax] * 2.0 * s; }
};

/// Reach: bit 1 from the low face, bit 2 from the high face (flood fill over conducting voxels).
std::vector<uint8_t> reach(const Grid& g) {
  std::vector<uint8_t> mark(g.nv, 0);
  std::vector<int32_t> queue;
  for (int side = 0; side < 2; ++side) {
    const uint8_t bit = side == 0 ? 1 : 2;
    queue.clear();
    const long layer = side == 0 ? 0 : g.n[g.ax] - 1;
    for (long i = 0; i < static_cast<long>(g.nv); ++i) {
      long c[3];
      g.coords(i, c);
      if (c[g.ax] == layer && g.sig(i) > 0) {
        mark[i] |= bit;
        queue.push_back(static_cast<int32_t>(i));
      }
    }
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const long i = queue[head];
      long c[3];
      g.coords(i, c);
      for (int k = 0; k < 3; ++k)
        for (int dir = -1; dir <= 1; dir += 2) {
          const long j = g.neighbour(i, c, k, dir);
          if (j < 0 || (mark[j] & bit) || !(g.sig(j) > 0)) continue;
          mark[j] |= bit;
          queue.push_back(static_cast<int32_t>(j));
        }
    }
  }
  return mark;
}

/// Spanning, dead-end and isolated fractions of the conducting voxels; returns the spanning count.
std::size_t classify(const std::vector<uint8_t>& mark, std::size_t conducting, ImageAxisResult& res) {
  std::size_t spanning = 0, dead = 0;
  for (std::size_t i = 0; i < mark.size(); ++i) {
    spanning += mark[i] == 3;
    dead += mark[i] == 1 || mark[i] == 2;
  }
  if (conducting > 0) {
    res.spanning_fraction = static_cast<double>(spanning) / conducting;
    res.dead_end_fraction = static_cast<double>(dead) / conducting;
    res.isolated_fraction = static_cast<double>(conducting - spanning - dead) / conducting;
  }
  res.percolates = spanning > 0;
  return spanning;
}

/// The finite-volume system over the spanning voxels (unknowns in storage order).
struct System {
  std::vector<int32_t> index;  ///< per voxel: its unknown, -1 off the spanning clusters
  std::vector<int32_t> vox;    ///< per unknown: its voxel
  std::vector<int32_t> start, column;
  std::vector<double> value, rhs, x;
  int32_t nu = 0;
};

/// Numbers the spanning voxels (mark 3).
void number_unknowns(const std::vector<uint8_t>& mark, System& S) {
  const std::size_t nv = mark.size();
  S.index.assign(nv, -1);
  for (std::size_t i = 0; i < nv; ++i)
    if (mark[i] == 3) S.index[i] = S.nu++;
  S.vox.resize(S.nu);
  for (std::size_t i = 0; i < nv; ++i)
    if (S.index[i] >= 0) S.vox[S.index[i]] = static_cast<int32_t>(i);
}

/// Assembles the CSR matrix (full symmetric storage, sorted columns, duplicates merged: a periodic
/// direction of 2 voxels couples the pair across two faces), the right-hand side of a unit
/// potential on the low face, and the initial guess.
void assemble(const Grid& g, System& S) {
  const int32_t nu = S.nu;
  const int ax = g.ax;
  S.start.assign(static_cast<std::size_t>(nu) + 1, 0);
  S.rhs.assign(nu, 0.0);
  S.x.resize(nu);
  S.column.reserve(static_cast<std::size_t>(nu) * 7);
  S.value.reserve(static_cast<std::size_t>(nu) * 7);
  for (int32_t r = 0; r < nu; ++r) {
    const long i = S.vox[r];
    long c[3];
    g.coords(i, c);
    const double si = g.sig(i);
    std::pair<int32_t, double> e[7];
    int ne = 0;
    double diag = 0;
    for (int k = 0; k < 3; ++k)
      for (int dir = -1; dir <= 1; dir += 2) {
        const long j = g.neighbour(i, c, k, dir);
        if (j < 0 || j == i) continue;
        const int32_t cj = S.index[j];
        if (cj < 0) continue;  // a conducting neighbour of a spanning voxel spans too: j does not conduct
        const double gf = g.face_g(si, g.sig(j), k);
        diag += gf;
        int m = 0;
        while (m < ne && e[m].first != cj) ++m;
        if (m == ne) e[ne++] = {cj, -gf};
        else e[m].second -= gf;
      }
    if (c[ax] == 0) {
      diag += g.boundary_g(si);
      S.rhs[r] += g.boundary_g(si) * 1.0;
    }
    if (c[ax] == g.n[ax] - 1) diag += g.boundary_g(si);
    e[ne++] = {r, diag};
    for (int m = 1; m < ne; ++m)  // insertion sort of at most 7 entries
      for (int q = m; q > 0 && e[q - 1].first > e[q].first; --q) std::swap(e[q - 1], e[q]);
    for (int m = 0; m < ne; ++m) {
      S.column.push_back(e[m].first);
      S.value.push_back(e[m].second);
    }
    S.start[r + 1] = static_cast<int32_t>(S.column.size());
    S.x[r] = 1.0 - (c[ax] + 0.5) / g.n[ax];  // the initial guess: the linear profile of a straight channel
  }
}

/// CG preconditioned by smoothed-aggregation multigrid.
void solve(System& S, const ImageTransportOptions& opt, ImageAxisResult& res) {
  const CsrView A{S.nu, S.start.data(), S.column.data(), S.value.data()};
  const auto ts = Clock::now();
  AmgOptions ao;
  // Aggregates of radius 2 (operator complexity ~1.26 instead of ~1.56 at radius 1) and one
  // smoothing sweep: on a 128³ phantom (2 M unknowns, two cores) 4.1 s and 0.86 GB instead of
  // 5.2 s and 1.0 GB with the defaults; 23 iterations instead of 16, each much cheaper.
  ao.aggregate_radius = 2;
  ao.sweeps = 1;
  const Amg amg(A, NearNullspace{}, ao);
  res.setup_time_s = seconds_since(ts);
  res.levels = static_cast<int>(amg.stats().rows.size());
  res.operator_complexity = amg.stats().operator_complexity;
  const int cap = opt.max_iterations > 0 ? opt.max_iterations : 10000;
  const PcgReport pr = pcg(A, &amg, S.rhs.data(), S.x.data(), opt.tolerance, cap);
  res.solve_time_s = pr.seconds;
  res.iterations = pr.iterations;
  res.residual = pr.residual;
  res.converged = pr.converged;
}

/// Currents through the two Dirichlet faces (A per volt), σ_eff and the tortuosity.
void face_currents(const Grid& g, const std::vector<int32_t>& index, const std::vector<double>& x, ImageAxisResult& res) {
  const int ax = g.ax;
  double in = 0, out = 0;
  for (long i = 0; i < static_cast<long>(g.nv); ++i) {
    const int32_t r = index[i];
    if (r < 0) continue;
    long c[3];
    g.coords(i, c);
    if (c[ax] == 0) in += g.boundary_g(g.sig(i)) * (1.0 - x[r]);
    if (c[ax] == g.n[ax] - 1) out += g.boundary_g(g.sig(i)) * x[r];
  }
  const double length = g.n[ax] * g.h[ax], cross = g.area[ax] * (static_cast<double>(g.nv) / g.n[ax]);
  res.current_in = in;
  res.current_out = out;
  res.flux_imbalance = in + out > 0 ? std::abs(in - out) / (in + out) : 0;
  res.sigma_eff = 0.5 * (in + out) * length / cross;
  res.sigma_eff_error = std::max(res.flux_imbalance, res.residual);
  res.tortuosity = res.sigma_eff > 0 ? res.porosity * res.sigma0 / res.sigma_eff : std::numeric_limits<double>::infinity();
}

/// Per voxel: the potential and the magnitude of the current density (face fluxes averaged per axis).
void fill_fields(const Grid& g, const std::vector<int32_t>& index, const std::vector<double>& x, ImageAxisResult& res) {
  res.potential.assign(g.nv, std::numeric_limits<float>::quiet_NaN());
  res.current.assign(g.nv, 0.0f);
  for (long i = 0; i < static_cast<long>(g.nv); ++i) {
    const int32_t r = index[i];
    if (r < 0) continue;
    res.potential[i] = static_cast<float>(x[r]);
    long c[3];
    g.coords(i, c);
    const double si = g.sig(i);
    double j2 = 0;
    for (int k = 0; k < 3; ++k) {
      double jf[2] = {0, 0};  // flux density in +k through the lower and the upper face
      for (int side = 0; side < 2; ++side) {
        const int dir = side == 0 ? -1 : 1;
        const long j = g.neighbour(i, c, k, dir);
        if (j >= 0 && j != i && index[j] >= 0) {
          const double gk = 2.0 * si * g.sig(j) / (si + g.sig(j)) / g.h[k];
          jf[side] = side == 0 ? gk * (x[index[j]] - x[r]) : gk * (x[r] - x[index[j]]);
        } else if (k == g.ax && side == 0 && c[k] == 0) {
          jf[0] = 2.0 * si / g.h[k] * (1.0 - x[r]);
        } else if (k == g.ax && side == 1 && c[k] == g.n[k] - 1) {
          jf[1] = 2.0 * si / g.h[k] * x[r];
        }
      }
      const double jk = 0.5 * (jf[0] + jf[1]);
      j2 += jk * jk;
    }
    res.current[i] = static_cast<float>(std::sqrt(j2));
  }
}

/// The matrix-free path: per voxel its unknown (4 bytes), per unknown the CG vectors and the
/// voxel-aggregation multigrid of image_multigrid.hpp.
void solve_matrix_free(const Grid& g, std::vector<uint8_t>& mark, ImageAxisResult& res) {
  std::vector<int32_t> index(g.nv, -1);
  int32_t nu = 0;
  for (std::size_t i = 0; i < g.nv; ++i)
    if (mark[i] == 3) index[i] = nu++;
  std::vector<uint8_t>().swap(mark);
  stage("unknowns numbered");
  res.unknowns = static_cast<std::size_t>(nu);
  std::vector<double> x(static_cast<std::size_t>(nu));
  for (long i = 0; i < static_cast<long>(g.nv); ++i)
    if (index[i] >= 0) {
      long c[3];
      g.coords(i, c);
      x[index[i]] = 1.0 - (c[g.ax] + 0.5) / g.n[g.ax];  // the linear profile of a straight channel
    }
  detail::VoxelSystem vs;
  for (int k = 0; k < 3; ++k) {
    vs.n[k] = g.n[k];
    vs.g[k] = g.area[k] / g.h[k];
  }
  vs.axis = g.ax;
  vs.periodic = g.opt.periodic_sides;
  vs.g_boundary = 2.0 * g.area[g.ax] / g.h[g.ax];
  vs.label = g.im.v.data();
  vs.sigma = g.opt.conductivity.data();
  vs.index = index.data();
  vs.unknowns = nu;
  detail::MatrixFreeOptions mo;
  mo.tolerance = g.opt.tolerance;
  mo.max_iterations = g.opt.max_iterations > 0 ? g.opt.max_iterations : 10000;
  if (const char* e = std::getenv("TOMODEM_IMAGE_MG"))  // tuning: "cycle,sweeps,omega"
    std::sscanf(e, "%d,%d,%lf", &mo.cycle, &mo.sweeps, &mo.omega);
  const detail::MatrixFreeReport mr = detail::solve_matrix_free(vs, x, mo);
  stage("solved (matrix-free)");
  res.nonzeros = mr.nonzeros;
  res.levels = mr.levels;
  res.operator_complexity = mr.operator_complexity;
  res.setup_time_s = mr.setup_s;
  res.solve_time_s = mr.solve_s;
  res.iterations = mr.iterations;
  res.residual = mr.residual;
  res.converged = mr.converged;
  face_currents(g, index, x, res);
  if (g.opt.fields) fill_fields(g, index, x, res);
}
}  // namespace

ImageAxisResult image_conductivity(const LabelImage& im, const ImageTransportOptions& opt) {
  const auto t0 = Clock::now();
  ImageAxisResult res;
  const Grid g(im, opt);
  res.axis = g.ax;
  const std::size_t nv = g.nv;
  double sigma0 = 0;
  for (double s : opt.conductivity) sigma0 = std::max(sigma0, s);
  res.sigma0 = sigma0;
  if (nv > 2147483645u) throw InputError("", "--image", std::to_string(nv) + " voxels", "more than 2^31 - 3 voxels");

  std::size_t conducting = 0;
  for (std::size_t i = 0; i < nv; ++i) conducting += g.sig(i) > 0;
  res.porosity = static_cast<double>(conducting) / static_cast<double>(nv);
  std::vector<uint8_t> mark = reach(g);
  stage("flood fill");
  const std::size_t spanning = classify(mark, conducting, res);
  if (!res.percolates) {
    res.tortuosity = std::numeric_limits<double>::infinity();
    res.converged = true;
    if (opt.fields) {
      res.potential.assign(nv, std::numeric_limits<float>::quiet_NaN());
      res.current.assign(nv, 0.0f);
    }
    res.wall_time_s = seconds_since(t0);
    return res;
  }
  if (7.0 * spanning > 2147483647.0)
    throw InputError("", "--image", std::to_string(spanning) + " connected voxels",
                     "more matrix entries than the solver's 32-bit indices hold; crop or downsample the volume");

  if (!opt.assembled) {
    solve_matrix_free(g, mark, res);
  } else {
    System S;
    number_unknowns(mark, S);
    std::vector<uint8_t>().swap(mark);
    res.unknowns = static_cast<std::size_t>(S.nu);
    assemble(g, S);
    stage("assembled");
    res.nonzeros = S.column.size();
    solve(S, opt, res);
    stage("solved (assembled)");
    face_currents(g, S.index, S.x, res);
    if (opt.fields) {
      std::vector<int32_t>().swap(S.column);
      std::vector<double>().swap(S.value);
      fill_fields(g, S.index, S.x, res);
    }
  }
  res.wall_time_s = seconds_since(t0);
  return res;
}

void write_image_fields(const std::string& path, const LabelImage& im, const std::vector<ImageAxisResult>& results,
                        const std::string& parameters) {
  UniformGrid grid;
  grid.dims = {im.nx, im.ny, im.nz};
  grid.spacing = im.spacing;
  for (int k = 0; k < 3; ++k) grid.corner[k] = im.origin[k] - 0.5 * im.spacing[k];  // origin: centre of voxel 0
  std::vector<GridBlock> blocks;
  for (const auto& r : results)
    blocks.push_back({kAxis[r.axis],
                      {{"potential", r.potential, "V per V applied (1 on the low face, 0 on the high face)"},
                       {"current_magnitude", r.current, "A/m^2 per V and per unit conductivity"}}});
  GridProvenance prov;
  prov.tool = "tomodem-conduct --image";
  prov.attributes = {{"parameters", parameters}};
  write_uniform_grid(path, grid, blocks, prov);
}

}  // namespace tomodem::network
