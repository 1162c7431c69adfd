// Simulation::contacts() holds O(contacts) memory, not O(listed pairs) (issue 19: the CLI's
// memory per particle): counted in bytes through a replaced global operator new, so the test
// does not depend on the machine or the allocator. Also checks the table itself against the
// Hertz formula and a brute-force search, and that taking it leaves the trajectory unchanged.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <new>

#include "tomodem/dem/simulation.hpp"

namespace {
// Bytes live on the heap and the most live since the last reset_peak(). A 16-byte header keeps
// each block's size (and the default alignment of new).
std::atomic<long> g_live{0}, g_peak{0};
void* counted_alloc(std::size_t n) {
  void* p = std::malloc(n + 16);
  if (!p) throw std::bad_alloc();
  *static_cast<std::size_t*>(p) = n;
  const long now = g_live += long(n);
  for (long peak = g_peak; now > peak && !g_peak.compare_exchange_weak(peak, now);) {
  }
  return static_cast<char*>(p) + 16;
}
void counted_free(void* p) {
  if (!p) return;
  void* block = static_cast<char*>(p) - 16;
  g_live -= long(*static_cast<std::size_t*>(block));
  std::free(block);
}
long reset_peak() { return g_peak = g_live.load(); }
}  // namespace

void* operator new(std::size_t n) { return counted_alloc(n); }
void* operator new[](std::size_t n) { return counted_alloc(n); }
void operator delete(void* p) noexcept { counted_free(p); }
void operator delete[](void* p) noexcept { counted_free(p); }
void operator delete(void* p, std::size_t) noexcept { counted_free(p); }
void operator delete[](void* p, std::size_t) noexcept { counted_free(p); }

