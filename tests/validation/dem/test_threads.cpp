// Threads: the force loop splits particles among threads and reduces per-thread buffers in a
// fixed order, so 1 and 2 threads differ only by the order of floating-point additions, and a
// repeated run with the same thread count is bit-identical.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "packings.hpp"

using namespace tomodem;
using namespace tomodem::dem;
using namespace tomodem::dem::testing;

namespace {
constexpr double R = 1e-3, rho = 2500, E = 1e8, nu = 0.25;

/// 216 polydisperse spheres (±10%), compressed (spacing 1.98 R̄: ~200 contacts), random
/// velocities, Hertz–Mindlin with friction and rolling resistance: every history stage is in
/// use and each thread owns ~100 particles, with contacts across the split.
Simulation scene(int threads) {
  ContactModel m = model(NormalLaw::hertz, TangentialLaw::mindlin, material(E, nu, rho), 0.5, 0.5);
  m.rolling = RollingLaw::elastic_plastic;
  m.pair(0, 0).rolling_friction = 0.1;
  m.finalize();
  LatticeSpec s;
  s.n = 6;
  s.radius = R;
  s.polydispersity = 0.1;
  s.spacing = 1.98;
  s.jitter = 0.05;
  s.speed = 0.05;
  Settings set;
  set.threads = threads;
  Simulation sim = lattice(m, s, set);
  sim.set_time_step(0.2 * sim.critical_time_step());
  return sim;
}

double max_position_difference(const Particles& a, const Particles& b) {
  double d = 0;
  for (std::size_t i = 0; i < a.size(); ++i) d = std::max(d, norm(a.x[i] - b.x[i]));
  return d;
}
}  // namespace

// 300 steps with ~200 contacts. Round-off from the reordered sums (1e-16 relative) grows
// through the contact dynamics, but over 300 steps stays far below the 1e-12 of the cell
// size the issue asks for (measured 5e-14).
TEST(Threads, OneAndTwoThreadsAgreeToRoundOff) {
  Simulation one = scene(1), two = scene(2);
  one.run(300);
  two.run(300);
  const Measurements me = one.measure();
  ASSERT_GT(me.contacts, 100);
  const double L = one.cell().h(0, 0);
  report("max |x1 - x2| / L", max_position_difference(one.particles(), two.particles()) / L);
  report("contacts", double(me.contacts));
  EXPECT_LT(max_position_difference(one.particles(), two.particles()) / L, 1e-12);
  const Measurements m2 = two.measure();
  EXPECT_NEAR(m2.pressure / me.pressure, 1.0, 1e-10);
}

TEST(Threads, SameInputSameThreadCountIsBitIdentical) {
  for (int threads : {1, 2}) {
    Simulation a = scene(threads), b = scene(threads);
    a.run(300);
    b.run(300);
    const Particles &pa = a.particles(), &pb = b.particles();
    EXPECT_EQ(std::memcmp(pa.x.data(), pb.x.data(), pa.size() * sizeof(Vec3)), 0) << threads << " threads";
    EXPECT_EQ(std::memcmp(pa.v.data(), pb.v.data(), pa.size() * sizeof(Vec3)), 0) << threads << " threads";
    EXPECT_EQ(std::memcmp(pa.omega.data(), pb.omega.data(), pa.size() * sizeof(Vec3)), 0) << threads << " threads";
  }
}
