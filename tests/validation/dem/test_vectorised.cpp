// The four-contact-wide Hertz–Mindlin loop (kernel_simd.hpp) against the scalar loop of the
// same laws (laws.hpp): the same physics through two code paths.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "scenes.hpp"

using namespace tomodem;
using namespace tomodem::dem;
using namespace tomodem::dem::testing;

namespace {
// 343 polydisperse spheres (R ± 20 %) on a jittered lattice, overlapping by ~2 % of R on
// average, random velocities and spins, in a triply periodic cell: many contacts across the
// faces, sticking and slipping ones (μ = 0.3), pairs entering and leaving contact.
Simulation packing(bool scalar) {
  const double R = 0.5e-3, rho = 2500;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  Particles p;
  const int n = 7;
  const double a = 1.9 * R;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        const std::size_t q = p.add({a * (i + 0.5 + 0.05 * u(rng)), a * (j + 0.5 + 0.05 * u(rng)),
                                     a * (k + 0.5 + 0.05 * u(rng))},
                                    R * (1 + 0.2 * u(rng)) * 0.97, rho, 0);
        p.v[q] = {0.05 * u(rng), 0.05 * u(rng), 0.05 * u(rng)};
      }
  p.enable_rotation();
  for (auto& w : p.omega) w = {100 * u(rng), 100 * u(rng), 100 * u(rng)};
  const ContactModel m = model(NormalLaw::hertz, TangentialLaw::mindlin, material(1e8, 0.25, rho), 0.5, 0.3);
  Settings s;
  s.scalar_kernels = scalar;
  Simulation sim(std::move(p), Cell::box({0, 0, 0}, {n * a, n * a, n * a}, true), m, s);
  sim.set_time_step(0.1 * sim.critical_time_step());
  return sim;
}
}  // namespace

// One step: every force and torque agrees to round-off (the per-contact arithmetic is the same;
// only the order of the sums over contacts differs): 1e-12 of the largest force.
// 400 steps: chaotic growth of round-off in a dense packing stays far below 1e-9 R.
TEST(VectorisedLoop, HertzMindlinMatchesScalarLoop) {
  Simulation vec = packing(false), ref = packing(true);
  EXPECT_NE(vec.describe().find("vectorised"), std::string::npos) << vec.describe();
  EXPECT_EQ(ref.describe().find("vectorised"), std::string::npos) << ref.describe();
  vec.step();
  ref.step();
  const auto &pv = vec.particles(), &pr = ref.particles();
  double fmax = 0, tmax = 0;
  for (std::size_t i = 0; i < pr.size(); ++i) fmax = std::max(fmax, norm(pr.f[i])), tmax = std::max(tmax, norm(pr.torque[i]));
  ASSERT_GT(fmax, 0);
  double df = 0, dtq = 0;
  for (std::size_t i = 0; i < pr.size(); ++i) {
    df = std::max(df, norm(pv.f[i] - pr.f[i]));
    dtq = std::max(dtq, norm(pv.torque[i] - pr.torque[i]));
  }
  std::printf("measured: force difference %.2e, torque difference %.2e (relative to the largest)\n", df / fmax,
              dtq / tmax);
  EXPECT_LT(df / fmax, 1e-12);
  EXPECT_LT(dtq / tmax, 1e-12);
  const Measurements mv = vec.measure(), mr = ref.measure();
  EXPECT_GT(mr.contacts, 500);  // the scene really exercises contacts
  vec.run(400);
  ref.run(400);
  double dx = 0;
  for (std::size_t i = 0; i < pr.size(); ++i) dx = std::max(dx, norm(pv.x[i] - pr.x[i]) / pr.r[i]);
  std::printf("measured: position difference after 400 steps %.2e R\n", dx);
  EXPECT_LT(dx, 1e-9);
  (void)mv;
}
