// Random bonded packings: explicit and implicit agree; stiff and extreme cases are stable.
#include <gtest/gtest.h>

#include <cmath>

#include "networks.hpp"
#include "tomodem/mechanics/elastic.hpp"

using namespace tomodem;
using namespace tomodem::mechanics;

namespace {
double implicit_E(const Network& net, const std::vector<dem::BondLaw>& laws, const std::string& solver = "ldlt",
                  ImplicitResult* out = nullptr) {
  ImplicitOptions o;
  o.solver = *parse_elastic_solver(solver);
  o.tolerance = 1e-10;
  const ImplicitResult r = solve_implicit(net.packing, net.image, bond_stiffnesses(net.packing, laws), o);
  if (out) *out = r;
  return r.E;
}
}  // namespace

// N = 400 random packing (RSA at 0.30, densified to 0.55): the quasi-static DEM test and the
// direct solve give the same E (the N ≥ 5000 case of issue 5 is the bench
// YoungBench.ExplicitAgreesWithImplicit5000). Tolerance 1.5%: the explicit slope carries a
// dynamic error of a few 1e-3 at 50 transits (docs/young.md). The explicit error estimate (slope
// spread and the rate check over half the loading time) must bound the measured difference.
TEST(RandomNetwork, ExplicitAgreesWithImplicit) {
  Network net = test::random_network(400, 0.5e-3, 0.30, 0.55, 5, 0.05);
  const auto laws = bond_laws(net.packing, "", LawOptions{}, true);
  ImplicitResult ir;
  const double Ei = implicit_E(net, laws, "ldlt", &ir);
  ExplicitOptions o;
  o.transits = 50;
  o.points = 4;
  o.local_damping = 0.3;
  const ExplicitResult er = run_explicit(net.packing, net.image, laws, o);
  std::printf("random N=400: Z %.2f, E_impl %.4e Pa (%.2f s), E_expl %.4e Pa (%.2f s), diff %.2e, estimate %.2e "
              "(spread %.2e, rate check %.2e); nu %.4f %.4f\n",
              2.0 * double(net.packing.bonds.size()) / 400, Ei, ir.wall_time_s, er.E, er.wall_time_s, er.E / Ei - 1,
              er.E_error, er.E_error_spread, er.E_error_rate, ir.nu, er.nu);
  EXPECT_GT(Ei, 0);
  EXPECT_NEAR(er.E / Ei, 1.0, 0.015);
  EXPECT_NEAR(er.nu, ir.nu, 0.02);
  EXPECT_GE(er.E_error, std::abs(er.E / Ei - 1));
}

// The direct and the iterative solvers agree on a random network (tolerance 1e-10: relative
// difference well below 1e-6 of C11), and the tensor is symmetric positive definite. Multigrid
// (two levels or more at 4 800 unknowns) needs a fraction of the Jacobi iterations.
TEST(RandomNetwork, LdltAndIterativeSolversAgree) {
  Network net = test::random_network(800, 0.5e-3, 0.30, 0.55, 9, 0.05);
  const auto laws = bond_laws(net.packing, "", LawOptions{}, false);
  ImplicitResult a, b, c;
  implicit_E(net, laws, "ldlt", &a);
  implicit_E(net, laws, "cg", &b);
  implicit_E(net, laws, "amg", &c);
  std::printf("N=800: Jacobi-CG %ld iterations, multigrid-CG %ld iterations (%d levels, complexity %.2f)\n",
              b.iterations, c.iterations, c.levels, c.operator_complexity);
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) {
      EXPECT_NEAR(a.C[i][j], b.C[i][j], 1e-6 * a.C[0][0]) << i << j;
      EXPECT_NEAR(a.C[i][j], c.C[i][j], 1e-6 * a.C[0][0]) << i << j;
    }
  for (int i = 0; i < 6; ++i) EXPECT_GT(a.C[i][i], 0);
  EXPECT_LT(b.E_error, 1e-6);
  EXPECT_LT(c.E_error, 1e-6);
  EXPECT_GE(c.levels, 2);
  EXPECT_LT(5 * c.iterations, b.iterations);
}

// Stiff and extreme cases (issue 5): E = 400 GPa, a_b/R from 0.01 to 0.5, floating particles
// and rattlers. The solve leaves them out and stays regular; E is finite, positive and grows
// with the neck size; the explicit test on the stiff network is stable (no exception) and agrees.
TEST(RandomNetwork, StiffExtremeNecksWithRattlersAreStable) {
  Network base = test::random_network(600, 0.5e-3, 0.30, 0.50, 21, 0.01, test::ceramic(400e9, 0.2, 3900));
  // Rattlers: particles 0..6 lose their bonds and shrink to 0.6 R, so they sit free in their
  // pores (no overlap: the DEM would otherwise push them out). The densified packing also has
  // small floating clusters of its own.
  Packing& p = base.packing;
  for (std::size_t b = 0; b < p.bonds.size(); ++b)
    if (p.bonds.i[b] < 7 || p.bonds.j[b] < 7) p.bonds.state[b] = BondTable::broken;
  for (int k = 0; k < 7; ++k) p.particles.radius[k] *= 0.6;
  const Clusters cl = find_clusters(p, base.image);
  EXPECT_GE(cl.outside_main, 7);
  const auto laws = bond_laws(p, "", LawOptions{}, true);
  double last = 0;
  for (double ratio : {0.01, 0.05, 0.2, 0.5}) {
    Network net = base;
    for (double& a : net.packing.bonds.radius) a = ratio * 0.5e-3;
    ImplicitResult r;
    const double E = implicit_E(net, laws, "ldlt", &r);
    std::printf("400 GPa, a/R %.2f: E %.4e Pa, nu %.4f, removed %ld particles\n", ratio, E, r.nu, r.particles_removed);
    EXPECT_TRUE(std::isfinite(E));
    EXPECT_GT(E, last);
    EXPECT_GE(r.particles_removed, 7);
    last = E;
    if (ratio == 0.5) {
      ExplicitOptions o;
      o.transits = 40;
      o.points = 3;
      o.local_damping = 0.3;
      o.rate_check = false;  // stability is the point here; the estimate is checked above
      const ExplicitResult er = run_explicit(net.packing, net.image, laws, o);
      std::printf("400 GPa, a/R 0.5 explicit: E %.4e Pa (diff %.2e), %ld steps\n", er.E, er.E / E - 1, er.steps);
      EXPECT_NEAR(er.E / E, 1.0, 0.03);
    }
  }
}
