// Effective conductivity of lattices against closed forms (docs/physics.md#resistor-networks).
#include <gtest/gtest.h>

#include <cmath>

#include "lattice.hpp"
#include "tomodem/network/conductivity.hpp"

using namespace tomodem;
using namespace tomodem::network;

namespace {
ConductOptions tight() {
  ConductOptions o;
  o.solver.tolerance = 1e-12;  // solver error ≪ the 1e-6 criterion
  return o;
}
// Relative tolerance of the criterion; the solves reach 1e-12, so only round-off remains.
constexpr double kRel = 1e-6;
// The closed forms below check the solver for a given edge conductance G = 2σa: Holm's law alone
// (--isolated-necks). The dense-network law is tested against voxel solutions (neck_law_test.cpp).
NetworkOptions holm_edges() {
  NetworkOptions o;
  o.face_cap = false;
  return o;
}
}  // namespace

// σ_eff = G/(2R) for a simple cubic lattice of spacing 2R and edge conductance G, with electrodes
// on each pair of faces; G = 2σa (Holm, like phases).
TEST(Conduct, SimpleCubicLatticeMatchesAnalytic) {
  const double R = 5e-6, a = 1e-6, sigma = 1e4;
  Packing p = test::sc_lattice(7, 6, 5, R, a, false);
  p.materials[0].conductivity = sigma;
  const Network net = build_network(p, holm_edges());
  const double G = 2 * sigma * a;
  for (int axis = 0; axis < 3; ++axis) {
    const AxisResult r = solve_electrodes(net, axis, tight());
    ASSERT_TRUE(r.percolates);
    EXPECT_NEAR(r.sigma_eff, G / (2 * R), kRel * G / (2 * R)) << "axis " << axis;
    EXPECT_LT(r.conservation_error, 1e-9);
    EXPECT_NEAR(r.percolating_fraction, 1.0, 1e-15);
    EXPECT_NEAR(r.dead_end_fraction, 0.0, 1e-15);
  }
}

// The same lattice, periodic, under imposed mean fields: the full tensor is G/(2R)·I.
TEST(Conduct, SimpleCubicLatticePeriodicTensor) {
  const double R = 1.0, a = 0.3;
  Packing p = test::sc_lattice(4, 5, 3, R, a, true);
  const Network net = build_network(p, holm_edges());
  const TensorResult t = solve_periodic(net, tight());
  const double s = 2 * a / (2 * R);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(t.sigma[r][c], r == c ? s : 0.0, kRel * s) << r << c;
  for (int k = 0; k < 3; ++k) EXPECT_TRUE(t.wraps[k]);
}

// Contacts instead of bonds: spheres of radius 1.05 at spacing 2 overlap; the geometric contact
// radius is sqrt(1.05² − 1) and the cell-list detection must find every lattice neighbour.
TEST(Conduct, SimpleCubicLatticeFromOverlapContacts) {
  Packing p = test::sc_lattice(6, 6, 6, 1.0, 0.1, false);
  p.bonds = BondTable{};
  for (auto& r : p.particles.radius) r = 1.05;
  const Network net = build_network(p, holm_edges());
  EXPECT_EQ(net.n_edges(), 3u * 5u * 36u);
  const double a = std::sqrt(1.05 * 1.05 - 1.0), G = 2 * a;
  const AxisResult r = solve_electrodes(net, 2, tight());
  EXPECT_NEAR(r.sigma_eff, G / 2.0, kRel * G / 2.0);
}

