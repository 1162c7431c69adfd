#include "tomodem/network/voxel.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/network/graph.hpp"
#include "tomodem/network/image_transport.hpp"

namespace tomodem::network {

namespace {
// Bytes per voxel of the cross-check: the label (1) and the image solver's working set.
double bytes_per_voxel() { return 1 + image_transport_bytes_per_voxel(false); }
}  // namespace

void check_voxel_grid(const Packing& pk, const VoxelOptions& opt) {
  const Mat3& h = pk.cell.h;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      if (r != c && h(r, c) != 0)
        throw InputError(opt.source, "/cell/h", "non-rectangular", "the voxel cross-check (--voxel-check) needs a rectangular cell");
  const std::string res = std::to_string(opt.resolution);
  if (opt.resolution < 2) throw InputError("", "--voxel-check", res, "need at least 2 voxels along the longest edge");
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
  check_memory_request(nv * bytes_per_voxel(), "", "--voxel-check", res,
                       "the voxel cross-check at " + res + " voxels along the longest edge (" + count + " voxels)");
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
  if (nm > 255)
    throw InputError(opt.source, "/materials", std::to_string(nm) + " materials",
                     "the voxel cross-check labels voxels by material in 8 bits (at most 255 materials)");
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
  // Rasterise into a label image (label = material index + 1, 0 = void) and solve it with the
  // segmented-image transport solver: one finite-volume scheme for --image and --voxel-check.
  LabelImage im;
  im.nx = n[0]; im.ny = n[1]; im.nz = n[2];
  im.spacing = {d[0], d[1], d[2]};
  im.origin = {pk.cell.origin[0], pk.cell.origin[1], pk.cell.origin[2]};
  im.v.assign(im.size(), 0);
  auto id = [&](int x, int y, int z) { return (static_cast<std::size_t>(z) * n[1] + y) * n[0] + x; };
  double dsum = 0;
  std::size_t dcount = 0;
  for (std::size_t p = 0; p < pk.particles.size(); ++p) {
    const int m = pk.particles.phase[p];
    const double s = sigma_of[m];
    if (!(s > 0)) continue;
    const Vec3 c = pk.particles.position[p] - pk.cell.origin;
    const double r = pk.particles.radius[p];
    dsum += 2 * r;
    ++dcount;
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
          uint8_t& v = im.v[id(w[0], w[1], w[2])];
          if (v == 0) v = static_cast<uint8_t>(m + 1);
        }
  }
  if (dcount) res.voxels_per_diameter = dsum / dcount / vs;
  // Neck resolution: the constriction a carries the resistance, and a neck narrower than a voxel
  // is either lost or a voxel-wide bridge, so the grid must put >= kNeckVoxels voxels across a.
  if (!opt.neck_radii.empty()) {
    std::vector<double> a = opt.neck_radii;
    std::sort(a.begin(), a.end());
    res.neck_min_voxels = a.front() / vs;
    res.neck_median_voxels = a[a.size() / 2] / vs;
    const double lmax = std::max({Lx, Ly, Lz});
    res.required_resolution_min = static_cast<long>(std::ceil(kNeckVoxels * lmax / std::max(a.front(), 1e-300)));
    res.required_resolution_median = static_cast<long>(std::ceil(kNeckVoxels * lmax / a[a.size() / 2]));
    res.necks_resolved = res.neck_min_voxels >= kNeckVoxels;
  }
  ImageTransportOptions io;
  for (std::size_t m = 0; m < nm; ++m) io.conductivity[m + 1] = sigma_of[m];
  io.axis = opt.axis;
  bool lateral_periodic = true;
  for (int k = 0; k < 3; ++k)
    if (k != opt.axis) lateral_periodic = lateral_periodic && pk.cell.periodic[k];
  io.periodic_sides = lateral_periodic;
  io.tolerance = opt.solver.tolerance;
  io.max_iterations = opt.solver.max_iterations;
  const ImageAxisResult r = image_conductivity(im, io);
  res.solid_fraction = r.porosity;
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
