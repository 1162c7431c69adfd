// tomodem-bond's core: neighbour pairs (linked cells in fractional coordinates, periodic-aware),
// neck radii by rule, relative density with overlaps counted once, clusters.
#include "tomodem/mechanics/bonding.hpp"

#include <algorithm>
#include <cmath>

#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/dem/sinter.hpp"

namespace tomodem::mechanics {

namespace {
Mat3 inverse(const Mat3& h) {
  const double d = h.det();
  Mat3 r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const int i1 = (j + 1) % 3, i2 = (j + 2) % 3, j1 = (i + 1) % 3, j2 = (i + 2) % 3;
      r(i, j) = (h(i1, j1) * h(i2, j2) - h(i1, j2) * h(i2, j1)) / d;
    }
  return r;
}
double harmonic_radius(double a, double b) { return 2 * a * b / (a + b); }
}  // namespace

std::vector<Neighbor> neighbor_pairs(const Packing& p, double reach) {
  const std::size_t n = p.particles.size();
  std::vector<Neighbor> out;
  if (n < 2) return out;
  const Mat3 h = p.cell.h, hinv = inverse(h);
  double rmax = 0;
  for (double r : p.particles.radius) rmax = std::max(rmax, r);
  const double cutoff = 2 * rmax + reach;
  // Bins: perpendicular width of the cell along each vector over the cut-off.
  int nb[3];
  for (int k = 0; k < 3; ++k) {
    const Vec3 a = h.col((k + 1) % 3), b = h.col((k + 2) % 3);
    const Vec3 nrm = cross(a, b);
    const double width = std::abs(dot(h.col(k), nrm)) / norm(nrm);
    nb[k] = std::max(1, std::min(int(width / cutoff), 1024));
  }
  std::vector<Vec3> s(n);
  std::vector<int64_t> bin(n);
  auto bin_of = [&](const Vec3& f, int k) {
    double w = f[k];
    if (p.cell.periodic[k]) w -= std::floor(w);
    return std::clamp(int(w * nb[k]), 0, nb[k] - 1);
  };
  const int64_t nbins = int64_t(nb[0]) * nb[1] * nb[2];
  std::vector<int64_t> head(nbins + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    s[i] = hinv * (p.particles.position[i] - p.cell.origin);
    bin[i] = (int64_t(bin_of(s[i], 0)) * nb[1] + bin_of(s[i], 1)) * nb[2] + bin_of(s[i], 2);
    ++head[bin[i] + 1];
  }
  for (int64_t b = 0; b < nbins; ++b) head[b + 1] += head[b];
  std::vector<int32_t> members(n);
  {
    std::vector<int64_t> fill(head.begin(), head.end() - 1);
    for (std::size_t i = 0; i < n; ++i) members[fill[bin[i]]++] = int32_t(i);
  }
  // Neighbouring bin offsets per axis, deduplicated when there are fewer than three bins.
  std::vector<int> offs[3];
  for (int k = 0; k < 3; ++k) {
    if (nb[k] >= 3)
      offs[k] = {-1, 0, 1};
    else if (nb[k] == 2)
      offs[k] = {0, 1};
    else
      offs[k] = {0};
  }
  for (std::size_t i = 0; i < n; ++i) {
    const int64_t bi = bin[i];
    const int c0 = int(bi / (int64_t(nb[1]) * nb[2])), c1 = int((bi / nb[2]) % nb[1]), c2 = int(bi % nb[2]);
    for (int o0 : offs[0])
      for (int o1 : offs[1])
        for (int o2 : offs[2]) {
          int c[3] = {c0 + o0, c1 + o1, c2 + o2};
          bool skip = false;
          for (int k = 0; k < 3; ++k) {
            if (c[k] < 0 || c[k] >= nb[k]) {
              if (!p.cell.periodic[k]) skip = true;
              c[k] = (c[k] % nb[k] + nb[k]) % nb[k];
            }
          }
          if (skip) continue;
          const int64_t bj = (int64_t(c[0]) * nb[1] + c[1]) * nb[2] + c[2];
          for (int64_t e = head[bj]; e < head[bj + 1]; ++e) {
            const int32_t j = members[e];
            if (std::size_t(j) <= i) continue;
            Vec3 ds = s[j] - s[i];
            Image im{0, 0, 0};
            for (int k = 0; k < 3; ++k)
              if (p.cell.periodic[k]) {
                im[k] = int32_t(-std::lround(ds[k]));
                ds[k] += im[k];
              }
            const Vec3 d = h * ds;
            const double dist = norm(d);
            if (dist < p.particles.radius[i] + p.particles.radius[j] + reach)
              out.push_back({int32_t(i), j, im, dist});
          }
        }
  }
  // Several bin offsets can map onto the same bin in small cells: keep each pair once.
  std::sort(out.begin(), out.end(), [](const Neighbor& a, const Neighbor& b) {
    return a.i != b.i ? a.i < b.i : (a.j != b.j ? a.j < b.j : a.image < b.image);
  });
  out.erase(std::unique(out.begin(), out.end(),
                        [](const Neighbor& a, const Neighbor& b) { return a.i == b.i && a.j == b.j && a.image == b.image; }),
            out.end());
  return out;
}

