// segment_gen_raw N FILE [SEED [grains]]: an N^3 little-endian uint16 volume for the out-of-core
// benchmark, written slab by slab (32 planes in memory), so a 2048^3 volume (16 GiB) needs
// about 0.5 GB. The recipe of bench_segment.cpp: N^3/20000 spheres of pores (grey 10000,
// radius 3-11 voxels, centres uniform) in solid (30000), near-Gaussian noise of sigma 20000/3
// (SNR 3; Irwin-Hall, see normal()), rounded and clamped to 0..65535. The noise of voxel i is a hash of (seed, i), so the
// file does not depend on the slab size. Written to FILE.part, then renamed.
// "grains": N^3/4000 solid spheres (grains, radius 6-10 voxels, overlapping where they fall so)
// in pore space instead, for --grains (about 41 % solid).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

namespace {
uint64_t splitmix(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}
// A near-normal deviate from a hash: the sum of four 16-bit uniforms (Irwin-Hall, mean 2,
// variance 1/3) scaled to unit variance; 10x cheaper than Box-Muller, tails cut at 3.46 sigma.
double normal(uint64_t seed, uint64_t i) {
  const uint64_t h = splitmix(seed * 0x100000001B3ull ^ i);
  const double s = double(h & 0xffff) + double((h >> 16) & 0xffff) + double((h >> 32) & 0xffff) + double(h >> 48);
  return (s / 65536.0 - 2.0) * 1.7320508075688772;
}
struct Sphere { double x, y, z, r; };
}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: segment_gen_raw N FILE [SEED [grains]]\n");
    return 2;
  }
  const long n = std::atol(argv[1]);
  const std::string path = argv[2];
  const uint64_t seed = argc > 3 ? std::strtoull(argv[3], nullptr, 10) : 1;
  const bool grains = argc > 4 && std::string(argv[4]) == "grains";
  if (n < 8 || n > 8192) {
    std::fprintf(stderr, "segment_gen_raw: N = %s: expected 8..8192\n", argv[1]);
    return 2;
  }
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0, double(n));
  std::vector<Sphere> s(std::size_t(double(n) * double(n) * double(n) / (grains ? 4000 : 20000)));
  for (auto& p : s) p = grains ? Sphere{U(rng), U(rng), U(rng), 6 + std::fmod(U(rng), 4.0)} : Sphere{U(rng), U(rng), U(rng), 3 + std::fmod(U(rng), 8.0)};
  std::sort(s.begin(), s.end(), [](const Sphere& a, const Sphere& b) { return a.z - a.r < b.z - b.r; });
  const long slab = 32, P = n * n;
  std::vector<uint8_t> pore(std::size_t(slab * P));
  std::vector<uint16_t> out(std::size_t(slab * P));
  const std::string part = path + ".part";
  std::FILE* f = std::fopen(part.c_str(), "wb");
  if (!f) {
    std::perror(part.c_str());
    return 1;
  }
  std::size_t first = 0;  // spheres sorted by their lowest z: skip those entirely below the slab
  for (long z0 = 0; z0 < n; z0 += slab) {
    const long z1 = std::min(n, z0 + slab);
    std::fill(pore.begin(), pore.end(), 0);
    for (std::size_t k = first; k < s.size() && s[k].z - s[k].r < double(z1); ++k) {
      const auto& p = s[k];
      if (p.z + p.r < double(z0)) continue;
      for (long z = std::max(z0, long(p.z - p.r)); z <= std::min(z1 - 1, long(p.z + p.r)); ++z)
        for (long y = std::max(0L, long(p.y - p.r)); y <= std::min(n - 1, long(p.y + p.r)); ++y)
          for (long x = std::max(0L, long(p.x - p.r)); x <= std::min(n - 1, long(p.x + p.r)); ++x)
            if ((x - p.x) * (x - p.x) + (y - p.y) * (y - p.y) + (z - p.z) * (z - p.z) <= p.r * p.r)
              pore[std::size_t((z - z0) * P + y * n + x)] = 1;
    }
    const long m = (z1 - z0) * P;
#pragma omp parallel for schedule(static)
    for (long i = 0; i < m; ++i) {
      const double v = ((pore[std::size_t(i)] != 0) != grains ? 10000.0 : 30000.0) + normal(seed, uint64_t(z0 * P + i)) * 20000.0 / 3;
      out[std::size_t(i)] = uint16_t(std::lround(std::clamp(v, 0.0, 65535.0)));
    }
    if (std::fwrite(out.data(), 2, std::size_t(m), f) != std::size_t(m)) {
      std::perror(part.c_str());
      std::fclose(f);
      std::remove(part.c_str());
      return 1;
    }
  }
  if (std::fclose(f) != 0 || std::rename(part.c_str(), path.c_str()) != 0) {
    std::perror(path.c_str());
    std::remove(part.c_str());
    return 1;
  }
  return 0;
}
