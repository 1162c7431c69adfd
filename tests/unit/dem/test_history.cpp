// Contact history (the Mindlin springs) follows its pair across neighbour-list rebuilds and
// periodic wraps, and a measurement leaves it as it was (issue 19: a measurement saves only the
// pairs that carry history, not a copy per listed pair).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <random>
#include <utility>

#include "scenes.hpp"
#include "tomodem/dem/simulation.hpp"

namespace tomodem::dem {
namespace {

constexpr double kR = 0.5e-3, kDt = 1.35e-6;
constexpr int kCells = 6;

ContactModel hertz_mindlin() {
  return testing::model(NormalLaw::hertz, TangentialLaw::mindlin, testing::material(1e8, 0.25, 2500), 0.5, 0.5);
}

/// kCells³ spheres on a jittered simple cubic lattice in a periodic cube, random velocities of
/// amplitude `speed` plus a common `drift` (which carries spheres through the periodic faces).
/// The same seed gives the same state whatever the skin.
Simulation lattice(double spacing, double speed, const Vec3& drift, double skin, int threads) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  Particles p;
  for (int a = 0; a < kCells; ++a)
    for (int b = 0; b < kCells; ++b)
      for (int c = 0; c < kCells; ++c) {
        const Vec3 x{(a + 0.5) * spacing, (b + 0.5) * spacing, (c + 0.5) * spacing};
        const std::size_t i = p.add(x + Vec3{u(rng), u(rng), u(rng)} * (0.015 * kR), kR, 2500, 0);
        p.v[i] = drift + Vec3{u(rng), u(rng), u(rng)} * speed;
      }
  Settings s;
  s.skin = skin;
  s.threads = threads;
  const double side = kCells * spacing;
  Simulation sim(std::move(p), Cell::box({0, 0, 0}, {side, side, side}, true), hertz_mindlin(), s);
  sim.set_time_step(kDt);
  return sim;
}

/// The history of every listed pair that carries one, by the ids of its two spheres (the cell
/// is wider than twice the cut-off, so a pair is listed through one image only).
std::map<std::pair<int64_t, int64_t>, Vec3> springs(const Simulation& sim) {
  const Simulation::EngineState e = sim.engine_state();
  const auto& id = sim.particles().id;
  EXPECT_EQ(e.history.size(), 3 * e.j.size());  // Mindlin: one 3-vector per pair
  std::map<std::pair<int64_t, int64_t>, Vec3> out;
  for (std::size_t i = 0; i + 1 < e.start.size(); ++i)
    for (int k = e.start[i]; k < e.start[i + 1]; ++k) {
      const Vec3 h{e.history[3 * std::size_t(k)], e.history[3 * std::size_t(k) + 1], e.history[3 * std::size_t(k) + 2]};
      if (norm(h) == 0) continue;
      const int64_t a = id[i], b = id[std::size_t(e.j[k])];
      EXPECT_TRUE(out.emplace(std::minmax(a, b), h).second) << "pair " << a << "-" << b << " listed twice";
    }
  return out;
}

TEST(DemHistory, FollowsPairsAcrossRebuildsAndPeriodicFaces) {
  // A jammed frictional lattice (neighbours overlap by 1.6 % of d) drifting at 2.5 m/s through
  // its periodic faces. Skin 0.2 d: a rebuild every ~20 steps; skin 0.001 d: one every step,
  // each carrying every spring to the new list and re-imaging the pairs that crossed a face.
  const double spacing = 0.9837 * 2 * kR, side = kCells * spacing;
  const Vec3 drift{2.5, 1.5, 0.8};
  const int steps = 400;
  Simulation wide = lattice(spacing, 0.1, drift, 0.2 * 2 * kR, 1);
  Simulation narrow = lattice(spacing, 0.1, drift, 0.001 * 2 * kR, 1);
  const std::vector<Vec3> x0 = wide.particles().x;
  wide.run(steps);
  narrow.run(steps);
  EXPECT_LE(wide.engine_state().builds, steps / 10);
  EXPECT_GE(narrow.engine_state().builds, steps - 1);
  int crossed = 0;  // spheres wrapped through a face (a jump of a cell side in a coordinate)
  for (std::size_t i = 0; i < x0.size(); ++i) {
    const Vec3 dx = narrow.particles().x[i] - x0[i];
    crossed += std::abs(dx.x) > side / 2 || std::abs(dx.y) > side / 2 || std::abs(dx.z) > side / 2;
  }
  EXPECT_GE(crossed, int(x0.size()) / 10);

  const auto a = springs(wide), b = springs(narrow);
  ASSERT_EQ(a.size(), b.size());
  // Every one of the 3 n contacts of the lattice carries a spring.
  EXPECT_EQ(a.size(), 3u * kCells * kCells * kCells);
  double largest = 0;
  for (const auto& kv : a) largest = std::max(largest, norm(kv.second));
  // The springs hold many steps of tangential motion: a history lost at a rebuild would leave
  // one step's increment (|v_rel| Δt ≤ 2 · 0.17 m/s · Δt), far below them.
  EXPECT_GT(largest, 20 * 0.35 * kDt);
  double worst = 0;  // largest difference of a spring between the runs, over the largest spring
  for (const auto& [pair, h] : a) {
    const auto it = b.find(pair);
    ASSERT_NE(it, b.end()) << "pair " << pair.first << "-" << pair.second << " lost its history";
    worst = std::max(worst, norm(h - it->second) / largest);
  }
  // The two runs differ only by round-off: wraps at other times (x - L is not exact) and other
  // list orders (force sums). 1e-9 is far above that round-off after 400 steps of a jammed state
  // (measured: 5e-13) and far below a lost or misassigned spring (of the order of 1).
  RecordProperty("worst_relative_difference", ::testing::PrintToString(worst));
  EXPECT_LE(worst, 1e-9);
}

/// Runs `steps` steps, measuring before the first (no spring set yet: the measurement's own
/// springs must be cleared) and after each when `measure`; the state, bit for bit.
struct Trajectory {
  std::vector<Vec3> x, v, omega;
  std::vector<double> history;
};
Trajectory run(Simulation sim, int steps, bool measure) {
  if (measure) sim.measure();
  for (int s = 0; s < steps; ++s) {
    sim.step();
    if (measure) sim.measure();
  }
  return {sim.particles().x, sim.particles().v, sim.particles().omega, sim.engine_state().history};
}

void expect_same_bits(const Trajectory& a, const Trajectory& b) {
  auto same = [](const std::vector<Vec3>& p, const std::vector<Vec3>& q) {
    return p.size() == q.size() && std::memcmp(p.data(), q.data(), p.size() * sizeof(Vec3)) == 0;
  };
  EXPECT_TRUE(same(a.x, b.x));
  EXPECT_TRUE(same(a.v, b.v));
  EXPECT_TRUE(same(a.omega, b.omega));
  ASSERT_EQ(a.history.size(), b.history.size());
  EXPECT_EQ(std::memcmp(a.history.data(), b.history.data(), a.history.size() * sizeof(double)), 0);
}

TEST(DemHistory, MeasuringLeavesTheTrajectoryUnchangedDilute) {
  // A gas (spacing 1.1 d, 1 m/s): few of the listed pairs touch, so the measurement saves the
  // history of those alone; contacts open and close between measurements. Two threads.
  const Vec3 drift{0.3, 0, 0};
  const auto with = run(lattice(1.1 * 2 * kR, 1.0, drift, 0.4 * 2 * kR, 2), 150, true);
  const auto without = run(lattice(1.1 * 2 * kR, 1.0, drift, 0.4 * 2 * kR, 2), 150, false);
  int touching = 0;
  for (std::size_t k = 0; k < with.history.size(); k += 3) touching += with.history[k] != 0 || with.history[k + 1] != 0;
  EXPECT_GT(touching, 0);                                 // the premise: springs to restore ...
  EXPECT_LT(touching, int(with.history.size() / 3) / 4);  // ... on few of the listed pairs
  expect_same_bits(with, without);
}

TEST(DemHistory, MeasuringLeavesTheTrajectoryUnchangedDense) {
  // Every listed pair touches: the measurement copies the whole history.
  const auto with = run(lattice(0.9837 * 2 * kR, 0.1, {0, 0, 0}, 0.1 * 2 * kR, 2), 100, true);
  const auto without = run(lattice(0.9837 * 2 * kR, 0.1, {0, 0, 0}, 0.1 * 2 * kR, 2), 100, false);
  expect_same_bits(with, without);
}

}  // namespace
}  // namespace tomodem::dem