double lens_volume(double r1, double r2, double d) {
  if (d >= r1 + r2) return 0;
  const double rmin = std::min(r1, r2);
  if (d <= std::abs(r1 - r2)) return 4.0 / 3.0 * M_PI * rmin * rmin * rmin;  // one inside the other
  const double t = r1 + r2 - d;
  return M_PI * t * t * (d * d + 2 * d * (r1 + r2) - 3 * (r1 - r2) * (r1 - r2)) / (12 * d);
}

double intersection_radius(double r1, double r2, double d) {
  if (d >= r1 + r2 || d <= std::abs(r1 - r2)) return 0;
  const double x = (d * d + r1 * r1 - r2 * r2) / (2 * d);
  return std::sqrt(std::max(0.0, r1 * r1 - x * x));
}

namespace {
double density_of(const Packing& p, const std::vector<Neighbor>& pairs, double scale) {
  // Positions scaled by `scale` (radii fixed): distances scale, the cell volume by scale³.
  double v = 0;
  for (double r : p.particles.radius) v += 4.0 / 3.0 * M_PI * r * r * r;
  for (const Neighbor& q : pairs) v -= lens_volume(p.particles.radius[q.i], p.particles.radius[q.j], q.distance * scale);
  return v / (p.cell.volume() * scale * scale * scale);
}
}  // namespace

double relative_density(const Packing& p) {
  if (p.particles.size() == 0) return 0;
  return density_of(p, neighbor_pairs(p, 0), 1.0);
}

