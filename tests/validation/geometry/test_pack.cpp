// Packings made by make_packing: realised size distribution and phase fractions against the
// request (issue 3: 2 % max CDF deviation, 1 % phase fractions), Laguerre volumes summing to
// the box, and a loose (below-jamming) solid-fraction target reached exactly.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <set>

#include "tomodem/geometry/pack.hpp"

using namespace tomodem;
using namespace tomodem::geometry;

namespace {
PhaseSpec phase(const std::string& name, double f, PsdKind k, double d, double sigma, PsdBasis b) {
  PhaseSpec p;
  p.name = name;
  p.volume_fraction = f;
  p.material.density = 6000;
  p.material.youngs_modulus = 1e8;
  p.material.poisson_ratio = 0.3;
  p.psd.kind = k;
  p.psd.diameter = d;
  p.psd.sigma = sigma;
  p.psd.basis = b;
  return p;
}
// Independent of the packer's own report (psd_max_cdf_deviation): the Kolmogorov–Smirnov
// distance between the empirical CDF of `d`, weighted by d^p (p = 0 by number, 3 by volume),
// and the requested lognormal (median d50, σ) cut at ±3σ and renormalised
// (SizeDistribution::truncation), written out here.
double ks_lognormal(std::vector<double> d, int p, double d50, double sigma) {
  const auto Phi = [](double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); };
  const auto F = [&](double x) {
    const double z = std::log(x / d50) / sigma;
    return z <= -3 ? 0.0 : z >= 3 ? 1.0 : (Phi(z) - Phi(-3)) / (Phi(3) - Phi(-3));
  };
  std::sort(d.begin(), d.end());
  double total = 0;
  for (double x : d) total += std::pow(x, p);
  double below = 0, dist = 0;
  for (double x : d) {
    const double w = std::pow(x, p), f = F(x);
    dist = std::max({dist, std::abs(f - below / total), std::abs((below + w) / total - f)});
    below += w;
  }
  return dist;
}
}  // namespace

TEST(Pack, TwoPhaseLognormalFractionsAndPsdAsRequested) {
  PackSpec s;
  s.phases = {phase("NiO", 0.5, PsdKind::lognormal, 1e-6, 0.3, PsdBasis::volume),
              phase("YSZ", 0.5, PsdKind::lognormal, 0.6e-6, 0.25, PsdBasis::number)};
  s.n_particles = 3000;
  s.target = Target::solid_fraction;
  s.target_solid_fraction = 0.35;  // below jamming: a short compression, equilibrium trivially
  const auto out = make_packing(s);
  const auto& r = out.report;
  ASSERT_EQ(r.phases.size(), 2u);
  // The diameters of each phase in the packing itself, against the request (NiO by volume,
  // YSZ by number); the packer's own figure is printed beside the independent one.
  ASSERT_EQ(out.packing.materials.size(), 2u);
  std::vector<double> d[2];
  for (std::size_t i = 0; i < out.packing.particles.size(); ++i)
    d[out.packing.particles.phase[i]].push_back(2 * out.packing.particles.radius[i]);
  for (int ph = 0; ph < 2; ++ph) {
    const bool nio = out.packing.materials[ph].name == "NiO";
    const double ks = nio ? ks_lognormal(d[ph], 3, 1e-6, 0.3) : ks_lognormal(d[ph], 0, 0.6e-6, 0.25);
    std::printf("%s: %zu particles, KS %.3e (packer reports %.3e)\n", out.packing.materials[ph].name.c_str(),
                d[ph].size(), ks, r.phases[ph].psd_max_cdf_deviation);
    // NiO by volume: 885 particles weighted by d³, measured 8.4e-3: the 2 % of issue 3. YSZ by
    // number: stratified quantiles give 1/(2N) = 2.4e-4 (measured 2.4e-4): limit 2e-3.
    EXPECT_LT(ks, nio ? 0.02 : 2e-3) << out.packing.materials[ph].name;
  }
  for (const auto& p : r.phases) {
    EXPECT_NEAR(p.realised_fraction, p.requested_fraction, 0.01) << p.name;  // issue 3: 1 %
  }
  EXPECT_NEAR(r.solid_fraction, 0.35, 1e-9);  // the final affine step lands on the target
  ASSERT_TRUE(r.tessellated);
  EXPECT_LT(r.laguerre_volume_error, 1e-9);  // issue 3
}

TEST(Pack, PoreFormersRemovedAfterPacking) {
  PackSpec s;
  s.phases = {phase("ceramic", 0.8, PsdKind::monodisperse, 1e-6, 0, PsdBasis::number),
              phase("pmma", 0.2, PsdKind::monodisperse, 4e-6, 0, PsdBasis::number)};
  s.phases[1].pore_former = true;
  s.n_particles = 2000;
  s.target = Target::solid_fraction;
  s.target_solid_fraction = 0.35;
  s.tessellate = false;
  const auto out = make_packing(s);
  EXPECT_GT(out.report.pore_formers_removed, 0u);
  for (int32_t p : out.packing.particles.phase) EXPECT_EQ(p, 0);
  // The ceramic keeps 80 % of the solid: φ drops by the pore formers' share (within 1 %).
  EXPECT_NEAR(out.report.solid_fraction / out.report.solid_fraction_with_pore_formers, 0.8, 0.01);
}

