// Building the network: contact detection (cell list vs brute force, periodic images), contact
// radii, Holm conductances, phase selection and bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <tuple>

#include "../../validation/network/lattice.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/network/network.hpp"

using namespace tomodem;
using namespace tomodem::network;

namespace {
using Key = std::tuple<int, int, int, int, int>;

std::set<Key> brute_force(const std::vector<Vec3>& x, const std::vector<double>& r, const Cell& c, double tol) {
  std::set<Key> out;
  const int n = static_cast<int>(x.size());
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      for (int a = -1; a <= 1; ++a)
        for (int b = -1; b <= 1; ++b)
          for (int d = -1; d <= 1; ++d) {
            const int w[3] = {a, b, d};
            bool ok = true;
            for (int k = 0; k < 3; ++k) ok = ok && (c.periodic[k] || w[k] == 0);
            if (!ok) continue;
            const Vec3 bvec = x[j] + c.h * Vec3(a, b, d) - x[i];
            // The contact definition: gap ≤ tol · R̄, R̄ = 2 R_i R_j / (R_i + R_j).
            const double rbar = 2 * r[i] * r[j] / (r[i] + r[j]);
            if (norm(bvec) - r[i] - r[j] <= tol * rbar) out.insert({i, j, a, b, d});
          }
  return out;
}

void compare_with_brute_force(bool periodic, int n, double box, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0, 1);
  std::vector<Vec3> x(n);
  std::vector<double> r(n);
  Cell c = Cell::box({-1, 2, 0}, {-1 + box, 2 + 0.8 * box, 1.2 * box}, periodic);
  for (int p = 0; p < n; ++p) {
    // Some positions outside the cell, to exercise wrapping of unwrapped coordinates.
    x[p] = c.origin + Vec3((1.4 * U(rng) - 0.2) * box, U(rng) * 0.8 * box, U(rng) * 1.2 * box);
    r[p] = 0.3 + 0.4 * U(rng);
  }
  const ContactPairs cp = find_contacts(x, r, c, 1e-3);
  std::set<Key> got;
  for (std::size_t k = 0; k < cp.i.size(); ++k)
    got.insert({cp.i[k], cp.j[k], cp.image[k][0], cp.image[k][1], cp.image[k][2]});
  EXPECT_EQ(got.size(), cp.i.size()) << "duplicate pairs";
  const auto want = brute_force(x, r, c, 1e-3);
  EXPECT_EQ(got, want);
  EXPECT_GT(want.size(), 0u);
}
}  // namespace

TEST(Contacts, CellListMatchesBruteForceOpen) { compare_with_brute_force(false, 300, 8.0, 1); }
TEST(Contacts, CellListMatchesBruteForcePeriodic) { compare_with_brute_force(true, 300, 8.0, 2); }
// A periodic cell only ~2 cutoffs wide: the -1 and +1 neighbour bins are distinct images.
TEST(Contacts, CellListMatchesBruteForceSmallPeriodicCell) { compare_with_brute_force(true, 20, 2.9, 3); }

TEST(Network, HolmConductanceOfLikeAndUnlikePhases) {
  // Like phases: 1/(4σa) + 1/(4σa) = 1/(2σa).
  EXPECT_DOUBLE_EQ(holm_conductance(0.1, 3.0, 3.0), 2 * 3.0 * 0.1);
  // Unlike: halves in series.
  const double R = 1 / (4 * 2.0 * 0.1) + 1 / (4 * 8.0 * 0.1);
  EXPECT_NEAR(holm_conductance(0.1, 2.0, 8.0), 1 / R, 1e-15);
}

TEST(Network, GeometricAndHertzContactRadius) {
  Packing p = test::sc_lattice(2, 1, 1, 1.0, 0.1, false);
  p.bonds = BondTable{};
  // Radii 1.1: overlap δ = 0.2 at distance 2.
  p.particles.radius = {1.1, 1.1};
  NetworkOptions o;
  Network g = build_network(p, o);
  ASSERT_EQ(g.n_edges(), 1u);
  EXPECT_NEAR(g.contact_radius[0], std::sqrt(1.1 * 1.1 - 1.0), 1e-14);
  o.contact_radius = ContactRadius::hertz;
  Network h = build_network(p, o);
  EXPECT_NEAR(h.contact_radius[0], std::sqrt(0.55 * 0.2), 1e-14);
  EXPECT_NEAR(h.graph.g[0], 2 * 1.0 * h.contact_radius[0], 1e-14);
}

