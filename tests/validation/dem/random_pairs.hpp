#pragma once
// Random isolated pairs for the four-contact-wide loops against the scalar ones
// (tests/unit/dem/test_kernel_x4.cpp, test_law_registry.cpp): no sum over contacts reorders
// anything, so each contact's result can be compared on its own.
#include <cmath>
#include <random>
#include <vector>

#include "kernel_simd.hpp"
#include "scenes.hpp"

namespace tomodem::dem::testing {

/// 517 pairs (the last group of four has spare lanes) of two phases: the first 256 mostly
/// touching, the rest mostly apart (both block paths of the loop). With `spin`, random angular
/// velocities; with `springs`, stored tangential springs (3 per contact, half of them zero, some
/// beyond the Coulomb cone). A third of the pairs meet across a periodic image (j stored one
/// image shift away, as a neighbour list stores a pair across the cell's faces).
struct RandomPairs {
  static constexpr int kPairs = 517;
  ContactModel m;
  std::vector<Vec3> x, v, w;
  std::vector<double> r, mass, hist;
  std::vector<int32_t> phase, start, owner, jj;
  std::vector<uint8_t> img;
  Vec3 shift[27] = {}, vshift[27] = {};
  std::vector<PackedSphere> sphere;  // ForceJob::sphere and shift4, filled by job()
  PackedSphere shift4[27] = {};

  /// mu_same, mu_cross: the friction of equal and unequal phases.
  RandomPairs(uint64_t seed, TangentialLaw tangential, bool spin, bool springs, double mu_same = 0, double mu_cross = 0) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(-1, 1), u01(0, 1);
    m.normal = NormalLaw::hertz;
    m.tangential = tangential;
    m.materials = {material(1e8, 0.25, 2500), material(3e8, 0.3, 7800)};
    m.finalize();
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 2; ++b) {
        m.pair(a, b).restitution = a == b ? 0.5 : 0.3;
        m.pair(a, b).friction = a == b ? mu_same : mu_cross;
      }
    m.finalize();
    const std::size_t np = 2 * std::size_t(kPairs);
    for (int c = 0; c < 27; ++c) {  // a cubic cell of edge 60 m holds every pair
      const Vec3 n{double(c / 9 - 1), double(c / 3 % 3 - 1), double(c % 3 - 1)};
      shift[c] = 60.0 * n;
      vshift[c] = 0.05 * n;
    }
    x.resize(np), v.resize(np), r.resize(np), mass.resize(np), phase.resize(np), start.resize(np + 1);
    if (spin) w.resize(np);
    for (int k = 0; k < kPairs; ++k) {
      const std::size_t i = 2 * std::size_t(k), j = i + 1;
      r[i] = 1e-3 * (1 + 0.3 * u(rng));
      r[j] = 1e-3 * (1 + 0.3 * u(rng));
      for (std::size_t q : {i, j}) {
        phase[q] = u01(rng) < 0.5 ? 0 : 1;
        mass[q] = (phase[q] ? 7800 : 2500) * 4.0 / 3.0 * M_PI * r[q] * r[q] * r[q];
        v[q] = {0.1 * u(rng), 0.1 * u(rng), 0.1 * u(rng)};
        if (spin) w[q] = {100 * u(rng), 100 * u(rng), 100 * u(rng)};
      }
      const bool touching = u01(rng) < (k < 256 ? 0.8 : 0.3);
      const double overlap = touching ? 0.02 * std::min(r[i], r[j]) * u01(rng) : -0.01 * r[i] * u01(rng);
      Vec3 dir{u(rng), u(rng), u(rng)};
      dir = (1 / norm(dir)) * dir;
      x[i] = {0.1 * k, 0, 0};
      x[j] = x[i] + (r[i] + r[j] - overlap) * dir;
      const int image = k % 3 == 2 ? int(u01(rng) * 26.999) : 13;  // 13: the centre image
      x[j] = x[j] - shift[image];
      v[j] = v[j] - vshift[image];
      start[i] = k, start[j] = k + 1;
      owner.push_back(int32_t(i));
      jj.push_back(int32_t(j));
      img.push_back(uint8_t(image));
    }
    start[np] = kPairs;
    if (springs) {
      hist.resize(3 * std::size_t(kPairs));
      for (double& h : hist) h = u01(rng) < 0.5 ? 1e-3 * u(rng) : 0;
    }
  }
  /// A job over all pairs; `h`: the history array (3 per contact) or nullptr.
  ForceJob job(Vec3* pair_force = nullptr, double* h = nullptr) {
    ForceJob jb{x.data(), v.data(), w.empty() ? nullptr : w.data(), r.data(), mass.data(), phase.data(),
                start.data(), owner.data(), jj.data(), img.data(), h, nullptr, h ? 3 : 0, shift, vshift,
                m.pairs.data(), 2, 1e-6};
    jb.pair_force = pair_force;
    sphere.resize(x.size());
    for (std::size_t q = 0; q < x.size(); ++q) sphere[q] = PackedSphere{x[q].x, x[q].y, x[q].z, r[q]};
    for (int c = 0; c < 27; ++c) shift4[c] = PackedSphere{shift[c].x, shift[c].y, shift[c].z, 0};
    jb.sphere = sphere.data();
    jb.shift4 = shift4;
    return jb;
  }
  int n() const { return int(x.size()); }
};

}  // namespace tomodem::dem::testing
