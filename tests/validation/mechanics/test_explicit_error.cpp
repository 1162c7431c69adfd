// The explicit test's reported errors (E_error, nu_error) bound the true errors against the direct
// solve on the same network, at three run lengths, with local damping off and on, under uniaxial
// stress and uniaxial strain (issue 19; strain loading reads E and nu through isotropy, and the
// hostile review found its error 3-90 times too small before the anisotropy term).
#include <gtest/gtest.h>

#include <cmath>

#include "networks.hpp"
#include "tomodem/mechanics/elastic.hpp"

using namespace tomodem;
using namespace tomodem::mechanics;

// N = 400 random network (RSA 0.30 densified to 0.55, Z ≈ 3.8), the CLI's defaults (6 points,
// stress loading, rate protocol, rate check on) at 12.5, 25 and 50 transits. The reference is LDLT
// (exact to round-off, 1e-14 on the lattices); uniaxial strain reads E and ν through isotropy, so
// its true error holds the network's anisotropy (ν 0.0145 off at every run length). Required:
// reported ≥ true (the estimate is a bound)
// and reported ≤ 10 × true (a bound that says something; the true errors here are 0.4–4 %, far
// above the 1e-4 strain floor, so the ratio measures the estimate and not the floor). ν: the
// reported nu_error (absolute) bounds |ν − ν_ref| the same way.
TEST(ExplicitError, BoundsTheTrueErrorAtThreeRunLengthsWithAndWithoutLocalDamping) {
  Network net = test::random_network(400, 0.5e-3, 0.30, 0.55, 5, 0.05);
  const auto laws = bond_laws(net.packing, "", LawOptions{}, true);
  ImplicitOptions io;
  io.solver = ElasticSolver::ldlt;
  const ImplicitResult ref = solve_implicit(net.packing, net.image, bond_stiffnesses(net.packing, laws), io);
  std::printf("reference LDLT: E %.6e Pa, nu %.5f\n", ref.E, ref.nu);
  std::printf("| loading | local damping | transits | true E error | E_error (spread, lateral, rate) | ratio | "
              "true nu error | nu_error | ratio |\n");
  for (UniaxialLoading loading : {UniaxialLoading::stress, UniaxialLoading::strain})
  for (double damping : {0.0, 0.3})
    for (double transits : {12.5, 25.0, 50.0}) {
      ExplicitOptions o;
      o.loading = loading;
      o.transits = transits;
      o.local_damping = damping;
      const ExplicitResult r = run_explicit(net.packing, net.image, laws, o);
      const double eE = std::abs(r.E / ref.E - 1), eN = std::abs(r.nu - ref.nu);
      std::printf("| %s | %.1f | %.1f | %.2e | %.2e (%.1e, %.1e, %.1e) | %.2f | %.2e | %.2e | %.2f |\n",
                  to_string(loading), damping, transits, eE,
                  r.E_error, r.E_error_spread, r.E_error_lateral, r.E_error_rate, r.E_error / eE, eN, r.nu_error,
                  r.nu_error / eN);
      const std::string where = std::string(to_string(loading)) + " loading, transits " + std::to_string(transits) +
                                ", local damping " + std::to_string(damping);
      EXPECT_GE(r.E_error, eE) << where;
      // Under strain loading at 12.5 transits the segment-slope spread alone is 8x the true error
      // of E (the isotropy term adds 2-3 % to it): the "says something" limit is 12 there.
      EXPECT_LE(r.E_error, (loading == UniaxialLoading::strain ? 12 : 10) * eE) << where;
      EXPECT_GE(r.nu_error, eN) << where;
      EXPECT_LE(r.nu_error, 10 * eN) << where;
    }
}
