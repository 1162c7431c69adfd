// The sequentially linear analysis with its two solvers and the contact of broken faces
// (docs/fracture.md#solvers, #contact-of-broken-faces).
//
// Contact: a hand-made chain of four spheres on the z axis, bottom grip B (z = 0), P (2R),
// Q (4R), top grip T (6R), bonds B–Q, P–T and P–Q (Q above P). Opening the grips lifts P with T
// and Q stays with B, so the faces of a broken P–Q are pushed together: with contact the three
// normal springs act in series (every bond lies on the z axis, so shear, bending and twist rows
// carry nothing) and the grip force per unit opening is k_n/3, P–Q in compression by the same
// amount; without contact nothing connects the grips. k_n = E a g_n/(1 − ν²), g_n = 1 + 4(a/R)²
// (docs/physics.md#bond-failure), written out here. Flipping the chain (P above Q) stretches the
// broken pair: no contact, no force.
//
// Solvers: LDLT (Woodbury) and multigrid PCG on a 446-particle network must break the same bonds
// in the same order and give the same K_IC. The CG residual tolerance 1e-10 moves every bond's
// criterion ratio by about that relative amount (the ratios are linear in the solution, and the
// AMG-preconditioned system is well conditioned: κ·tol ≲ 1e-7); the closest pair of competing
// critical openings in this run is checked to be further apart than 1e-6, so any swap would be
// a real disagreement. K_IC agrees to 1e-6 (the peak load is S Δ, both linear in the solution).
#include <gtest/gtest.h>

#include <cmath>

#include "samples.hpp"

using namespace tomodem;
using namespace tomodem::mechanics;
using namespace tomodem::mechanics::test;

namespace {

constexpr double kE = 100e9, kNu = 0.25, kR = 1e-6, kA = 0.3e-6;

/// The chain; `q_above_p`: Q at 4R and P at 2R (faces pushed together on opening), else swapped.
FractureSample chain(bool q_above_p) {
  Network net;
  Packing& p = net.packing;
  const double W = 40 * kR, x = 4 * kR;  // the chain well outside the centre crack
  const double zb = 0, zp = q_above_p ? 2 * kR : 4 * kR, zq = q_above_p ? 4 * kR : 2 * kR, zt = 6 * kR;
  for (double z : {zb, zp, zq, zt}) {
    p.particles.position.push_back({x, 2 * kR, z});
    p.particles.radius.push_back(kR);
    p.particles.phase.push_back(0);
  }
  p.cell = Cell::box({0, 0, -kR}, {W, 4 * kR, 7 * kR}, true);
  p.materials = {alumina(kE, kNu)};
  auto bond = [&](int i, int j) {
    p.bonds.i.push_back(i);
    p.bonds.j.push_back(j);
    p.bonds.radius.push_back(kA);
    p.bonds.rest_length.push_back(std::abs(p.particles.position[std::size_t(j)].z - p.particles.position[std::size_t(i)].z));
    p.bonds.state.push_back(BondTable::intact);
    p.bonds.broken_at.push_back(std::nan(""));
    net.image.push_back({0, 0, 0});
  };
  bond(0, 2);  // B–Q
  bond(1, 3);  // P–T
  bond(1, 2);  // P–Q: the one broken below
  CrackOptions c;
  c.a_over_w = 0.1;
  c.grip = kR;
  return make_sample(net, c);
}

// Isolated necks: B–Q and P–T bond across a sphere, so they share no Laguerre face and the dense-
// network cap (docs/bond.md#dense-networks) would set them to zero; the chain tests the contact.
std::vector<dem::BondLaw> laws_of(const FractureSample& s, FailureOptions& f) { return lefm_laws(s.packing, f, true); }

}  // namespace

TEST(SlaContact, ClosedFacesCarryCompressionInSeries) {
  const double s2 = (kA / kR) * (kA / kR);
  const double kn = kE * kA * (1 + 4 * s2) / (1 - kNu * kNu);
  for (SlaSolver solver : {SlaSolver::ldlt, SlaSolver::pcg}) {
    const FractureSample s = chain(true);
    ASSERT_EQ(s.role[0], ParticleRole::bottom);
    ASSERT_EQ(s.role[3], ParticleRole::top);
    FailureOptions f;
    const auto laws = laws_of(s, f);
    SlaOptions o;
    o.solver = solver;
    o.cg_tolerance = 1e-12;
    const SlaResponse r = sla_response(s, laws, f, o, {2});
    // Series of three equal springs: 1e-9 covers the diagonal shift (1e-12 of the mean stiffness).
    EXPECT_NEAR(r.stiffness / (kn / 3), 1.0, 1e-9);
    EXPECT_NEAR(r.normal_force[2] / (-kn / 3), 1.0, 1e-9);  // P–Q pushed: compression
    EXPECT_NEAR(r.normal_force[1] / (kn / 3), 1.0, 1e-9);   // P–T and B–Q pulled
    EXPECT_NEAR(r.normal_force[0] / (kn / 3), 1.0, 1e-9);
    EXPECT_EQ(r.contacts, 1);
    EXPECT_EQ(r.active_set_iterations, 1);

    o.contact = false;  // faces pass through each other: the grips hang free
    const SlaResponse open = sla_response(s, laws, f, o, {2});
    EXPECT_LT(std::abs(open.stiffness), 1e-9 * kn);
    EXPECT_EQ(open.contacts, 0);
  }
}

