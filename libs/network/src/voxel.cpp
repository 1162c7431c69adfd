#include "tomodem/network/voxel.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/network/graph.hpp"
#include "tomodem/network/image_transport.hpp"
#include "tomodem/spatial/image.hpp"

namespace tomodem::network {

namespace {
// Bytes per voxel of the cross-check: the label (1) and the image solver's working set.
double bytes_per_voxel() { return 1 + image_transport_bytes_per_voxel(false); }

// Conductivity of each material in the cross-check (0: does not conduct).
std::vector<double> material_sigma(const Packing& pk, const std::vector<std::string>& phases) {
  const std::size_t nm = pk.materials.size();
  std::vector<double> sigma_of(nm, phases.empty() ? 1.0 : 0.0);
  for (std::size_t m = 0; m < nm; ++m) sigma_of[m] *= pk.materials[m].conductivity;
  for (const auto& name : phases)
    for (std::size_t m = 0; m < nm; ++m)
      if (pk.materials[m].name == name) sigma_of[m] = pk.materials[m].conductivity;
  return sigma_of;
}

// Mean diameter of the particles whose material conducts (all particles when none does).
double mean_diameter_of(const Packing& pk, const std::vector<double>& sigma_of) {
  double sum = 0, all = 0;
  std::size_t n = 0;
  for (std::size_t p = 0; p < pk.particles.size(); ++p) {
    all += 2 * pk.particles.radius[p];
    const int m = pk.particles.phase[p];
    if (m >= 0 && static_cast<std::size_t>(m) < sigma_of.size() && sigma_of[m] > 0) {
      sum += 2 * pk.particles.radius[p];
      ++n;
    }
  }
  if (n) return sum / n;
  return pk.particles.size() ? all / pk.particles.size() : 0.0;
}

// The unit of a per-diameter resolution: the given diameter (a box cut from a packing keeps the
// whole packing's) or the conducting mean diameter.
double unit_diameter(const Packing& pk, const VoxelOptions& opt) {
  return opt.diameter > 0 ? opt.diameter : mean_diameter_of(pk, material_sigma(pk, opt.phases));
}

// The voxel size: the longest edge over the resolution, or the conducting particles' mean
// diameter over it (--voxel-check 16d).
double voxel_size_of(const Packing& pk, const VoxelOptions& opt) {
  const Mat3& h = pk.cell.h;
  if (opt.per_diameter) return unit_diameter(pk, opt) / opt.resolution;
  return std::max({h(0, 0), h(1, 1), h(2, 2)}) / opt.resolution;
}

/// A conducting solid of the image: a sphere (particle) or a cylinder of radius r from a to b
/// (the part of a bond outside the spheres: the neck the network gives the bond).
struct Solid {
  Vec3 a, b;
  double r = 0;
  int material = 0;
  bool cylinder = false;
  bool contains(const Vec3& p) const {
    if (!cylinder) return norm2(p - a) <= r * r;
    const Vec3 ab = b - a, ap = p - a;
    const double L2 = norm2(ab), t = dot(ap, ab);
    if (t < 0 || t > L2) return false;
    return norm2(ap) - t * t / L2 <= r * r;
  }
  Vec3 lower() const { return {std::min(a[0], b[0]) - r, std::min(a[1], b[1]) - r, std::min(a[2], b[2]) - r}; }
  Vec3 upper() const { return {std::max(a[0], b[0]) + r, std::max(a[1], b[1]) + r, std::max(a[2], b[2]) + r}; }
};

/// The particles of the conducting phases and, when `bonds`, a cylinder of radius a_b for each
/// intact bond between two of them (half in each particle's material), in cell coordinates.
std::vector<Solid> conducting_solids(const Packing& pk, const std::vector<double>& sigma_of, bool bonds) {
  std::vector<Solid> s;
  for (std::size_t p = 0; p < pk.particles.size(); ++p) {
    const int m = pk.particles.phase[p];
    if (!(sigma_of[m] > 0)) continue;
    const Vec3 c = pk.particles.position[p] - pk.cell.origin;
    s.push_back({c, c, pk.particles.radius[p], m, false});
  }
  if (!bonds) return s;
  const Mat3 hinv = pk.cell.h.inverse();
  const BondTable& B = pk.bonds;
  for (std::size_t k = 0; k < B.size(); ++k) {
    if ((!B.state.empty() && B.state[k] != BondTable::intact) || B.radius.empty()) continue;
    const std::size_t i = static_cast<std::size_t>(B.i[k]), j = static_cast<std::size_t>(B.j[k]);
    if (i >= pk.particles.size() || j >= pk.particles.size()) continue;
    const int mi = pk.particles.phase[i], mj = pk.particles.phase[j];
    if (!(sigma_of[mi] > 0 && sigma_of[mj] > 0) || !(B.radius[k] > 0)) continue;
    const Vec3 xi = pk.particles.position[i] - pk.cell.origin;
    const Vec3 xj = pk.particles.position[j] - pk.cell.origin +
                    pk.cell.h * spatial::as_vector(spatial::minimum_image(pk.cell, hinv, pk.particles.position[i],
                                                                          pk.particles.position[j]));
    const Vec3 mid = 0.5 * (xi + xj);
    s.push_back({xi, mid, B.radius[k], mi, true});
    s.push_back({mid, xj, B.radius[k], mj, true});
  }
  return s;
}

// Distance from p to the segment a-b.
double segment_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double L2 = norm2(ab);
  const double t = L2 > 0 ? std::clamp(dot(p - a, ab) / L2, 0.0, 1.0) : 0.0;
  return norm(p - (a + t * ab));
}

/// A voxel cut by a solid's surface: the voxel, the solid, and the periodic image of the voxel
/// (in cells) in which the solid was met.
struct Cut {
  int32_t voxel, solid;
  int8_t image[3];
  bool operator<(const Cut& o) const { return voxel < o.voxel || (voxel == o.voxel && solid < o.solid); }
};

/// Partial-volume rasterisation: a voxel wholly inside a solid takes its material's label
/// (1..nm); a voxel cut by a surface is sampled at s³ points and takes the label of its mean
/// conductivity on a scale of (255 − nm) levels of σmax (a quantisation of 0.2 % of σmax).
/// Fills `label_sigma` and returns the conducting volume fraction.
double rasterise(const std::vector<Solid>& solids, const Cell& cell, const int n[3], const double d[3], int s,
                 const std::vector<double>& sigma_of, LabelImage& im, std::array<double, 256>& label_sigma) {
  const int nm = static_cast<int>(sigma_of.size());
  const double smax = *std::max_element(sigma_of.begin(), sigma_of.end());
  const int levels = 255 - nm;
  for (int m = 0; m < nm; ++m) label_sigma[m + 1] = sigma_of[m];
  for (int k = 1; k <= levels; ++k) label_sigma[nm + k] = smax * k / levels;
  const double half_diag = 0.5 * std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  auto id = [&](int x, int y, int z) { return (static_cast<std::size_t>(z) * n[1] + y) * n[0] + x; };
  auto wrap = [&](int x, int k, int* image) {
    const int w = ((x % n[k]) + n[k]) % n[k];
    *image = (x - w) / n[k];
    return w;
  };
  std::vector<Cut> cut;
  for (std::size_t q = 0; q < solids.size(); ++q) {
    const Solid& sd = solids[q];
    const Vec3 lo = sd.lower(), hi = sd.upper();
    int l[3], u[3];
    for (int k = 0; k < 3; ++k) {
      l[k] = static_cast<int>(std::floor(lo[k] / d[k] - 0.5));
      u[k] = static_cast<int>(std::ceil(hi[k] / d[k] - 0.5));
      if (!cell.periodic[k]) { l[k] = std::max(l[k], 0); u[k] = std::min(u[k], n[k] - 1); }
    }
    for (int z = l[2]; z <= u[2]; ++z)
      for (int y = l[1]; y <= u[1]; ++y)
        for (int x = l[0]; x <= u[0]; ++x) {
          const Vec3 c((x + 0.5) * d[0], (y + 0.5) * d[1], (z + 0.5) * d[2]);
          // The distance from the voxel centre to the solid's axis decides inside, outside or cut.
          const double dist = sd.cylinder ? segment_distance(c, sd.a, sd.b) : norm(c - sd.a);
          if (dist - half_diag >= sd.r) continue;
          int img[3];
          const int wx = wrap(x, 0, &img[0]), wy = wrap(y, 1, &img[1]), wz = wrap(z, 2, &img[2]);
          const std::size_t v = id(wx, wy, wz);
          uint8_t& lab = im.v[v];
          if (lab >= 1 && lab <= nm) continue;  // already wholly inside a solid
          if (!sd.cylinder && dist + half_diag <= sd.r) { lab = static_cast<uint8_t>(sd.material + 1); continue; }
          cut.push_back({static_cast<int32_t>(v), static_cast<int32_t>(q),
                         {static_cast<int8_t>(img[0]), static_cast<int8_t>(img[1]), static_cast<int8_t>(img[2])}});
        }
  }
  std::sort(cut.begin(), cut.end());
  double cut_volume = 0;
  const double inv = 1.0 / (s * s * s);
  for (std::size_t b = 0; b < cut.size();) {
    std::size_t e = b;
    while (e < cut.size() && cut[e].voxel == cut[b].voxel) ++e;
    const std::size_t v = static_cast<std::size_t>(cut[b].voxel);
    if (im.v[v] >= 1 && im.v[v] <= nm) { b = e; continue; }
    const long x = static_cast<long>(v % n[0]), y = static_cast<long>((v / n[0]) % n[1]),
               z = static_cast<long>(v / (static_cast<std::size_t>(n[0]) * n[1]));
    double sum = 0, inside = 0;
    for (int i = 0; i < s; ++i)
      for (int j = 0; j < s; ++j)
        for (int k = 0; k < s; ++k)
          for (std::size_t c = b; c < e; ++c) {  // the first solid that holds the sample gives its material
            const Cut& ct = cut[c];
            const Vec3 p((x + ct.image[0] * n[0] + (i + 0.5) / s) * d[0], (y + ct.image[1] * n[1] + (j + 0.5) / s) * d[1],
                         (z + ct.image[2] * n[2] + (k + 0.5) / s) * d[2]);
            const Solid& sd = solids[ct.solid];
            if (!sd.contains(p)) continue;
            sum += sigma_of[sd.material];
            inside += 1;
            break;
          }
    const int level = static_cast<int>(std::lround(sum * inv / smax * levels));
    im.v[v] = level > 0 ? static_cast<uint8_t>(nm + level) : 0;
    cut_volume += inside * inv;
    b = e;
  }
  std::size_t full = 0;
  for (uint8_t lab : im.v) full += lab >= 1 && lab <= nm;
  return (full + cut_volume) / im.v.size();
}
}  // namespace

