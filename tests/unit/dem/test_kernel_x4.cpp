// The four-contact-wide frictionless Hertz loop (kernel_simd_body.inc, pair_kernel_hertz_x4)
// against the scalar loop of kernel.hpp over the laws of laws.hpp, with and without tallies
// (issue 19: a deforming cell tallies every step, so the tally pass runs four-wide too).
#include <gtest/gtest.h>

#include <cmath>

#include "random_pairs.hpp"

using namespace tomodem;
using namespace tomodem::dem;
using namespace tomodem::dem::testing;

namespace {

double max_norm(const std::vector<Vec3>& a) {
  double s = 0;
  for (const Vec3& q : a) s = std::max(s, norm(q));
  return s;
}
double max_diff(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  double s = 0;
  for (std::size_t q = 0; q < a.size(); ++q) s = std::max(s, norm(a[q] - b[q]));
  return s;
}

}  // namespace

// Each contact is the same arithmetic in another instruction order (R* and m* from one division):
// a few ulp, so 1e-13 of the largest value. The tally's sums run over 400-odd contacts in
// another order: 1e-12 relative.
TEST(KernelX4, FrictionlessHertzEqualsScalarLawsWithAndWithoutTally) {
  RandomPairs s(7, TangentialLaw::none, false, false);
  const std::size_t np = std::size_t(s.n());
  using Scalar = law::NormalHertz;
  for (bool tally : {false, true}) {
    std::vector<Vec3> f0(np), f1(np), pf0(RandomPairs::kPairs), pf1(RandomPairs::kPairs);
    std::vector<double> st0(np), st1(np);
    Tally t0, t1;
    ForceJob j0 = s.job(tally ? pf0.data() : nullptr), j1 = s.job(tally ? pf1.data() : nullptr);
    if (tally) {
      detail::pair_kernel<Scalar, law::TangentialNone, law::RollingNone, true>(j0, 0, s.n(), f0.data(), nullptr, &t0, st0.data());
      detail::pair_kernel_hertz_x4<true>(j1, 0, s.n(), f1.data(), nullptr, &t1, st1.data());
    } else {
      detail::pair_kernel<Scalar, law::TangentialNone, law::RollingNone, false>(j0, 0, s.n(), f0.data(), nullptr, nullptr, nullptr);
      detail::pair_kernel_hertz_x4<false>(j1, 0, s.n(), f1.data(), nullptr, nullptr, nullptr);
    }
    const double fmax = max_norm(f0);
    ASSERT_GT(fmax, 0);
    EXPECT_LT(max_diff(f0, f1), 1e-13 * fmax) << "tally " << tally;
    if (!tally) continue;
    std::printf("measured: %ld contacts, virial trace %.6e / %.6e, elastic %.6e / %.6e J\n", t0.contacts,
                t0.virial.trace(), t1.virial.trace(), t0.elastic, t1.elastic);
    EXPECT_GT(t0.contacts, 200);  // both block paths hold contacts
    EXPECT_EQ(t1.contacts, t0.contacts);
    EXPECT_LT(max_diff(pf0, pf1), 1e-13 * max_norm(pf0));
    double vmax = 0, dv = 0, smax = 0, ds = 0;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) vmax = std::max(vmax, std::abs(t0.virial(a, b))), dv = std::max(dv, std::abs(t1.virial(a, b) - t0.virial(a, b)));
    for (std::size_t q = 0; q < np; ++q) smax = std::max(smax, st0[q]), ds = std::max(ds, std::abs(st1[q] - st0[q]));
    EXPECT_LT(dv, 1e-12 * vmax);
    EXPECT_LT(ds, 1e-13 * smax);
    EXPECT_NEAR(t1.elastic, t0.elastic, 1e-12 * t0.elastic);
    EXPECT_NEAR(t1.dissipated, t0.dissipated, 1e-12 * t0.dissipated);
    EXPECT_NEAR(t1.sum_contact_force, t0.sum_contact_force, 1e-12 * t0.sum_contact_force);
    EXPECT_NEAR(t1.max_overlap_ratio, t0.max_overlap_ratio, 1e-13 * t0.max_overlap_ratio);
    EXPECT_GT(t0.dissipated, 0);
    // An independent check of the virial: Σ F_j ⊗ l has the trace Σ F_j · l (pair k joins
    // particles 2k and 2k + 1).
    double trace = 0;
    for (std::size_t k = 0; k < std::size_t(RandomPairs::kPairs); ++k) trace += dot(pf0[k], s.x[2 * k + 1] + s.shift[s.img[k]] - s.x[2 * k]);
    EXPECT_NEAR(t1.virial.trace(), trace, 1e-12 * std::abs(trace));
  }
}

namespace {

/// Whether the upper halves of ymm0-15 hold data right after a call of `kernel` (XINUSE bit 2,
/// read with xgetbv, ecx = 1); -1 where the processor cannot tell.
__attribute__((noinline)) int upper_halves_dirty_after(PairKernel kernel, const ForceJob& job, int n, Vec3* f, Vec3* t) {
#if defined(__x86_64__)
  if (!__builtin_cpu_supports("avx")) return -1;
  unsigned eax, ebx, ecx, edx;
  __asm__("cpuid" : "=a"(eax), "=b"(ebx), "=c"(ecx), "=d"(edx) : "a"(0xd), "c"(1));
  if (!(eax & 4)) return -1;  // no xgetbv with ecx = 1
  kernel(job, 0, n, f, t, nullptr, nullptr);
  unsigned lo, hi;
  __asm__ volatile("xgetbv" : "=a"(lo), "=d"(hi) : "c"(1));
  return (lo & 4) != 0;
#else
  (void)kernel, (void)job, (void)n, (void)f, (void)t;
  return -1;
#endif
}

}  // namespace

// A vector loop must return with the upper halves of the vector registers clean: the code after
// it in a generic build is baseline SSE, which on this project's machines ran 2-3× slower with
// them dirty (the gas scene's integrator; GCC emits no vzeroupper on return from a function with
// vector arguments yet assumes every call returns clean). The random pairs take both block paths
// and the out-of-line quads of picked contacts, where the dirty return was.
TEST(KernelX4, VectorLoopsReturnWithCleanUpperHalves) {
  for (TangentialLaw law : {TangentialLaw::mindlin, TangentialLaw::none}) {
    RandomPairs s(5, law, true, true, 0.3, 0.6);
    const KernelSet k = select_kernels(s.m);
    ASSERT_TRUE(k.vectorised);
    std::vector<Vec3> f(std::size_t(s.n())), t(std::size_t(s.n()));
    const int dirty = upper_halves_dirty_after(k.pair[0], s.job(nullptr, s.hist.data()), s.n(), f.data(), t.data());
    if (dirty < 0) GTEST_SKIP() << "the processor does not report which register state is in use";
    EXPECT_EQ(dirty, 0) << (law == TangentialLaw::none ? "frictionless Hertz" : "Hertz-Mindlin");
  }
}