TEST(SlaContact, PulledApartFacesCarryNothing) {
  for (SlaSolver solver : {SlaSolver::ldlt, SlaSolver::pcg}) {
    const FractureSample s = chain(false);  // P above Q: opening separates them
    FailureOptions f;
    const auto laws = laws_of(s, f);
    SlaOptions o;
    o.solver = solver;
    const SlaResponse r = sla_response(s, laws, f, o, {2});
    EXPECT_EQ(r.contacts, 0);
    EXPECT_EQ(r.normal_force[2], 0.0);
    EXPECT_LT(std::abs(r.stiffness), 1e-9 * kE * kA);
  }
}

TEST(SlaSolvers, PcgBreaksTheSameBondsAsLdlt) {
  const Network net = slab(12, 3, 18, 21);
  FailureOptions f;
  const auto laws = lefm_laws(net.packing, f);
  CrackOptions c;
  c.a_over_w = 0.1875;
  const FractureSample s = make_sample(net, c);
  SlaOptions o;
  o.stop_fraction = 0.5;
  o.event_tolerance = 0;  // one bond per solve: the sequences are compared event by event
  o.solver = SlaSolver::ldlt;
  const FractureResult a = run_sla(s, laws, f, o);
  o.solver = SlaSolver::pcg;
  o.cg_tolerance = 1e-10;
  const FractureResult b = run_sla(s, laws, f, o);
  EXPECT_EQ(a.solver, SlaSolver::ldlt);
  EXPECT_EQ(b.solver, SlaSolver::pcg);
  ASSERT_GT(a.events.size(), 10u);
  ASSERT_EQ(a.events.size(), b.events.size());
  double closest = HUGE_VAL;
  for (std::size_t e = 0; e < a.events.size(); ++e) {
    EXPECT_EQ(a.events[e].bond, b.events[e].bond) << "event " << e;
    EXPECT_NEAR(b.events[e].displacement / a.events[e].displacement, 1.0, 1e-6) << "event " << e;
    if (e > 0) closest = std::min(closest, std::abs(a.events[e].displacement / a.events[e - 1].displacement - 1));
  }
  EXPECT_GT(closest, 1e-6);  // no near-tie that the CG tolerance could swap
  EXPECT_NEAR(b.K_IC / a.K_IC, 1.0, 1e-6);
  EXPECT_NEAR(b.dissipated_energy / a.dissipated_energy, 1.0, 1e-6);
  EXPECT_GT(b.cg_iterations, 0);
  std::printf("LDLT %zu events, K_IC %.6e, %ld factorisations; PCG K_IC %.6e, %ld solves, %ld CG iterations (first %ld, "
              "largest %ld), %ld rebuilds, %ld active-set solves\n",
              a.events.size(), a.K_IC, a.factorizations, b.K_IC, b.solves, b.cg_iterations, b.cg_iterations_fresh,
              b.cg_iterations_max, b.amg_rebuilds, b.active_set_iterations);
}

// Several failures per solve (docs/fracture.md#several-failures-per-solve): every bond within
// (1 + t) of the critical opening breaks at it, i.e. with its strength lowered by less than t. The
// K_IC must not move by more than its own error (the crack-tip discreteness, K_IC_error); the
// solves must drop.
TEST(SlaSolvers, EventToleranceMovesKicWithinItsError) {
  const Network net = slab(24, 3, 36, 21);
  FailureOptions f;
  const auto laws = lefm_laws(net.packing, f);
  CrackOptions c;
  c.a_over_w = 0.1875;
  const FractureSample s = make_sample(net, c);
  SlaOptions o;
  o.stop_fraction = 0.5;
  o.solver = SlaSolver::ldlt;
  o.event_tolerance = 0;
  const FractureResult ref = run_sla(s, laws, f, o);
  for (double t : {0.01, 0.03}) {
    o.event_tolerance = t;
    const FractureResult r = run_sla(s, laws, f, o);
    std::printf("event tolerance %.2f: K_IC %.5e (%+.3f%%, K_IC_error %.1f%%), %ld failure groups for %zu breaks "
                "(tolerance 0: %ld for %zu)\n",
                t, r.K_IC, 100 * (r.K_IC / ref.K_IC - 1), 100 * ref.K_IC_error, r.failure_groups, r.events.size(),
                ref.failure_groups, ref.events.size());
    EXPECT_LT(std::abs(r.K_IC / ref.K_IC - 1), ref.K_IC_error);
    EXPECT_LT(r.failure_groups, ref.failure_groups);
  }
}
