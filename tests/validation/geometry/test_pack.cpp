// Packings made by make_packing: realised size distribution and phase fractions against the
// request (issue 3: 2 % max CDF deviation, 1 % phase fractions), Laguerre volumes summing to
// the box, and a loose (below-jamming) solid-fraction target reached exactly.
#include <gtest/gtest.h>

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
  for (const auto& p : r.phases) {
    EXPECT_LT(p.psd_max_cdf_deviation, 0.02) << p.name;                   // issue 3: 2 %
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
