// The pressure bracket of the quasistatic protocol (geometry::PressureBracket, densify.cpp)
// against its closed forms: on a linear q(φ) the secant lands on the root exactly; a packing that
// unloads as it is compressed (a rearrangement) never sends the next state backwards, where a
// secant through the two states would (φ = −1.3 on a bonded-aggregate packing, a numerical
// failure); the bracket and the φ/2 floor hold.
#include <gtest/gtest.h>

#include <cmath>

#include "tomodem/geometry/pack.hpp"

using tomodem::geometry::PressureBracket;

namespace {
constexpr double kTarget = 1e5;  // Pa
constexpr double kHertz = 2.5;   // α: q = p^(1/(α−1)) = p^(2/3)
}  // namespace

// q(φ) = c (φ − φ_J) above jamming: the secant through two loaded states is exact, and so is a
// Newton step with the exact slope (tolerance: a few ulp of φ).
TEST(PressureBracket, SecantAndNewtonHitTheRootOfALinearQ) {
  const double phi_j = 0.64, c = 4e4;
  PressureBracket b(kHertz, kTarget);
  const auto p_of = [&](double phi) { return std::pow(c * (phi - phi_j), 1.5); };
  const double phi_root = phi_j + b.q_of(kTarget) / c;
  const double newton = b.next(0.645, p_of(0.645), c);
  EXPECT_NEAR(newton, phi_root, 1e-14);
  PressureBracket s(kHertz, kTarget);
  s.next(0.645, p_of(0.645), 0.5 * c);  // a wrong slope: the Newton step misses
  const double secant = s.next(0.646, p_of(0.646), 0.5 * c);
  EXPECT_NEAR(secant, phi_root, 1e-14);
}

// Two loaded states below the target where the denser one carries less (q fell with φ): the
// secant would point to φ = 0.3485 − (q_t − q)·0.0009/(q − q_last) < 0. The next state must be
// denser than the last one.
TEST(PressureBracket, AnUnloadingCompressionStillMovesTowardsTheTarget) {
  PressureBracket b(kHertz, kTarget);
  const double slope = 1e6;
  const double first = b.next(0.347514, 3.42666, slope);
  EXPECT_GT(first, 0.347514);
  const double second = b.next(0.348412, 1.15888, slope);  // the recorded pair of the failure
  EXPECT_GT(second, 0.348412);
  EXPECT_LT(second, 0.348412 + (b.q_of(kTarget) - b.q_of(1.15888)) / slope * (1 + 1e-12));  // the Newton step
  // No slope at all (no stiffness sums): a probe compression, not a division by zero.
  PressureBracket z(kHertz, kTarget);
  const double probe = z.next(0.4, 10.0, 0.0);
  EXPECT_GT(probe, 0.4);
  EXPECT_LT(probe, 0.4 * 1.01);
}

// Above the target the next state is looser but never below half the density; unloaded states
// probe by doubling steps capped at 1 %; once both ends are known the next state is inside them.
TEST(PressureBracket, StaysInsideTheBracketAndAboveHalfTheDensity) {
  PressureBracket b(kHertz, kTarget);
  const double far_above = b.next(0.5, 1e12, 1.0);  // Newton would go to φ ≪ 0
  EXPECT_DOUBLE_EQ(far_above, 0.25);
  PressureBracket u(kHertz, kTarget);
  double phi = 0.3, step = 0;
  for (int k = 0; k < 12; ++k) {
    const double next = u.next(phi, 0.0, 0.0);
    step = next / phi - 1;
    phi = next;
  }
  EXPECT_NEAR(step, 0.01, 1e-15);  // 1e-4 doubled: 2e-4, 4e-4, ..., capped at 1e-2
  PressureBracket br(kHertz, kTarget);
  br.next(0.60, 5e4, 1e6);                      // below
  const double inside = br.next(0.62, 2e5, 1e9);  // above: a Newton step of ~1e-6 stays put
  EXPECT_GT(inside, 0.60);
  EXPECT_LT(inside, 0.62);
  // An unloading state above the lower end: the secant through it is refused and the next
  // state is still inside (0.60, 0.62).
  const double again = br.next(0.61, 1e4, 1e6);
  EXPECT_GT(again, 0.61);
  EXPECT_LT(again, 0.62);
  EXPECT_FALSE(br.collapsed(0.61));
}