double conducting_mean_diameter(const Packing& pk, const std::vector<std::string>& phases) {
  return mean_diameter_of(pk, material_sigma(pk, phases));
}

Packing packing_box(const Packing& pk, const Vec3& lower, const Vec3& edge, const std::string& option) {
  const Mat3& h = pk.cell.h;
  char box[160];
  std::snprintf(box, sizeof box, "lower corner %.4g %.4g %.4g m, edge %.4g %.4g %.4g m", lower[0], lower[1], lower[2],
                edge[0], edge[1], edge[2]);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      if (r != c && h(r, c) != 0) throw InputError("", option, box, "needs a rectangular cell");
  const Vec3 lo = lower - pk.cell.origin;
  for (int k = 0; k < 3; ++k) {
    const double L = h(k, k);
    if (!(edge[k] > 0) || !std::isfinite(edge[k]) || !std::isfinite(lo[k]))
      throw InputError("", option, box, "the box needs finite positive edges");
    if (pk.cell.periodic[k] && edge[k] > 0.5 * L)
      throw InputError("", option, box,
                       std::string("the box is longer than half the periodic cell along ") + char('x' + k) +
                           " (" + value_text(L) + " m): its pairs would not be minimum images");
    if (!pk.cell.periodic[k] && (lo[k] < 0 || lo[k] + edge[k] > L * (1 + 1e-12)))
      throw InputError("", option, box, std::string("the box leaves the (not periodic) cell along ") + char('x' + k));
  }
  std::vector<uint8_t> keep(pk.particles.size(), 0);
  std::vector<Vec3> inside(pk.particles.size());
  for (std::size_t p = 0; p < pk.particles.size(); ++p) {
    Vec3 s = pk.particles.position[p] - lower;
    bool in = true;
    for (int k = 0; k < 3; ++k) {
      if (pk.cell.periodic[k]) s[k] -= h(k, k) * std::floor(s[k] / h(k, k));
      in = in && s[k] >= 0 && s[k] < edge[k];
    }
    keep[p] = in;
    inside[p] = lower + s;
  }
  Packing out = select_particles(pk, keep);
  std::size_t q = 0;
  for (std::size_t p = 0; p < pk.particles.size(); ++p)
    if (keep[p]) out.particles.position[q++] = inside[p];
  out.cell = Cell::box(lower, lower + edge, false);
  return out;
}