// Aggregates (issue 3): groups of `aggregate_size` particles bonded during packing. Each member
// is bonded to the one it grew on; the bond (radius 0.3 R, k_n = 2E*a g_n ≈ 0.45 E R) strains by
// F/(k_n l) ≈ F/(0.9 E R²) under contact forces F of order p d² at most a few times over, i.e.
// ≈ 2e-3 at p = 1e-4 E. Without the bonds the frictionless, non-adhesive members would separate
// by O(R); the test asks every bonded distance to stay within 2 % of its rest length, no bonded
// pair in the contact table, and the count of bonds (size − 1 per aggregate). 200 particles: 50
// aggregates and 150 bonds under a jammed packing's forces are as good a sample of the claim as
// 400 (which took 19 s CPU).
TEST(Pack, AggregatesStayBondedThroughPacking) {
  PackSpec s;
  s.phases = {phase("agglomerated", 1.0, PsdKind::monodisperse, 1e-6, 0, PsdBasis::number)};
  s.phases[0].aggregate_size = 4;
  s.n_particles = 200;
  s.initial_solid_fraction = 0.15;  // rigid clusters of 4 find room by random insertion
  s.target = Target::pressure;
  s.target_pressure = 1e-4 * s.phases[0].material.youngs_modulus;
  s.tessellate = false;
  const auto out = make_packing(s);
  const auto& r = out.report;
  const auto& pk = out.packing;
  EXPECT_EQ(r.aggregates, 50u);
  ASSERT_EQ(pk.bonds.size(), 150u);
  EXPECT_EQ(r.aggregate_bonds, 150u);
  EXPECT_TRUE(r.equilibrium);
  const double L = pk.cell.h(0, 0);
  double worst = 0;
  for (std::size_t b = 0; b < pk.bonds.size(); ++b) {
    Vec3 d = pk.particles.position[std::size_t(pk.bonds.j[b])] - pk.particles.position[std::size_t(pk.bonds.i[b])];
    for (int k = 0; k < 3; ++k) d[k] -= L * std::round(d[k] / L);
    worst = std::max(worst, std::abs(norm(d) / pk.bonds.rest_length[b] - 1));
    EXPECT_EQ(pk.bonds.state[b], 0);
  }
  std::printf("aggregates: phi %.4f, Z %.3f, worst bond strain %.2e, %d relaxations\n", r.solid_fraction, r.coordination,
              worst, r.minimisations);
  EXPECT_LT(worst, 0.02);
  std::set<std::pair<int32_t, int32_t>> bonded;
  for (std::size_t b = 0; b < pk.bonds.size(); ++b)
    bonded.insert({std::min(pk.bonds.i[b], pk.bonds.j[b]), std::max(pk.bonds.i[b], pk.bonds.j[b])});
  for (std::size_t k = 0; k < pk.contacts.i.size(); ++k)
    EXPECT_FALSE(bonded.count({std::min(pk.contacts.i[k], pk.contacts.j[k]), std::max(pk.contacts.i[k], pk.contacts.j[k])}));
}

// The overlap statistics of the summary (the solid-fraction reachability criterion is their
// 99th percentile, docs/pack.md) against a recount from the written packing's own contacts and
// radii: mean, the sorted list's element floor(0.99 (n − 1)), and the largest. One phase and no
// pore formers, so the written contacts are those the packer measured: agreement to round-off.
// A jammed packing at p = 1e-3 E has overlaps of about a percent of a radius, so the three
// statistics differ and their order (mean < p99 ≤ max) is a check of its own.
TEST(Pack, OverlapStatisticsAgainstARecountFromTheContacts) {
  PackSpec s;
  s.phases = {phase("ceramic", 1.0, PsdKind::lognormal, 1e-6, 0.2, PsdBasis::number)};
  s.n_particles = 400;
  s.target = Target::pressure;
  s.target_pressure = 1e-3 * s.phases[0].material.youngs_modulus;
  s.tessellate = false;
  const auto out = make_packing(s);
  const auto& r = out.report;
  const auto& pk = out.packing;
  std::vector<double> ratio;
  double mean = 0;
  for (std::size_t k = 0; k < pk.contacts.size(); ++k) {
    if (!(pk.contacts.overlap[k] > 0)) continue;
    ratio.push_back(pk.contacts.overlap[k] / std::min(pk.particles.radius[std::size_t(pk.contacts.i[k])],
                                                      pk.particles.radius[std::size_t(pk.contacts.j[k])]));
    mean += ratio.back();
  }
  ASSERT_GT(ratio.size(), 500u);
  mean /= double(ratio.size());
  std::sort(ratio.begin(), ratio.end());
  const double p99 = ratio[std::size_t(0.99 * double(ratio.size() - 1))];
  std::printf("overlaps over %zu contacts: mean %.4f, p99 %.4f, max %.4f of the smaller radius\n", ratio.size(), mean,
              p99, ratio.back());
  EXPECT_NEAR(r.overlap.mean, mean, 1e-12 * mean);
  EXPECT_EQ(r.overlap.p99, p99);
  EXPECT_EQ(r.overlap.max, ratio.back());
  EXPECT_LT(r.overlap.mean, r.overlap.p99);
  EXPECT_LE(r.overlap.p99, r.overlap.max);
}