BondingReport bond_network(Network& net, const BondingOptions& o) {
  Packing& p = net.packing;
  const std::size_t n = p.particles.size();
  BondingReport rep;
  const int nph = p.materials.empty() ? 1 + (n ? *std::max_element(p.particles.phase.begin(), p.particles.phase.end()) : 0)
                                      : int(p.materials.size());
  std::vector<char> excluded(std::size_t(nph) * nph, 0);
  std::vector<double> ratio(std::size_t(nph) * nph, o.neck_ratio);
  for (auto [a, b] : o.excluded)
    if (a >= 0 && b >= 0 && a < nph && b < nph) excluded[a * nph + b] = excluded[b * nph + a] = 1;
  for (auto [ab, r] : o.pair_ratio)
    if (ab.first >= 0 && ab.second >= 0 && ab.first < nph && ab.second < nph)
      ratio[ab.first * nph + ab.second] = ratio[ab.second * nph + ab.first] = r;

  double rmin = 1e300;
  for (double r : p.particles.radius) rmin = std::min(rmin, r);
  rep.initial_relative_density = relative_density(p);

  if (o.rule == NeckRule::sinter) {
    // Sintering to the target density (docs/sintering.md); its necks become the bonds.
    const double v0 = p.cell.volume();
    dem::SinteredPacking s = dem::sinter_packing(p, o.source, o.sinter_file, o.target_density, o.threads);
    p.particles.position = std::move(s.packing.particles.position);
    p.particles.radius = std::move(s.packing.particles.radius);
    p.particles.velocity.clear();
    p.particles.angular_velocity.clear();
    p.cell = s.packing.cell;
    p.bonds = std::move(s.packing.bonds);
    net.image.clear();
    for (const Vec3& im : s.bond_image)
      net.image.push_back({int32_t(std::lround(im.x)), int32_t(std::lround(im.y)), int32_t(std::lround(im.z))});
    for (std::size_t b = 0; b < p.bonds.size(); ++b)
      rep.neck_ratio.push_back(p.bonds.radius[b] / harmonic_radius(p.particles.radius[std::size_t(p.bonds.i[b])],
                                                                   p.particles.radius[std::size_t(p.bonds.j[b])]));
    rep.scale = std::cbrt(p.cell.volume() / v0);
    rep.sintering_time_s = s.report.final.time;
    rep.sintering_steps = s.report.steps;
    p.contacts = ContactTable{};
    rep.n_bonds = long(p.bonds.size());
    rep.bonds_per_particle = n ? 2.0 * double(rep.n_bonds) / double(n) : 0;
    rep.relative_density = relative_density(p);  // the grown radii: the sintering run's density (same lens formula)
    rep.clusters = find_clusters(p, net.image);
    return rep;
  }

  if (o.rule == NeckRule::density) {
    // Homothetic densification: centres (and the cell) move towards each other by a factor s < 1
    // (radii fixed) until the union density reaches the target. Pairs are searched once at the
    // largest reach the bracket needs.
    if (!(o.target_density > rep.initial_relative_density && o.target_density < 1))
      throw InputError("", "--target-density", value_text(o.target_density),
                       "must lie between the packing's relative density (" + value_text(rep.initial_relative_density) +
                           ") and 1");
    // Without overlaps the density would grow as 1/s³; overlaps slow it down, so start there
    // and lower the bracket until the target is passed.
    double hi = 1.0, lo = std::cbrt(rep.initial_relative_density / o.target_density) * 0.98;
    double rmax_d = 0;
    for (double r : p.particles.radius) rmax_d = std::max(rmax_d, r);
    std::vector<Neighbor> pairs;
    for (;;) {
      // Pairs that overlap at scale lo: d·lo < R_i + R_j, i.e. d < R_i + R_j + (R_i + R_j)(1/lo − 1).
      pairs = neighbor_pairs(p, 2 * rmax_d * (1 / lo - 1) * 1.001);
      if (density_of(p, pairs, lo) > o.target_density || lo < 0.3) break;
      lo *= 0.97;
    }
    if (density_of(p, pairs, lo) <= o.target_density)
      throw InputError("", "--target-density", value_text(o.target_density),
                       "not reached by densifying this packing (pairwise lens formula)");
    for (int it = 0; it < 100 && hi - lo > 1e-13; ++it) {
      const double mid = 0.5 * (lo + hi);
      (density_of(p, pairs, mid) > o.target_density ? lo : hi) = mid;
    }
    const double s = 0.5 * (lo + hi);
    rep.scale = s;
    for (Vec3& x : p.particles.position) x = p.cell.origin + s * (x - p.cell.origin);
    p.cell.h *= s;
  }

  // Candidate pairs: overlapping or within the gap tolerance.
  double rmax = 0;
  for (double r : p.particles.radius) rmax = std::max(rmax, r);
  const std::vector<Neighbor> pairs = neighbor_pairs(p, std::max(0.0, o.gap_tolerance) * 2 * rmax);
  BondTable bt;
  net.image.clear();
  for (const Neighbor& q : pairs) {
    const double ri = p.particles.radius[q.i], rj = p.particles.radius[q.j];
    const double rbar = harmonic_radius(ri, rj);
    const double gap = q.distance - ri - rj;
    if (gap > o.gap_tolerance * rbar) continue;
    const int pa = p.particles.phase[q.i], pb = p.particles.phase[q.j];
    if (pa < nph && pb < nph && excluded[pa * nph + pb]) continue;
    double a;
    if (o.rule == NeckRule::ratio) {
      a = ratio[pa * nph + pb] * rbar;
    } else {
      a = std::max(intersection_radius(ri, rj, q.distance), o.min_neck_ratio * rbar);
    }
    bt.i.push_back(q.i);
    bt.j.push_back(q.j);
    bt.radius.push_back(a);
    bt.rest_length.push_back(q.distance);
    bt.state.push_back(BondTable::intact);
    bt.broken_at.push_back(std::nan(""));
    net.image.push_back(q.image);
    rep.neck_ratio.push_back(a / rbar);
  }
  p.bonds = std::move(bt);
  p.contacts = ContactTable{};  // contacts of the input describe another state
  rep.n_bonds = long(p.bonds.size());
  rep.bonds_per_particle = n ? 2.0 * double(rep.n_bonds) / double(n) : 0;
  rep.relative_density = relative_density(p);
  rep.clusters = find_clusters(p, net.image);
  (void)rmin;
  return rep;
}

}  // namespace tomodem::mechanics