void check_voxel_grid(const Packing& pk, const VoxelOptions& opt) {
  const Mat3& h = pk.cell.h;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      if (r != c && h(r, c) != 0)
        throw InputError(opt.source, "/cell/h", "non-rectangular", "the voxel cross-check (--voxel-check) needs a rectangular cell");
  const std::string res = std::to_string(opt.resolution) + (opt.per_diameter ? "d" : "");
  if (opt.resolution < 2)
    throw InputError("", "--voxel-check", res,
                     opt.per_diameter ? "need at least 2 voxels per diameter" : "need at least 2 voxels along the longest edge");
  const double L[3] = {h(0, 0), h(1, 1), h(2, 2)};
  if (!(L[0] > 0 && L[1] > 0 && L[2] > 0))
    throw InputError(opt.source, "/cell/h", "diagonal " + std::to_string(L[0]) + " " + std::to_string(L[1]) + " " +
                                                std::to_string(L[2]),
                     "the voxel cross-check needs positive cell lengths");
  const double vs = voxel_size_of(pk, opt);
  double nv = 1;
  for (double l : L) nv *= std::max(1.0, std::round(l / vs));
  char count[32];
  std::snprintf(count, sizeof count, "%.3g", nv);
  const std::string what = opt.per_diameter ? " voxels per mean diameter (" : " voxels along the longest edge (";
  check_memory_request(nv * bytes_per_voxel(), "", "--voxel-check", res,
                       "the voxel cross-check at " + std::to_string(opt.resolution) + what + count + " voxels)");
  if (nv > 2147483645.0)
    throw InputError("", "--voxel-check", res,
                     std::string("a grid of ") + count + " voxels: more than the solver's 2^31 - 3 nodes; "
                     "choose a coarser resolution");
}

