// Bond strength in dense networks (issue 18): where the laws cap a neck's springs at its pair's
// Laguerre face, the failure criterion takes the section of the face's area (when πa² exceeds it)
// and the capped springs (docs/fracture.md#dense-networks). Expected values are written from the
// formulas there, not taken from the library: section a_s = sqrt(A_f/π), LEFM F_c = 2 sqrt(k Γ A_s)
// for the normal spring k and the section A_s (the isolated neck's σ_c = 2 sqrt(2E*Γ g_n/(πa))
// times πa² for k = 2E* a g_n, A_s = πa²).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "samples.hpp"
#include "tomodem/mechanics/bond_section.hpp"
#include "tomodem/mechanics/fracture.hpp"

using namespace tomodem;
using namespace tomodem::mechanics;
using namespace tomodem::mechanics::test;

// Simple cubic lattice (spacing d) of spheres R = 0.6 d bonded to their six neighbours with
// a = R: the isolated neck area πa² = 1.13 d² exceeds the square face d² of the cubic power cell.
// By hand: k_n isolated = 2E* a g_n = 2E a/(1−ν²) · 2 = 1.28 E d > E_face A_f/L = E d, so k_n = E d;
// k_t = 8G* a g_t = 0.71 E d stays; a_s = d/sqrt(π); LEFM F_c = 2 sqrt(E d Γ d²), shear
// F_t,c = 2 sqrt(k_t Γ d²), Γ = 2γ_s.
TEST(DenseStrength, OverlappingNecksTakeTheFaceAsTheirSection) {
  const double d = 2e-6, R = 0.6 * d, E = 100e9, nu = 0.25, gamma = 1.0, Gamma = 2 * gamma;
  Network net;
  net.packing = lattice("simple_cubic", 3, d, R, alumina(E, nu, 3000, gamma));
  BondingOptions bo;
  bo.rule = NeckRule::ratio;
  bo.neck_ratio = 1.0;
  bond_network(net, bo);
  const Packing& p = net.packing;
  ASSERT_EQ(p.bonds.size(), 81u);  // 27 sites × 6 neighbours / 2
  FailureOptions f;
  const std::vector<dem::BondLaw> laws = lefm_laws(p, f);
  std::vector<double> section;
  const BondStiffnesses k = bond_stiffnesses(p, laws, section);
  const double a = R, s = std::min(a / R, 0.5) * std::min(a / R, 0.5);
  const double G = E / (2 * (1 + nu)), kt = 8 * G / (2 * (2 - nu)) * a * (1 + 1.2 * s);
  EXPECT_EQ(k.face_capped, 81);
  for (std::size_t b = 0; b < p.bonds.size(); ++b) {
    // Tolerances 1e-12: CGAL's face areas of a cubic lattice are exact to round-off (3e-15,
    // dense_network_validation), the rest is a few floating-point operations.
    EXPECT_NEAR(k.kn[b], E * d, 1e-12 * E * d);
    EXPECT_NEAR(k.kt[b], kt, 1e-12 * kt);
    ASSERT_NEAR(section[b], d / std::sqrt(M_PI), 1e-12 * d);
    const dem::BondStrength st = dem::bond_strength(f.criterion, laws[0], section[b],
                                                    equivalent_neck(laws[0], section[b], k.kn[b], k.kt[b]));
    const double A = d * d;
    EXPECT_NEAR(st.tension * A, 2 * std::sqrt(E * d * Gamma * A), 1e-12 * st.tension * A);
    EXPECT_NEAR(st.shear * A, 2 * std::sqrt(kt * Gamma * A), 1e-12 * st.shear * A);
  }
  // Necks well inside their face keep their own section (a = 0.3 R: πa² = 0.10 d²).
  EXPECT_EQ(section_radius(0.3 * R, d * d), 0.3 * R);
}

// The SLA on a cracked simple cubic lattice of such necks (every bond alike): the LEFM run must
// break the same bonds at the same openings as a stress-criterion run whose σ_c, τ_c are the
// hand-computed face values above (F_c/d², F_t,c/d²), both taking their stresses on the section
// d². With the isolated neck's strength (πa², uncapped g_n) the LEFM critical tensile force would
// be sqrt(1.28 × 1.13) = 1.20 times the face value.
// Tolerance 1e-9: the two runs solve the same systems; only the strengths' round-off differs.
TEST(DenseStrength, SlaOnOverlappingNecksBreaksAtTheFaceStrength) {
  const double d = 2e-6, R = 0.6 * d, E = 100e9, nu = 0.25, gamma = 1.0, Gamma = 2 * gamma;
  Network net;
  net.packing = lattice("simple_cubic", 8, d, R, alumina(E, nu, 3000, gamma));
  BondingOptions bo;
  bo.rule = NeckRule::ratio;
  bo.neck_ratio = 1.0;
  bond_network(net, bo);
  CrackOptions c;
  c.a_over_w = 0.25;
  const FractureSample s = make_sample(net, c);
  FailureOptions lefm;
  const std::vector<dem::BondLaw> lefm_law = lefm_laws(s.packing, lefm);
  const double A = d * d, G = E / (2 * (1 + nu)), kt = 8 * G / (2 * (2 - nu)) * R * (1 + 1.2 * 0.25);
  FailureOptions stress;
  stress.criterion = dem::BondFailure::stress;
  stress.tensile_strength = 2 * std::sqrt(E * d * Gamma * A) / A;
  stress.shear_strength = 2 * std::sqrt(kt * Gamma * A) / A;
  std::vector<dem::BondLaw> stress_law = bond_laws(s.packing, "", LawOptions{}, true);
  set_failure(stress_law, s.packing, stress, "");
  SlaOptions o;
  o.stop_fraction = 0.5;
  const FractureResult a = run_sla(s, lefm_law, lefm, o), b = run_sla(s, stress_law, stress, o);
  ASSERT_GT(a.events.size(), 3u);
  ASSERT_EQ(a.events.size(), b.events.size());
  // The lattice's symmetric bonds break in groups at one opening, in an order set by round-off:
  // the openings event by event, the broken bonds as sets.
  std::vector<int32_t> broken_a, broken_b;
  for (std::size_t e = 0; e < a.events.size(); ++e) {
    EXPECT_NEAR(a.events[e].displacement, b.events[e].displacement, 1e-9 * b.events[e].displacement) << "event " << e;
    broken_a.push_back(a.events[e].bond);
    broken_b.push_back(b.events[e].bond);
  }
  std::sort(broken_a.begin(), broken_a.end());
  std::sort(broken_b.begin(), broken_b.end());
  EXPECT_EQ(broken_a, broken_b);
  std::printf("simple cubic, a = R = 0.6 d: %zu breaks, first at %.4g m, K_IC %.4g (stress criterion at the face "
              "strengths %.4g)\n", a.events.size(), a.events[0].displacement, a.K_IC, b.K_IC);
}

