// tomodem-bond's core: neck radii by rule on the pairs in contact (libs/spatial), relative density
// from the exact union volume of the spheres (spatial/union_volume.hpp), clusters.
#include "tomodem/mechanics/bonding.hpp"

#include <algorithm>
#include <cmath>

#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/dem/bonds.hpp"
#include "tomodem/dem/sinter.hpp"
#include "tomodem/spatial/union_volume.hpp"

namespace tomodem::mechanics {

using spatial::harmonic_radius;

std::vector<Neighbor> neighbor_pairs(const Packing& p, double reach) {
  return spatial::pairs_within(p.particles.position, p.particles.radius, p.cell, reach);
}

namespace {
/// Exact union density (spatial::union_volume) with the centres and the cell scaled by `scale`
/// about the origin (radii fixed).
double density_of(const Packing& p, double scale) {
  Cell c = p.cell;
  c.h *= scale;
  std::vector<Vec3> x(p.particles.position);
  for (Vec3& v : x) v = p.cell.origin + scale * (v - p.cell.origin);
  return spatial::union_relative_density(x, p.particles.radius, c);
}
}  // namespace

double relative_density(const Packing& p) {
  if (p.particles.size() == 0) return 0;
  return density_of(p, 1.0);
}

double relative_density_pairwise(const Packing& p) {
  if (p.particles.size() == 0) return 0;
  return spatial::union_volume(p.particles.position, p.particles.radius, p.cell).pairwise / p.cell.volume();
}

namespace {

/// Rule sinter: the packing is sintered to the target density (docs/sintering.md) and its necks
/// become the bonds.
void bond_by_sintering(Network& net, const BondingOptions& o, BondingReport& rep) {
  Packing& p = net.packing;
  const double v0 = p.cell.volume();
  dem::SinteredPacking s = dem::sinter_packing(p, o.source, o.sinter_file, o.target_density, o.threads, !quiet());  // progress unless -q
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
}

/// Rule density: homothetic densification, centres (and the cell) moving towards each other by a
/// factor s < 1 (radii fixed) until the union density reaches the target. Pairs are searched once
/// at the largest reach the bracket needs.
void densify_to_target(Packing& p, const BondingOptions& o, BondingReport& rep) {
  if (!(o.target_density > rep.initial_relative_density && o.target_density < 1))
    throw InputError("", "--target-density", value_text(o.target_density),
                     "must lie between the packing's relative density (" + value_text(rep.initial_relative_density) +
                         ") and 1");
  // Without overlaps the density would grow as 1/s³; overlaps slow it down, so start there and
  // lower the bracket until the target is passed.
  double hi = 1.0, lo = std::cbrt(rep.initial_relative_density / o.target_density) * 0.98;
  while (density_of(p, lo) <= o.target_density && lo >= 0.3) lo *= 0.97;
  if (density_of(p, lo) <= o.target_density)
    throw InputError("", "--target-density", value_text(o.target_density),
                     "not reached by densifying this packing (centres scaled by down to " + value_text(lo) + ")");
  // The union density rises monotonically as the centres close in; bisection to 1e-10 in s.
  for (int it = 0; it < 60 && hi - lo > 1e-10; ++it) {
    const double mid = 0.5 * (lo + hi);
    (density_of(p, mid) > o.target_density ? lo : hi) = mid;
  }
  const double s = 0.5 * (lo + hi);
  rep.scale = s;
  for (Vec3& x : p.particles.position) x = p.cell.origin + s * (x - p.cell.origin);
  p.cell.h *= s;
}

/// Per phase pair (nph × nph): excluded from bonding, and the neck ratio of rule ratio.
struct PhaseRules {
  int nph;
  std::vector<char> excluded;
  std::vector<double> ratio;
  PhaseRules(const Packing& p, const BondingOptions& o) {
    const std::size_t n = p.particles.size();
    nph = p.materials.empty() ? 1 + (n ? *std::max_element(p.particles.phase.begin(), p.particles.phase.end()) : 0)
                              : int(p.materials.size());
    excluded.assign(std::size_t(nph) * std::size_t(nph), 0);
    ratio.assign(std::size_t(nph) * std::size_t(nph), o.neck_ratio);
    const auto ok = [&](int a, int b) { return a >= 0 && b >= 0 && a < nph && b < nph; };
    for (auto [a, b] : o.excluded)
      if (ok(a, b)) excluded[std::size_t(a * nph + b)] = excluded[std::size_t(b * nph + a)] = 1;
    for (auto [ab, r] : o.pair_ratio)
      if (ok(ab.first, ab.second))
        ratio[std::size_t(ab.first * nph + ab.second)] = ratio[std::size_t(ab.second * nph + ab.first)] = r;
  }
};

/// Rules ratio, overlap, density: a bond for every pair in contact (spatial::in_contact) whose
/// phases are not excluded, neck radius by the rule.
void bond_contacts(Network& net, const BondingOptions& o, BondingReport& rep) {
  Packing& p = net.packing;
  const PhaseRules rules(p, o);
  double rmax = 0;
  for (double r : p.particles.radius) rmax = std::max(rmax, r);
  const std::vector<Neighbor> pairs = neighbor_pairs(p, spatial::contact_reach(rmax, o.gap_tolerance));
  BondTable bt;
  net.image.clear();
  for (const Neighbor& q : pairs) {
    const double ri = p.particles.radius[std::size_t(q.i)], rj = p.particles.radius[std::size_t(q.j)];
    if (!spatial::in_contact(q.distance, ri, rj, o.gap_tolerance)) continue;
    const double rbar = harmonic_radius(ri, rj);
    const int pa = p.particles.phase[std::size_t(q.i)], pb = p.particles.phase[std::size_t(q.j)];
    if (pa < rules.nph && pb < rules.nph && rules.excluded[std::size_t(pa * rules.nph + pb)]) continue;
    const double a = o.rule == NeckRule::ratio
                         ? rules.ratio[std::size_t(pa * rules.nph + pb)] * rbar
                         : std::max(intersection_radius(ri, rj, q.distance), o.min_neck_ratio * rbar);
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
}

}  // namespace

NeckRange neck_range(const Packing& p) {
  NeckRange r;
  r.valid_up_to = dem::kNeckCorrectionMaxRatio;
  for (std::size_t b = 0; b < p.bonds.size(); ++b) {
    if (p.bonds.state[b] != BondTable::intact) continue;
    const double q = p.bonds.radius[b] / harmonic_radius(p.particles.radius[std::size_t(p.bonds.i[b])],
                                                         p.particles.radius[std::size_t(p.bonds.j[b])]);
    r.max_ratio = std::max(r.max_ratio, q);
    if (q > r.valid_up_to) ++r.bonds_beyond;
  }
  return r;
}

std::string neck_range_warning(const NeckRange& r, long n_bonds) {
  if (r.bonds_beyond == 0) return "";
  return std::to_string(r.bonds_beyond) + " of " + std::to_string(n_bonds) + " necks have a/R above " +
         value_text(r.valid_up_to) + " (largest " + value_text(r.max_ratio) +
         "), beyond the range the neck stiffness corrections g_n, g_t are derived for: their g is held at its a/R = " +
         value_text(r.valid_up_to) + " value (docs/bond.md#neck-laws)";
}

BondingReport bond_network(Network& net, const BondingOptions& o) {
  Packing& p = net.packing;
  BondingReport rep;
  rep.initial_relative_density = relative_density(p);
  if (o.rule == NeckRule::sinter) {
    bond_by_sintering(net, o, rep);
  } else {
    if (o.rule == NeckRule::density) densify_to_target(p, o, rep);
    bond_contacts(net, o, rep);
  }
  p.contacts = ContactTable{};  // contacts of the input describe another state
  const std::size_t n = p.particles.size();
  rep.n_bonds = long(p.bonds.size());
  rep.bonds_per_particle = n ? 2.0 * double(rep.n_bonds) / double(n) : 0;
  rep.relative_density = relative_density(p);  // rule sinter: the grown radii, the same union as the run
  rep.relative_density_pairwise = relative_density_pairwise(p);
  rep.clusters = find_clusters(p, net.image);
  return rep;
}

}  // namespace tomodem::mechanics