VoxelResult voxel_conductivity(const Packing& pk, const VoxelOptions& opt) {
  const auto t0 = std::chrono::steady_clock::now();
  const Mat3& h = pk.cell.h;
  check_voxel_grid(pk, opt);
  const std::size_t nm = pk.materials.size();
  if (nm > 127)
    throw InputError(opt.source, "/materials", std::to_string(nm) + " materials",
                     "the voxel cross-check labels voxels in 8 bits, a label per material and 128 partial-volume "
                     "levels at least (at most 127 materials)");
  const std::vector<double> sigma_of = material_sigma(pk, opt.phases);
  const double Lx = h(0, 0), Ly = h(1, 1), Lz = h(2, 2);
  const double vs = voxel_size_of(pk, opt);
  VoxelResult res;
  const int n[3] = {std::max(1, static_cast<int>(std::lround(Lx / vs))), std::max(1, static_cast<int>(std::lround(Ly / vs))),
                    std::max(1, static_cast<int>(std::lround(Lz / vs)))};
  res.nx = n[0]; res.ny = n[1]; res.nz = n[2];
  const double d[3] = {Lx / n[0], Ly / n[1], Lz / n[2]};  // exact fit: slightly anisotropic at worst
  res.voxel_size = vs;
  res.resolution_per_longest_edge = std::max({n[0], n[1], n[2]});
  // Rasterise (partial volume) into a label image and solve it with the segmented-image transport
  // solver: one finite-volume scheme for --image and --voxel-check.
  LabelImage im;
  im.nx = n[0]; im.ny = n[1]; im.nz = n[2];
  im.spacing = {d[0], d[1], d[2]};
  im.origin = {pk.cell.origin[0], pk.cell.origin[1], pk.cell.origin[2]};
  im.v.assign(im.size(), 0);
  ImageTransportOptions io;
  if (*std::max_element(sigma_of.begin(), sigma_of.end()) > 0) {
    const std::vector<Solid> solids = conducting_solids(pk, sigma_of, opt.bonds);
    res.solid_fraction = rasterise(solids, pk.cell, n, d, std::max(1, opt.subsamples), sigma_of, im, io.conductivity);
  }
  res.voxels_per_diameter = unit_diameter(pk, opt) / vs;
  // Neck resolution q = a²/(R* h) (voxel.hpp): the imaged neck is wider by a relative O(1/q).
  if (!opt.neck_radii.empty() && opt.neck_reduced_radii.size() == opt.neck_radii.size()) {
    std::vector<double> a = opt.neck_radii, q(a.size());
    for (std::size_t e = 0; e < a.size(); ++e) q[e] = a[e] * a[e] / std::max(opt.neck_reduced_radii[e], 1e-300);
    std::sort(a.begin(), a.end());
    std::sort(q.begin(), q.end());  // a²/R*, m
    res.neck_min_voxels = a.front() / vs;
    res.neck_median_voxels = a[a.size() / 2] / vs;
    res.neck_resolution_min = q.front() / vs;
    res.neck_resolution_median = q[q.size() / 2] / vs;
    const double unit = opt.per_diameter ? unit_diameter(pk, opt) : std::max({Lx, Ly, Lz});
    res.required_resolution_min = static_cast<long>(std::ceil(kNeckResolution * unit / std::max(q.front(), 1e-300)));
    res.required_resolution_median = static_cast<long>(std::ceil(kNeckResolution * unit / q[q.size() / 2]));
    res.necks_resolved = res.neck_resolution_median >= kNeckResolution;
  }
  io.axis = opt.axis;
  bool lateral_periodic = true;
  for (int k = 0; k < 3; ++k)
    if (k != opt.axis) lateral_periodic = lateral_periodic && pk.cell.periodic[k];
  io.periodic_sides = lateral_periodic;
  io.tolerance = opt.solver.tolerance;
  io.max_iterations = opt.solver.max_iterations;
  const ImageAxisResult r = image_conductivity(im, io);
  res.percolates = r.percolates;
  res.sigma_eff = r.percolates ? r.sigma_eff : 0.0;
  res.conservation_error = r.flux_imbalance;
  res.solver.iterations = r.iterations;
  res.solver.residual = r.residual;
  res.solver.converged = r.converged;
  res.solver.unknowns = r.unknowns;
  res.solver.nonzeros = r.nonzeros;
  res.solver.levels = r.levels;
  res.solver.operator_complexity = r.operator_complexity;
  res.solver.setup_time_s = r.setup_time_s;
  res.solver.solve_time_s = r.solve_time_s;
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