// Layers of two phases (two particle layers each, alternating along x): current across the
// layers sees the series (harmonic) bound, current along them the parallel (arithmetic) bound of
// the two phases' lattice conductivities σ_k a/R. Holm halves make both exact on the lattice.
TEST(Conduct, LayeredTwoPhaseSeriesAndParallelBounds) {
  const double R = 1.0, a = 0.2, s1 = 2.0, s2 = 30.0;
  Packing p = test::sc_lattice(8, 4, 4, R, a, true, [](int x, int, int) { return (x / 2) % 2; });
  p.materials[0].conductivity = s1;
  p.materials[1].conductivity = s2;
  const Network net = build_network(p, holm_edges());
  const double l1 = s1 * a / R, l2 = s2 * a / R;
  const double series = 2.0 / (1.0 / l1 + 1.0 / l2), parallel = 0.5 * (l1 + l2);
  const TensorResult t = solve_periodic(net, tight());
  EXPECT_NEAR(t.sigma[0][0], series, kRel * series);
  EXPECT_NEAR(t.sigma[1][1], parallel, kRel * parallel);
  EXPECT_NEAR(t.sigma[2][2], parallel, kRel * parallel);
  // Electrodes across the layers: 7 edges in series per chain, σ = (n−1)·2R / (2R·Σ 1/G)·…
  Packing q = test::sc_lattice(8, 4, 4, R, a, false, [](int x, int, int) { return (x / 2) % 2; });
  q.materials = p.materials;
  const Network nq = build_network(q, holm_edges());
  double rsum = 0;
  for (int x = 0; x + 1 < 8; ++x) {
    const double sa = (x / 2) % 2 ? s2 : s1, sb = ((x + 1) / 2) % 2 ? s2 : s1;
    // Holm (docs/physics.md): 1/(4σa) on each side of the constriction, in series.
    rsum += 1.0 / (4 * sa * a) + 1.0 / (4 * sb * a);
  }
  // One chain per lattice column: I = 16/rsum over A = (8R)², L = 7·2R.
  const double want = 16.0 / rsum * 14.0 * R / (64.0 * R * R);
  const AxisResult r = solve_electrodes(nq, 0, tight());
  EXPECT_NEAR(r.sigma_eff, want, kRel * want);
  const AxisResult ry = solve_electrodes(nq, 1, tight());
  EXPECT_NEAR(ry.sigma_eff, parallel, kRel * parallel);
}

// Extreme contrast 1e8 between the layers: both bounds still exact (the IC factorisation scales
// the diagonal, so the contrast does not slow convergence much).
TEST(Conduct, ExtremeContrast1e8) {
  const double R = 1.0, a = 0.2, s1 = 1e-4, s2 = 1e4;
  Packing p = test::sc_lattice(8, 4, 4, R, a, true, [](int x, int, int) { return (x / 2) % 2; });
  p.materials[0].conductivity = s1;
  p.materials[1].conductivity = s2;
  const Network net = build_network(p, holm_edges());
  const double l1 = s1 * a / R, l2 = s2 * a / R;
  const double series = 2.0 / (1.0 / l1 + 1.0 / l2), parallel = 0.5 * (l1 + l2);
  ConductOptions o = tight();
  o.solver.tolerance = 1e-14;
  const TensorResult t = solve_periodic(net, o);
  EXPECT_NEAR(t.sigma[0][0], series, kRel * series);
  EXPECT_NEAR(t.sigma[1][1], parallel, kRel * parallel);
  for (int k = 0; k < 3; ++k) EXPECT_TRUE(t.axes[k].solver.converged);
}

// Isolated clusters (a floating pair, a cluster touching one face only) are left out of the
// solve and reported; the spanning lattice still gives G/(2R) over its own cross-section.
TEST(Conduct, IsolatedClustersAreReportedNotSolved) {
  const double R = 1.0, a = 0.2;
  // Column lattice 6×2×2 (x) at the bottom of a 6×4×2 cell; the top half keeps only a few bonds.
  Packing p = test::sc_lattice(6, 4, 2, R, a, false);
  BondTable kept;
  for (std::size_t b = 0; b < p.bonds.size(); ++b) {
    const Vec3 xi = p.particles.position[p.bonds.i[b]], xj = p.particles.position[p.bonds.j[b]];
    const bool bottom = xi.y < 4 && xj.y < 4;
    // Top half: a dangling 3-chain from the low face and an isolated pair in the middle.
    const bool chain = xi.y > 4 && xj.y > 4 && xi.z < 2 && xj.z < 2 && std::abs(xi.y - xj.y) < 1e-9 &&
                       std::abs(xi.y - 5) < 1e-9 && xi.x < 4 && xj.x < 4;
    const bool pair = xi.y > 6 && xj.y > 6 && xi.z > 2 && xj.z > 2 && std::abs(xi.x - 5) < 1e-9 &&
                      std::abs(xj.x - 7) < 1e-9;
    if (!(bottom || chain || pair)) continue;
    kept.i.push_back(p.bonds.i[b]);
    kept.j.push_back(p.bonds.j[b]);
    kept.radius.push_back(a);
    kept.state.push_back(0);
  }
  p.bonds = kept;
  NetworkOptions no;
  no.use_contacts = false;
  const Network net = build_network(p, no);
  const AxisResult r = solve_electrodes(net, 0, tight());
  ASSERT_TRUE(r.percolates);
  EXPECT_EQ(r.n_solved, 24u);  // the 6×2×2 bottom lattice only
  EXPECT_NEAR(r.percolating_fraction, 0.5, 1e-12);
  // Half the cross-section carries current: σ = ½·G/(2R).
  EXPECT_NEAR(r.sigma_eff, 0.5 * 2 * a / (2 * R), kRel * a);
  EXPECT_LT(r.conservation_error, 1e-9);
}