namespace tomodem::dem {
namespace {

constexpr double kR = 0.5e-3, kE = 1e8, kNu = 0.25, kRho = 2500;

ContactModel hertz_mindlin() {
  ContactModel m;
  m.normal = NormalLaw::hertz;
  m.tangential = TangentialLaw::mindlin;
  Material mat;
  mat.name = "glass";
  mat.youngs_modulus = kE;
  mat.poisson_ratio = kNu;
  mat.density = kRho;
  m.materials = {mat};
  m.finalize();
  m.pair(0, 0).restitution = 0.5;
  m.pair(0, 0).friction = 0.5;
  m.finalize();
  return m;
}

/// n³ spheres on a simple cubic lattice of `spacing` in a periodic cube; every `every`-th
/// sphere is moved by `shift` along x, towards its -x neighbour. At rest.
Simulation lattice(int n, double spacing, double skin, int every, double shift, int threads = 1) {
  Particles p;
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b)
      for (int c = 0; c < n; ++c) p.add({(a + 0.5) * spacing, (b + 0.5) * spacing, (c + 0.5) * spacing}, kR, kRho, 0);
  for (std::size_t i = 0; every > 0 && i < p.size(); i += std::size_t(every)) p.x[i].x -= shift;
  Settings s;
  s.skin = skin;
  s.threads = threads;
  return Simulation(std::move(p), Cell::box({0, 0, 0}, {n * spacing, n * spacing, n * spacing}, true), hertz_mindlin(), s);
}

/// Overlapping pairs by brute force (minimum image in the periodic cube of edge L).
long overlapping_pairs(const Particles& p, double L) {
  long count = 0;
  for (std::size_t i = 0; i < p.size(); ++i)
    for (std::size_t j = i + 1; j < p.size(); ++j) {
      Vec3 d = p.x[j] - p.x[i];
      for (double* c : {&d.x, &d.y, &d.z}) *c -= L * std::round(*c / L);
      count += norm(d) < p.r[i] + p.r[j];
    }
  return count;
}

/// Every contact of the table: the overlap from the positions, the normal force of Hertz's law
/// at rest, F = 4/3 E* sqrt(R*) δ^3/2 (no damping or tangential force without motion).
void expect_hertz_table(const ContactTable& ct, const Particles& p, double L) {
  const double e_star = kE / (2 * (1 - kNu * kNu)), r_star = kR / 2;
  for (std::size_t c = 0; c < ct.size(); ++c) {
    Vec3 d = p.x[std::size_t(ct.j[c])] - p.x[std::size_t(ct.i[c])];
    for (double* x : {&d.x, &d.y, &d.z}) *x -= L * std::round(*x / L);
    const double delta = 2 * kR - norm(d);
    // Round-off of a difference of positions ~1e-3 m: 1e-18 m against overlaps >= 1e-6 m.
    EXPECT_NEAR(ct.overlap[c], delta, 1e-15);
    const double f = 4.0 / 3.0 * e_star * std::sqrt(r_star) * std::pow(delta, 1.5);
    EXPECT_NEAR(norm(ct.normal_force[c]), f, 1e-9 * f);  // a few round-offs of the law's sums
    EXPECT_GT(dot(ct.normal_force[c], d), 0);  // on j from i: pushes j away
    EXPECT_LE(norm(ct.tangential_force[c]), 1e-12 * f);  // the normal part taken off: round-off
  }
}

// A dilute state: 9 listed pairs per sphere (skin 0.65 d reaches the 18 neighbours at 1.1 d and
// 1.56 d, not those at 1.91 d), one sphere in 40 moved into contact with its -x neighbour.
constexpr int kN = 12;
constexpr double kSpacing = 2.2 * kR, kSkin = 1.3 * kR, kShift = 0.24 * kR;

TEST(DemContactOutput, HoldsBytesPerContactNotPerListedPair) {
  Simulation sim = lattice(kN, kSpacing, kSkin, 40, kShift);
  sim.measure();  // builds the list and sizes the per-particle tallies before the count
  const std::size_t n = sim.particles().size();
  const std::size_t pairs = sim.engine_state().j.size();
  ASSERT_GE(pairs, 8 * n);  // the premise: many more listed pairs than contacts
  const long before = reset_peak();
  const ContactTable ct = sim.contacts();
  const long held = g_peak - before;
  const std::size_t contacts = ct.size();
  EXPECT_EQ(long(contacts), overlapping_pairs(sim.particles(), kN * kSpacing));
  ASSERT_GT(contacts, 0u);
  ASSERT_LT(contacts, n / 10);
  // What the contacts path needs: a CSR start per particle (4 B), the saved forces and torques
  // (2 x 24 B per particle), and per contact its list entry, history, owner, force and table row
  // (under 256 B); 64 KiB for what does not scale (vectors of one entry per thread, the
  // measurement). The old path held a force and a history copy per listed pair (48 B each:
  // 432 B per particle here), which is more than this bound.
  const long bound = long(52 * n + 256 * contacts) + 65536;
  EXPECT_LE(held, bound) << "contacts() held " << held << " B for " << contacts << " contacts, " << pairs << " listed pairs";
  EXPECT_LT(bound, long(48 * pairs));  // the bound tells the two paths apart
  expect_hertz_table(ct, sim.particles(), kN * kSpacing);
}

TEST(DemContactOutput, DenseStateEveryListedPairInContact) {
  // Spacing 0.98 d: the six nearest neighbours overlap by 2 % of d, the next ones (1.39 d) are
  // beyond the skin, so every listed pair is a contact (the table comes from the list itself).
  const int n = 8;
  Simulation sim = lattice(n, 0.98 * 2 * kR, 0.1 * kR, 0, 0);
  const ContactTable ct = sim.contacts();
  EXPECT_EQ(ct.size(), 3u * n * n * n);
  EXPECT_EQ(long(ct.size()), overlapping_pairs(sim.particles(), n * 0.98 * 2 * kR));
  EXPECT_EQ(sim.engine_state().j.size(), ct.size());
  expect_hertz_table(ct, sim.particles(), n * 0.98 * 2 * kR);
}

TEST(DemContactOutput, TakingTheTableLeavesTheTrajectoryUnchanged) {
  // Two threads: the narrowed list of the contacts pass has its own thread split and pair
  // owners, and the list's own must be back afterwards. Moving spheres, so history matters.
  auto run = [](bool take_contacts) {
    Simulation sim = lattice(kN, kSpacing, kSkin, 40, kShift, 2);
    for (std::size_t i = 0; i < sim.particles().size(); ++i) sim.particles().v[i] = {0.01 * double(i % 7), -0.02, 0.03 * double(i % 3)};
    sim.set_time_step(0.2 * sim.critical_time_step());
    sim.run(3);  // the moved spheres still overlap their neighbours
    if (take_contacts) EXPECT_GT(sim.contacts().size(), 0u);
    sim.run(50);
    return sim.particles().x;
  };
  const auto with = run(true), without = run(false);
  ASSERT_EQ(with.size(), without.size());
  for (std::size_t i = 0; i < with.size(); ++i) {  // bit for bit
    EXPECT_EQ(with[i].x, without[i].x);
    EXPECT_EQ(with[i].y, without[i].y);
    EXPECT_EQ(with[i].z, without[i].z);
  }
}

}  // namespace
}  // namespace tomodem::dem