// A bond that breaks under the LEFM criterion holds at most 2ΓA_s in its normal and bending
// springs and 2ΓA_s in its shear and twist springs: σ = T/A_s + 4|M_b|/(A_s a_s) ≤ σ_c with
// F_c²/(2k_n) = 2ΓA_s, k_bend = ¼ k_n a² and a_s ≤ a bound T²/2k_n + M_b²/2k_bend by 2ΓA_s (the
// same for τ with k_twist = ½ k_t a²). So no broken bond of the SLA may have held more than
// 4ΓA_f, A_f its face. With the isolated necks' strength on capped springs (before issue 18's
// fix) a capped bond held 2Γπa² k_n/k_cap in tension alone: the 0.85 network below is where
// that exceeds the bound. Each broken bond is checked to 1e-9 (round-off of the solve).
TEST(DenseStrength, BrokenBondsHoldAtMostTheirFacesEnergy) {
  const Network net = slab(12, 3, 18, 11, alumina(), 1e-6, 0.36, 0.85);
  FailureOptions f;
  const std::vector<dem::BondLaw> laws = lefm_laws(net.packing, f);
  CrackOptions c;
  c.a_over_w = 0.2;
  const FractureSample s = make_sample(net, c);
  SlaOptions o;
  o.stop_fraction = 0;
  const FractureResult r = run_sla(s, laws, f, o);
  const std::vector<double> face = bond_face_areas(s.packing);
  const double Gamma = 2 * alumina().surface_energy;
  std::vector<double> section;
  const BondStiffnesses k = bond_stiffnesses(s.packing, laws, section);
  ASSERT_GT(r.events.size(), 10u);
  long capped = 0;
  double worst = 0;
  for (const FractureEvent& e : r.events) {
    const std::size_t b = std::size_t(e.bond);
    const dem::BondStiffness iso = dem::bond_stiffness(laws[0], s.packing.bonds.radius[b], 1e-6, 1e-6);
    capped += k.kn[b] < iso.kn;
    worst = std::max(worst, e.bond_energy / (4 * Gamma * face[b]));
    EXPECT_LE(e.bond_energy, 4 * Gamma * face[b] * (1 + 1e-9)) << "bond " << b;
  }
  std::printf("%zu broken bonds, %ld with capped k_n; largest energy / (4 Gamma A_face) %.3f; K_IC %.4g Pa m^0.5\n",
              r.events.size(), capped, worst, r.K_IC);
  EXPECT_GT(capped, 0);  // the check is about capped bonds: some of them must break
}

// A chain and a layer of bonded spheres in an open cell have no three-dimensional tessellation
// (geometry::LaguerreFaces leaves every face open): the face-capped law falls back to the
// isolated necks, stiffness and section alike, without calling CGAL on a flat point set.
TEST(DenseStrength, ChainsAndLayersInAnOpenCellKeepTheIsolatedNecks) {
  const double R = 1e-6;
  const std::vector<std::vector<Vec3>> shapes{{{0, 0, 0}, {1.8 * R, 0, 0}, {3.6 * R, 0, 0}},
                                              {{0, 0, 0}, {1.8 * R, 0, 0}, {0, 1.8 * R, 0}, {1.8 * R, 1.8 * R, 0}}};
  for (const std::vector<Vec3>& x : shapes) {
    Network net;
    Packing& p = net.packing;
    for (const Vec3& c : x) {
      p.particles.position.push_back(c);
      p.particles.radius.push_back(R);
      p.particles.phase.push_back(0);
    }
    p.cell = Cell::box({-10 * R, -10 * R, -10 * R}, {10 * R, 10 * R, 10 * R}, false);
    p.materials = {alumina()};
    bond_ratio(net, 0.4);
    ASSERT_EQ(p.bonds.size(), x.size() - 1 + (x.size() == 4 ? 1 : 0));
    FailureOptions f;
    const std::vector<dem::BondLaw> laws = lefm_laws(p, f);
    std::vector<double> section;
    const BondStiffnesses k = bond_stiffnesses(p, laws, section);
    EXPECT_EQ(k.face_capped, 0);
    EXPECT_EQ(k.no_face, 0);
    for (std::size_t b = 0; b < p.bonds.size(); ++b) {
      EXPECT_EQ(k.kn[b], dem::bond_stiffness(laws[0], p.bonds.radius[b], R, R).kn);  // same formula: exact
      EXPECT_EQ(section[b], p.bonds.radius[b]);
    }
  }
}
