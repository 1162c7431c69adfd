// Benchmark (label bench; issue 7: 10^6 particles carved by a 512³ level set in under 10 s on two
// cores). Setup (not timed against the target): random spherical macropores (radius 8–24 voxels,
// ~20 % of the volume) in a 512³ mask written as tomodem-segment's OpenVDB level set; an FCC lattice
// of 1 000 188 touching spheres. Timed: reading the level set, and the carve (target integration,
// centre rule, contact graph before and after). Prints stage times, CPU time, load average and
// peak memory. TOMODEM_BENCH_N overrides the edge (e.g. 128 for a quick run), TOMODEM_BENCH_RULE=fraction
// uses the volume-fraction rule.
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>

#include "tomodem/carve/carve.hpp"
#include "tomodem/dem/scene.hpp"
#include "tomodem/image/outputs.hpp"

using namespace tomodem;
using namespace tomodem::carve;

namespace {
double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }
double cpu_s() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}
double peak_mib() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) / 1024.0;
}
std::string loadavg() {
  std::ifstream in("/proc/loadavg");
  std::string s;
  std::getline(in, s);
  return s;
}
}  // namespace

TEST(BenchCarve, MillionParticlesLevelSet512) {
  const char* e = std::getenv("TOMODEM_BENCH_N");
  const std::size_t n = e ? std::size_t(std::atol(e)) : 512;
  const char* rule = std::getenv("TOMODEM_BENCH_RULE");
  const double voxel = 1e-5;
  const std::string path = (std::filesystem::temp_directory_path() / "tomodem_bench_carve.vdb").string();
  double t = now();
  {
    image::Mask m(image::Dims{n, n, n}, 0);
    m.spacing = {voxel, voxel, voxel};
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> U(0, 1);
    const double f = double(n) / 512;
    std::size_t filled = 0;
    while (double(filled) < 0.2 * double(m.v.size())) {
      const double R = (8 + 16 * U(rng)) * f, cx = U(rng) * double(n), cy = U(rng) * double(n), cz = U(rng) * double(n);
      for (long z = std::max(0L, long(cz - R)); z <= std::min(long(n) - 1, long(cz + R)); ++z)
        for (long y = std::max(0L, long(cy - R)); y <= std::min(long(n) - 1, long(cy + R)); ++y)
          for (long x = std::max(0L, long(cx - R)); x <= std::min(long(n) - 1, long(cx + R)); ++x) {
            const double dx = double(x) - cx, dy = double(y) - cy, dz = double(z) - cz;
            auto& v = m.at(std::size_t(x), std::size_t(y), std::size_t(z));
            if (!v && dx * dx + dy * dy + dz * dz <= R * R) v = 1, ++filled;
          }
    }
    image::write_level_set(path, m);
  }
  std::cout << "setup: " << n << "^3 level set written in " << now() - t << " s" << std::endl;
  // 63³ FCC cells × 4 = 1 000 188 spheres, radius 0.999 of touching.
  const int cells = 63;
  const double a = 1.0;
  Packing p;
  p.particles.position = dem::lattice_sites(dem::LatticeKind::fcc, cells, a);
  p.particles.radius.assign(p.particles.position.size(), 0.999 * a / (2 * std::sqrt(2.0)));
  p.particles.phase.assign(p.particles.position.size(), 0);
  p.cell = Cell::box({0, 0, 0}, {cells * a, cells * a, cells * a}, true);
  Options o;
  o.mapping.fit = true;
  o.threads = 2;
  if (rule && std::string(rule) == "fraction") o.rule = Rule::fraction;
  const double c0 = cpu_s();
  t = now();
  const auto ls = load_level_set(path);
  const double t_read = now() - t;
  const Result r = tomodem::carve::carve(p, *ls, o);
  const double total = now() - t;
  const auto& rp = r.report;
  std::cout << "particles " << p.particles.size() << ", removed " << rp.n_removed << ", cut " << rp.n_cut << "\n"
            << "macroporosity target " << rp.macroporosity_target << ", achieved " << rp.macroporosity_achieved << "\n"
            << "read level set " << t_read << " s; integration (" << rp.target_grid << "^3) " << rp.time_target_s
            << " s; classify (" << (rule ? rule : "centre") << ") " << rp.time_classify_s << " s; connectivity (x2) "
            << rp.time_connectivity_s << " s; carve " << rp.wall_time_s << " s\n"
            << "TOTAL " << total << " s wall, " << cpu_s() - c0 << " s CPU, threads 2, peak RSS " << peak_mib()
            << " MiB, loadavg " << loadavg() << std::endl;
  std::filesystem::remove(path);
  EXPECT_GT(rp.n_removed, 0u);
  EXPECT_NEAR(rp.macroporosity_achieved, rp.macroporosity_target, 0.01);
}
