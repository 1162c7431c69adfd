// Benchmark (label bench, reported not asserted): 512^3 16-bit volume, median 3x3x3 + Otsu +
// connected components of the pores, on the threads available (OMP_NUM_THREADS). Prints the
// time of each stage, the CPU time, the load average and the peak resident memory.
// In the same run: the previous median (std::nth_element over the 27 values) on a slab of 32
// planes against the selection network on the same slab (the before/after ratio), and the
// macropore stage (two exact distance transforms + labelling) that tomodem-segment runs next.
// TOMODEM_BENCH_N overrides the edge (e.g. 1024); TOMODEM_BENCH_RAW=FILE also writes the
// generated volume as little-endian uint16 (input for /usr/bin/time -v tomodem-segment).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <omp.h>
#include <sys/resource.h>

#include "tomodem/image/phantom.hpp"
#include "tomodem/image/segment.hpp"

using namespace tomodem::image;

namespace {
double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }
double peak_mib() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) / 1024.0;
}
double cpu_s() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}
double load1() {
  double l = -1;
  std::ifstream("/proc/loadavg") >> l;
  return l;
}
}  // namespace

TEST(BenchSegment, MedianOtsuLabelling512) {
  const char* e = std::getenv("TOMODEM_BENCH_N");
  const std::size_t n = e ? std::size_t(std::atol(e)) : 512;
  // Input: 16-bit values (pores 10000, solid 30000, SNR 3), generated here without the
  // phantom geometry cost: random spheres of pores stamped into a solid block.
  Volume v(Dims{n, n, n}, 30000.0f);
  const double t_gen = now();
  {
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> U(0, double(n));
    for (int k = 0; k < int(n * n * n / 20000); ++k) {
      const double cx = U(rng), cy = U(rng), cz = U(rng), r = 3 + std::fmod(U(rng), 8.0);
      for (long z = long(cz - r); z <= long(cz + r); ++z)
        for (long y = long(cy - r); y <= long(cy + r); ++y)
          for (long x = long(cx - r); x <= long(cx + r); ++x)
            if (x >= 0 && y >= 0 && z >= 0 && x < long(n) && y < long(n) && z < long(n) &&
                (x - cx) * (x - cx) + (y - cy) * (y - cy) + (z - cz) * (z - cz) <= r * r)
              v.at(std::size_t(x), std::size_t(y), std::size_t(z)) = 10000.0f;
    }
#pragma omp parallel
    {
      std::mt19937_64 r2(17 + omp_get_thread_num());
      std::normal_distribution<float> G(0, 20000.0f / 3);
#pragma omp for
      for (std::size_t i = 0; i < v.v.size(); ++i) v.v[i] = std::round(std::clamp(v.v[i] + G(r2), 0.0f, 65535.0f));
    }
  }
  if (const char* raw = std::getenv("TOMODEM_BENCH_RAW")) write_volume(raw, v, true);
  // Before/after on the same slab of 32 planes: nth_element (the previous code) and the network.
  double t_generic = 0, t_network = 0;
  {
    Volume slab(Dims{n, n, std::min<std::size_t>(32, n)});
    std::copy_n(v.v.begin(), slab.v.size(), slab.v.begin());
    Volume a = slab, b = slab;
    const double s0 = cpu_s();
    median_inplace(a, 1, true);
    const double s1 = cpu_s();
    median_inplace(b, 1);
    t_generic = s1 - s0;
    t_network = cpu_s() - s1;
    EXPECT_EQ(a.v, b.v);  // the same median, exactly
  }
  // Wall and CPU (all threads) time of each stage: on a loaded machine the CPU time is the
  // figure that carries over (on two free cores the wall time is at most the CPU time).
  const double t0 = now(), c0 = cpu_s();
  median_inplace(v, 1);
  const double t1 = now(), c1 = cpu_s();
  const double t = otsu_threshold(v);
  const Mask pores = threshold(v, t, true);
  const double t2 = now(), c2 = cpu_s();
  int count = 0;
  const Labels L = components(pores, 6, &count);
  const double t3 = now(), c3 = cpu_s(), rss3 = peak_mib();
  std::cout << "bench_segment n=" << n << " threads=" << omp_get_max_threads() << " generate " << (t0 - t_gen)
            << " s; wall (CPU) s: median " << (t1 - t0) << " (" << (c1 - c0) << "), otsu+threshold " << (t2 - t1) << " ("
            << (c2 - c1) << "), labelling " << (t3 - t2) << " (" << (c3 - c2) << "), total " << (t3 - t0) << " (" << (c3 - c0)
            << "); load average " << load1() << ", pores " << count << ", peak RSS " << rss3 << " MiB\n";
  std::cout << "bench_segment median on " << n << "x" << n << "x" << std::min<std::size_t>(32, n)
            << ": CPU nth_element " << t_generic << " s, network " << t_network << " s, speed-up " << t_generic / t_network << "\n";
  // The next stage of tomodem-segment: macropores (ball radius 3 voxels).
  const double t4 = now(), c4 = cpu_s();
  int n_macro = 0;
  const Labels M = macropores(pores, 3.0, 1, &n_macro);
  const double t5 = now(), c5 = cpu_s();
  std::cout << "bench_segment macropores r=3: " << (t5 - t4) << " s (CPU " << (c5 - c4) << " s, " << n_macro
            << " macropores), load average "
            << load1() << ", peak RSS " << peak_mib() << " MiB\n";
  EXPECT_GT(count, 0);
}
