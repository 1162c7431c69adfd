// Composite electrode: electronic and ionic networks coupled at charge-transfer contacts.
#include <gtest/gtest.h>

#include <cmath>

#include "lattice.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/network/electrode.hpp"

using namespace tomodem;
using namespace tomodem::network;

namespace {
constexpr double kPi = 3.14159265358979323846;
CompositeOptions options(double gct) {
  CompositeOptions o;
  o.electronic = {"A"};
  o.ionic = {"B"};
  o.axis = 0;
  o.charge_transfer = gct;
  o.network.use_contacts = false;
  o.conduct.solver.tolerance = 1e-13;
  return o;
}
}  // namespace

// Chain e–e–e–i–i between collector (x low) and electrolyte (x high): the resistance is the
// series sum 2/G_ee + 1/G_ct + 1/G_ii, G_ct = g_ct·2πa (exact up to round-off).
TEST(Composite, SeriesChainResistanceIsExact) {
  const double a = 0.3, se = 100.0, si = 0.5, gct = 7.0;
  Packing p = test::sc_lattice(5, 1, 1, 1.0, a, false, [](int x, int, int) { return x < 3 ? 0 : 1; });
  p.materials[0].conductivity = se;
  p.materials[1].conductivity = si;
  const CompositeResult r = solve_composite(p, options(gct));
  ASSERT_TRUE(r.percolates);
  // Holm (docs/physics.md): a like-phase contact of radius a has resistance 1/(2σa).
  const double want = 2 / (2 * se * a) + 1 / (gct * 2 * kPi * a) + 1 / (2 * si * a);
  EXPECT_NEAR(r.resistance_ohm, want, 1e-9 * want);
  EXPECT_NEAR(r.tpb_length_m, 2 * kPi * a, 1e-15);
  EXPECT_NEAR(r.tpb_density_m_per_m3, 2 * kPi * a / (10.0 * 2 * 2), 1e-15);
  EXPECT_EQ(r.n_tpb_contacts, 1u);
  EXPECT_NEAR(r.charge_transfer_current_fraction, 1.0, 1e-9);
}

// Two parallel reaction paths in a 2-wide ladder: the resistance falls as g_ct grows and tends
// to the purely ohmic limit; it is never below the ohmic limit.
TEST(Composite, ResistanceFallsWithChargeTransferTowardsOhmicLimit) {
  Packing p = test::sc_lattice(6, 2, 1, 1.0, 0.3, false, [](int x, int y, int) { return y == 0 ? 0 : 1; });
  p.materials[0].conductivity = 10.0;
  p.materials[1].conductivity = 1.0;
  double last = 1e300;
  for (double g : {1e-2, 1e0, 1e2, 1e6}) {
    const CompositeResult r = solve_composite(p, options(g));
    ASSERT_TRUE(r.percolates);
    EXPECT_LT(r.resistance_ohm, last);
    EXPECT_LT(r.conservation_error, 1e-9);
    last = r.resistance_ohm;
  }
  // Every rung of the ladder is a TPB contact inside the spanning cluster: all 6 are active.
  const CompositeResult r = solve_composite(p, options(1e6));
  EXPECT_EQ(r.n_tpb_contacts, 6u);
  EXPECT_NEAR(r.tpb_active_density_m_per_m3, r.tpb_density_m_per_m3, 1e-12);
}

TEST(Composite, NoChargeTransferContactMeansNoPath) {
  // Electronic row at y = 0 and ionic row at y = 2 with no contact between them.
  Packing p = test::sc_lattice(5, 3, 1, 1.0, 0.3, false, [](int x, int y, int) { return y == 0 ? 0 : 1; });
  BondTable kept;
  for (std::size_t b = 0; b < p.bonds.size(); ++b)
    if (p.particles.phase[p.bonds.i[b]] == p.particles.phase[p.bonds.j[b]]) {
      kept.i.push_back(p.bonds.i[b]);
      kept.j.push_back(p.bonds.j[b]);
      kept.radius.push_back(0.3);
    }
  p.bonds = kept;
  const CompositeResult r = solve_composite(p, options(1.0));
  EXPECT_FALSE(r.percolates);
  EXPECT_TRUE(std::isinf(r.resistance_ohm));
}

TEST(Composite, BadInput) {
  Packing p = test::sc_lattice(3, 1, 1, 1.0, 0.3, false);
  CompositeOptions o = options(1.0);
  o.charge_transfer = 0;
  EXPECT_THROW(solve_composite(p, o), InputError);
  o = options(1.0);
  o.ionic = {"A"};
  EXPECT_THROW(solve_composite(p, o), InputError);
  o = options(1.0);
  o.ionic = {"YSZ"};
  EXPECT_THROW(solve_composite(p, o), InputError);
}
