// K_IC of pre-cracked bonded networks (issue 8): consistency over crack lengths, the energy
// release rate against K²(1−ν²)/E, rate independence of the explicit test, explicit against the
// sequentially linear analysis, and a stiff network (E = 400 GPa) failing without blow-up while
// its energy budget closes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "samples.hpp"
#include "tomodem/mechanics/elastic.hpp"
#include "tomodem/mechanics/fracture.hpp"

using namespace tomodem;
using namespace tomodem::mechanics;
using namespace tomodem::mechanics::test;

namespace {

FractureSample centre(const Network& net, double a_over_w) {
  CrackOptions c;
  c.geometry = CrackGeometry::centre;
  c.a_over_w = a_over_w;
  return make_sample(net, c);
}

const Network& medium() {  // ~2 400 particles, W ≈ 21 d, B ≈ 3.5 d, H ≈ 31 d, density 0.66
  static const Network net = slab(24, 4, 36, 7);
  return net;
}
const Network& small_net() {  // ~400 particles, W ≈ 10 d
  static const Network net = slab(12, 3, 18, 11);
  return net;
}

}  // namespace

// K_IC = Y σ_peak sqrt(πa) with Feddersen's Y must not depend on the crack length once a spans
// several particles: 2a/W = 0.2, 0.35, 0.5 (a = 2–5 diameters) change the peak load by ~40%, and
// the three K_IC agree within 10% (issue 8). Each K_IC is the mean over three crack planes of the
// same network (z_c = middle, ±0.1 H): the peak is set by the few bonds at the crack tips, and
// one plane alone scatters by ±8% (measured, docs/fracture.md).
TEST(Toughness, SlaKicIndependentOfCrackLength) {
  FailureOptions f;
  const std::vector<dem::BondLaw> laws = lefm_laws(medium().packing, f);
  SlaOptions o;
  o.stop_fraction = 0.7;
  std::vector<double> K;
  for (double two_a_over_w : {0.2, 0.35, 0.5}) {
    double sum = 0, force = 0;
    for (double offset : {-0.1, 0.0, 0.1}) {
      CrackOptions c;
      c.a_over_w = 0.5 * two_a_over_w;
      c.plane_offset = offset;
      const FractureResult r = run_sla(make_sample(medium(), c), laws, f, o);
      std::printf("2a/W = %.2f, plane %+.1f H: first break %.4g N, peak %.4g N, K_IC = %.4g Pa m^0.5 (+-%.1f%%), "
                  "%zu breaks, %.2f s\n",
                  two_a_over_w, offset, r.events.empty() ? 0.0 : r.events[0].force, r.peak_force, r.K_IC,
                  100 * r.K_IC_error, r.events.size(), r.wall_time_s);
      sum += r.K_IC;
      force += r.peak_force;
    }
    std::printf("2a/W = %.2f: mean peak %.4g N, mean K_IC %.4g Pa m^0.5\n", two_a_over_w, force / 3, sum / 3);
    K.push_back(sum / 3);
  }
  const double mean = (K[0] + K[1] + K[2]) / 3;
  const double spread = (*std::max_element(K.begin(), K.end()) - *std::min_element(K.begin(), K.end())) / mean;
  std::printf("spread %.1f%% of the mean %.4g\n", 100 * spread, mean);
  EXPECT_LT(spread, 0.10);
}

// The energy release rate from the dissipated energy: SLA until cut through, the energy released
// by all breaks (½Δ²(S_before − S_after) each) over the crack area they created (broken bonds ×
// the section area one ligament bond carries), against G = K_IC²(1−ν²)/E with E, ν of the periodic
// network (implicit solve): within 20% (issue 8). The projected work of fracture (over the flat
// ligament) is larger: the crack wanders and breaks bonds off the plane (docs/fracture.md).
TEST(Toughness, SlaDissipatedEnergyMatchesKic) {
  FailureOptions f;
  const std::vector<dem::BondLaw> laws = lefm_laws(medium().packing, f);
  ImplicitOptions io;
  io.full_tensor = false;
  const ImplicitResult el = solve_implicit(medium().packing, medium().image, bond_stiffnesses(medium().packing, laws), io);
  const FractureSample s = centre(medium(), 0.1875);
  SlaOptions o;
  o.stop_fraction = 0;
  const FractureResult r = run_sla(s, laws, f, o);
  ASSERT_TRUE(r.cut_through) << r.stop_reason;
  const double G_diss = r.dissipated_energy / r.crack_area;
  const double G_K = r.K_IC * r.K_IC * (1 - el.nu * el.nu) / el.E;
  std::printf("E = %.4g Pa, nu = %.3f, K_IC = %.4g: G from dissipation %.4g J/m2, K^2(1-nu^2)/E = %.4g J/m2, ratio %.3f; "
              "work of fracture %.4g J/m2; %zu breaks for %ld ligament bonds, broken-bond energy %.3g of the "
              "dissipation; %.2f s\n",
              el.E, el.nu, r.K_IC, G_diss, G_K, G_diss / G_K, r.work_of_fracture, r.events.size(), s.ligament_bonds,
              r.broken_bond_energy / r.dissipated_energy, r.wall_time_s);
  EXPECT_NEAR(G_diss / G_K, 1.0, 0.20);
}

