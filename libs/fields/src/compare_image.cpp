// Image and model side by side: CG solid fractions of a scan and of a packing, and their agreement.
#include "tomodem/fields/compare_image.hpp"

#include <cmath>

namespace tomodem::fields {

namespace {
constexpr double kPi = 3.14159265358979323846;

std::vector<double> cg_density(const Snapshot& s, const Kernel& kernel, const GridSpec& grid, int threads) {
  Accumulator acc(kernel, grid, s.cell, 0, threads);
  acc.add(s);
  return acc.fields().density;
}
}  // namespace

std::vector<double> packing_solid_fraction(const Packing& p, const Kernel& kernel, const GridSpec& grid, int threads) {
  Snapshot s;
  s.cell = p.cell;
  s.h_reference = p.cell.h;
  s.x = p.particles.position;
  s.m.resize(p.particles.size());
  for (std::size_t k = 0; k < p.particles.size(); ++k) s.m[k] = 4.0 / 3.0 * kPi * std::pow(p.particles.radius[k], 3);
  return cg_density(s, kernel, grid, threads);
}

std::vector<double> image_solid_fraction(const network::LabelImage& im, const std::set<int>& solid, const Cell& cell,
                                         const Kernel& kernel, const GridSpec& grid, int threads) {
  Snapshot s;
  s.cell = cell;
  s.h_reference = cell.h;
  const Vec3 centre = cell.origin + 0.5 * (cell.h * Vec3(1, 1, 1));
  const double vol = im.spacing[0] * im.spacing[1] * im.spacing[2];
  const Mat3 hinv = cell.h.inverse();
  const std::size_t n[3] = {im.nx, im.ny, im.nz};
  for (std::size_t z = 0; z < n[2]; ++z)
    for (std::size_t y = 0; y < n[1]; ++y)
      for (std::size_t x = 0; x < n[0]; ++x) {
        if (!solid.count(im.v[(z * n[1] + y) * n[0] + x])) continue;
        const std::size_t i[3] = {x, y, z};
        Vec3 r = centre;
        for (int k = 0; k < 3; ++k) r[k] += (static_cast<double>(i[k]) + 0.5 - 0.5 * static_cast<double>(n[k])) * im.spacing[k];
        // Only the part of the scan inside the cell: a scan larger than a periodic cell is not
        // its periodic image, so nothing wraps (nodes near the faces are then not compared).
        const Vec3 f = hinv * (r - cell.origin);
        if (!(f[0] >= 0 && f[0] < 1 && f[1] >= 0 && f[1] < 1 && f[2] >= 0 && f[2] < 1)) continue;
        s.x.push_back(r);
        s.m.push_back(vol);
      }
  return cg_density(s, kernel, grid, threads);
}

FieldAgreement compare_fields(const std::vector<double>& a, const std::vector<double>& b, const std::vector<uint8_t>& mask) {
  FieldAgreement r;
  double sa = 0, sb = 0;
  for (std::size_t i = 0; i < a.size() && i < b.size(); ++i)
    if (mask.empty() || mask[i]) {
      sa += a[i];
      sb += b[i];
      ++r.nodes;
    }
  if (r.nodes == 0) return r;
  r.mean_a = sa / r.nodes;
  r.mean_b = sb / r.nodes;
  double cab = 0, caa = 0, cbb = 0, mad = 0;
  for (std::size_t i = 0; i < a.size() && i < b.size(); ++i)
    if (mask.empty() || mask[i]) {
      const double da = a[i] - r.mean_a, db = b[i] - r.mean_b;
      cab += da * db;
      caa += da * da;
      cbb += db * db;
      mad += std::abs(a[i] - b[i]);
    }
  r.mean_absolute_difference = mad / r.nodes;
  // Two constant fields: correlated by convention when equal (the identity), else undefined (NaN).
  r.correlation = caa > 0 && cbb > 0 ? cab / std::sqrt(caa * cbb) : (mad == 0 ? 1.0 : std::nan(""));
  return r;
}

}  // namespace tomodem::fields