// Hertz radius from the packing's contact force: a = (3 F R* / 4 E*)^(1/3), 1/E* = Σ (1 − ν²)/E
// (docs/physics.md#resistor-networks), conductance 2σa for like phases (σ = 1 S/m here).
TEST(Network, HertzRadiusFromContactForce) {
  Packing p = test::sc_lattice(2, 1, 1, 1.0, 0.1, false);
  p.bonds = BondTable{};
  p.particles.radius = {1.0, 1.0};  // touching at distance 2
  p.materials[0].youngs_modulus = 2e9;
  p.materials[0].poisson_ratio = 0.25;
  p.contacts.i = {0};
  p.contacts.j = {1};
  p.contacts.overlap = {0.0};
  p.contacts.normal_force = {Vec3{3e6, 0, 0}};
  p.contacts.tangential_force = {Vec3{0, 0, 0}};
  NetworkOptions o;
  o.contact_radius = ContactRadius::hertz_force;
  const Network g = build_network(p, o);
  ASSERT_EQ(g.n_edges(), 1u);
  const double estar = 1 / (2 * (1 - 0.25 * 0.25) / 2e9), rstar = 0.5;
  const double a = std::cbrt(3 * 3e6 * rstar / (4 * estar));  // 0.1018
  EXPECT_NEAR(g.contact_radius[0], a, 1e-12 * a);
  EXPECT_NEAR(g.graph.g[0], 2 * 1.0 * a, 1e-12 * a);
  EXPECT_EQ(parse_contact_radius("hertz-force"), ContactRadius::hertz_force);
  // No contact forces in the packing: bad input naming the dataset.
  p.contacts = ContactTable{};
  try {
    build_network(p, o);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "/contacts/normal_force");
  }
}

TEST(Network, BondReplacesContactAndBrokenBondsAreIgnored) {
  Packing p = test::sc_lattice(3, 1, 1, 1.0, 0.25, false);
  Network n = build_network(p, NetworkOptions{});
  ASSERT_EQ(n.n_edges(), 2u);  // two bonds; the touching contacts are the same pairs
  EXPECT_EQ(n.kind[0], EdgeKind::bond);
  EXPECT_DOUBLE_EQ(n.contact_radius[0], 0.25);
  p.bonds.state[0] = BondTable::broken;
  Network b = build_network(p, NetworkOptions{});
  ASSERT_EQ(b.n_edges(), 2u);  // the broken bond's pair is still a touching contact
  int contacts = 0;
  for (auto k : b.kind) contacts += k == EdgeKind::contact;
  EXPECT_EQ(contacts, 1);
}

TEST(Network, PeriodicBondsTakeTheNearestImage) {
  Packing p = test::sc_lattice(4, 3, 3, 1.0, 0.2, true);
  Network n = build_network(p, NetworkOptions{});
  EXPECT_EQ(n.n_edges(), 3u * 36u);
  for (std::size_t e = 0; e < n.n_edges(); ++e) EXPECT_NEAR(norm(n.branch(e)), 2.0, 1e-12) << "edge " << e;
}

TEST(Network, ConductingPhasesSelectNodes) {
  Packing p = test::sc_lattice(4, 1, 1, 1.0, 0.2, false, [](int x, int, int) { return x % 2; });
  NetworkOptions o;
  o.phases = {"B"};
  Network n = build_network(p, o);
  EXPECT_EQ(n.n_nodes(), 2u);
  EXPECT_EQ(n.n_edges(), 0u);  // B particles are not neighbours
}

TEST(NetworkBadInput, UnknownPhaseNamesTheFieldAndValue) {
  Packing p = test::sc_lattice(2, 1, 1, 1.0, 0.2, false);
  NetworkOptions o;
  o.phases = {"A", "Nickel"};
  o.source = "in.h5";
  try {
    build_network(p, o);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "--phases");
    EXPECT_EQ(e.value(), "Nickel");
    EXPECT_NE(std::string(e.what()).find("A, B"), std::string::npos) << e.what();
  }
}

TEST(NetworkBadInput, NonPositiveConductivity) {
  Packing p = test::sc_lattice(2, 1, 1, 1.0, 0.2, false);
  p.particles.phase[1] = 1;  // B has a particle, so it conducts by default
  p.materials[1].conductivity = -3;
  NetworkOptions o;
  o.source = "in.h5";
  try {
    build_network(p, o);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "in.h5");
    EXPECT_EQ(e.field(), "/materials/1/conductivity_S_per_m");
    EXPECT_EQ(std::stod(e.value()), -3.0);
  }
  o.phases = {"A"};  // B does not conduct: its conductivity is not needed
  EXPECT_NO_THROW(build_network(p, o));
}

// A material without particles (a pore former removed after packing) is not asked for a
// conductivity by default; named in --phases it still is.
TEST(NetworkBadInput, MaterialWithoutParticlesNeedsNoConductivity) {
  Packing p = test::sc_lattice(2, 1, 1, 1.0, 0.2, false);
  Material pore_former = p.materials[0];
  pore_former.name = "pore_former";
  pore_former.conductivity = 0;
  p.materials.push_back(pore_former);
  const Network reference = build_network(test::sc_lattice(2, 1, 1, 1.0, 0.2, false), NetworkOptions{});
  const Network net = build_network(p, NetworkOptions{});
  EXPECT_EQ(net.conducting[2], 0);
  EXPECT_EQ(net.n_edges(), reference.n_edges());
  NetworkOptions o;
  o.phases = {"A", "pore_former"};
  EXPECT_THROW(build_network(p, o), InputError);
}

TEST(NetworkBadInput, EmptyPackingAndNoConductingParticle) {
  Packing empty;
  empty.materials.resize(1);
  empty.materials[0].conductivity = 1;
  EXPECT_THROW(build_network(empty, NetworkOptions{}), InputError);
  Packing p = test::sc_lattice(2, 1, 1, 1.0, 0.2, false);
  NetworkOptions o;
  o.phases = {"B"};
  EXPECT_THROW(build_network(p, o), InputError);
}