// Halving the loading rate (from 200 to 400 transits to the reference strain) changes K_IC by
// less than 3% (issue 8): the chosen rate is quasi-static.
TEST(Toughness, ExplicitKicIndependentOfRate) {
  FailureOptions f;
  const std::vector<dem::BondLaw> laws = lefm_laws(small_net().packing, f);
  const FractureSample s = centre(small_net(), 0.1875);
  ExplicitFractureOptions o;
  o.stop_fraction = 0.5;
  o.track_energy = false;
  double K[2];
  for (int k = 0; k < 2; ++k) {
    o.transits = 200 * (k + 1);
    const FractureResult r = run_explicit_fracture(s, laws, f, o);
    std::printf("transits %.0f: K_IC = %.4g (peak after %.0f transits), %ld steps, %.2f s\n", o.transits, r.K_IC,
                r.transits_to_peak, r.steps, r.wall_time_s);
    K[k] = r.K_IC;
  }
  EXPECT_NEAR(K[0] / K[1], 1.0, 0.03);
}

// Explicit (quasi-static DEM with failure) against SLA on the same sample: within 10% (issue 8;
// the 5 000-particle comparison is in the bench label).
TEST(Toughness, ExplicitAgreesWithSla) {
  FailureOptions f;
  const std::vector<dem::BondLaw> laws = lefm_laws(small_net().packing, f);
  const FractureSample s = centre(small_net(), 0.1875);
  SlaOptions so;
  so.stop_fraction = 0.5;
  ExplicitFractureOptions eo;
  eo.stop_fraction = 0.5;
  eo.track_energy = false;
  const FractureResult a = run_sla(s, laws, f, so);
  const FractureResult b = run_explicit_fracture(s, laws, f, eo);
  std::printf("SLA K_IC = %.4g (%.2f s), explicit K_IC = %.4g (%.2f s), ratio %.4f\n", a.K_IC, a.wall_time_s, b.K_IC,
              b.wall_time_s, b.K_IC / a.K_IC);
  EXPECT_NEAR(b.K_IC / a.K_IC, 1.0, 0.10);
}

// A stiff network (E = 400 GPa, so the time step is half that at 100 GPa) fails without
// blowing up, and kinetic + stored + dissipated (dashpots, friction, released bond energy)
// equals the work of the grips within 2% at every record of the test, through failure.
TEST(Toughness, StiffNetworkFailsStablyAndEnergyBalances) {
  const Network net = slab(12, 3, 18, 13, alumina(400e9));
  FailureOptions f;
  const std::vector<dem::BondLaw> laws = lefm_laws(net.packing, f);
  const FractureSample s = centre(net, 0.1875);
  ExplicitFractureOptions o;
  o.stop_fraction = 0.3;
  o.track_energy = true;
  const FractureResult r = run_explicit_fracture(s, laws, f, o);
  std::printf("E = 400 GPa: K_IC = %.4g, %zu breaks, energy balance error %.3g%% of the grip work, %.2f s\n", r.K_IC,
              r.events.size(), 100 * r.energy_balance_error, r.wall_time_s);
  EXPECT_GT(r.events.size(), 0u);
  EXPECT_TRUE(std::isfinite(r.K_IC));
  EXPECT_LT(r.energy_balance_error, 0.02);
  // The released bond energy is part of the dissipation.
  EXPECT_GT(r.dissipated_energy, r.broken_bond_energy);
}

// The default stop (0.5 of the peak, docs/fracture.md: why) ends the SLA before the tail that only
// the post-peak curve needs: on three crack planes of the small network the run to cut-through
// reaches no higher load after the load first fell below half its peak, so the peak and K_IC are
// the same numbers (exactly: the same solves up to the stop) with fewer breaks.
TEST(Toughness, DefaultStopKeepsThePeakOfTheRunToCutThrough) {
  FailureOptions f;
  const std::vector<dem::BondLaw> laws = lefm_laws(small_net().packing, f);
  for (double offset : {-0.1, 0.0, 0.1}) {
    CrackOptions c;
    c.a_over_w = 0.2;
    c.plane_offset = offset;
    const FractureSample s = make_sample(small_net(), c);
    SlaOptions full;
    full.stop_fraction = 0;
    const FractureResult a = run_sla(s, laws, f, SlaOptions{}), b = run_sla(s, laws, f, full);
    EXPECT_EQ(a.peak_force, b.peak_force) << "plane " << offset;
    EXPECT_EQ(a.K_IC, b.K_IC) << "plane " << offset;
    EXPECT_LT(a.events.size(), b.events.size()) << "plane " << offset;
    std::printf("plane %+.1f H: K_IC %.4g, %zu breaks to half the peak, %zu to cut-through\n", offset, a.K_IC,
                a.events.size(), b.events.size());
  }
}