// No path between the electrodes: reported (percolates = false, σ = 0), not an error.
TEST(Conduct, NoPathBetweenElectrodesIsReported) {
  Packing p = test::sc_lattice(6, 3, 3, 1.0, 0.2, false);
  BondTable kept;
  for (std::size_t b = 0; b < p.bonds.size(); ++b) {
    const double xi = p.particles.position[p.bonds.i[b]].x, xj = p.particles.position[p.bonds.j[b]].x;
    if ((xi < 6 && xj > 6) || (xj < 6 && xi > 6)) continue;  // cut the x = 6 plane
    kept.i.push_back(p.bonds.i[b]);
    kept.j.push_back(p.bonds.j[b]);
    kept.radius.push_back(0.2);
  }
  p.bonds = kept;
  NetworkOptions no;
  no.use_contacts = false;
  const Network net = build_network(p, no);
  const AxisResult r = solve_electrodes(net, 0, tight());
  EXPECT_FALSE(r.percolates);
  EXPECT_EQ(r.sigma_eff, 0.0);
  EXPECT_EQ(r.percolating_fraction, 0.0);
  EXPECT_EQ(r.phases.at("A").isolated, 1.0);
  // Along y the cut does not matter.
  EXPECT_TRUE(solve_electrodes(net, 1, tight()).percolates);
}

// Dead ends: a lattice chain with side branches; the branches are percolating but off the backbone.
TEST(Conduct, DeadEndsCarryNoCurrent) {
  Packing p = test::sc_lattice(5, 2, 1, 1.0, 0.2, false);
  BondTable kept;  // chain along x at y = 1, and one-bond branches to y = 3
  for (std::size_t b = 0; b < p.bonds.size(); ++b) {
    kept.i.push_back(p.bonds.i[b]);
    kept.j.push_back(p.bonds.j[b]);
    kept.radius.push_back(0.2);
    const Vec3 xi = p.particles.position[p.bonds.i[b]], xj = p.particles.position[p.bonds.j[b]];
    const bool top_x = xi.y > 2 && xj.y > 2;  // drop the x-bonds of the top row
    if (top_x) { kept.i.pop_back(); kept.j.pop_back(); kept.radius.pop_back(); }
  }
  p.bonds = kept;
  NetworkOptions no;
  no.use_contacts = false;
  const Network net = build_network(p, no);
  const AxisResult r = solve_electrodes(net, 0, tight());
  ASSERT_TRUE(r.percolates);
  // Top row: the two end particles touch the electrodes (terminal, on the backbone); the three
  // middle ones are dead ends: 3 of 10 particles.
  EXPECT_NEAR(r.dead_end_fraction, 0.3, 1e-12);
  EXPECT_NEAR(r.percolating_fraction, 1.0, 1e-12);
  for (std::size_t e = 0; e < net.n_edges(); ++e) {
    const int32_t i = net.graph.i[e], j = net.graph.j[e];
    if (!r.backbone[i] || !r.backbone[j]) {
      EXPECT_NEAR(r.edge_current[e], 0.0, 1e-12);
    }
  }
}
