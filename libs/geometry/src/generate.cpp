// Random insertion of spheres and rigid clusters into a periodic cell (largest first, one bin
// grid per size level so wide distributions stay O(N)).
#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include "tomodem/core/error.hpp"
#include "tomodem/geometry/pack.hpp"
#include "tomodem/spatial/grid.hpp"

namespace tomodem::geometry {

std::vector<Vec3> insert_random(const std::vector<double>& radius, const std::vector<std::vector<int>>& clusters,
                                const std::vector<Vec3>& offsets, const Cell& cell, uint64_t seed) {
  const std::size_t n = radius.size();
  std::vector<Vec3> x(n);
  if (n == 0) return x;
  const double rmin = *std::min_element(radius.begin(), radius.end());
  const double rmax = *std::max_element(radius.begin(), radius.end());
  // Levels of radius (rmin 2^l, rmin 2^(l+1)], each with a bin grid of side >= 2 r_max(level).
  // (spatial's levels; the bins here are filled one insertion at a time, as linked lists.)
  const int L = spatial::level_count(rmin, rmax);
  const auto level_of = [&](double r) { return spatial::level_of(r, rmin, L); };
  const Mat3 hinv = cell.h.inverse();
  double width[3];
  for (int k = 0; k < 3; ++k) width[k] = cell.volume() / norm(cross(cell.h.col((k + 1) % 3), cell.h.col((k + 2) % 3)));
  struct Level {
    double rmax = 0;
    int nb[3] = {1, 1, 1};
    std::vector<int32_t> head;
  };
  std::vector<Level> lev(static_cast<std::size_t>(L));
  for (double r : radius) lev[std::size_t(level_of(r))].rmax = std::max(lev[std::size_t(level_of(r))].rmax, r);
  for (auto& lv : lev) {
    if (lv.rmax == 0) continue;
    for (int k = 0; k < 3; ++k) lv.nb[k] = std::clamp(int(width[k] / (2 * lv.rmax)), 1, 256);
    lv.head.assign(std::size_t(lv.nb[0]) * lv.nb[1] * lv.nb[2], -1);
  }
  std::vector<int32_t> next(n, -1);
  std::vector<int> level(n);
  for (std::size_t i = 0; i < n; ++i) level[i] = level_of(radius[i]);
  const auto frac = [&](const Vec3& p) {
    Vec3 s = hinv * (p - cell.origin);
    for (int k = 0; k < 3; ++k) s[k] -= std::floor(s[k]);
    return s;
  };
  const auto fits = [&](const Vec3& p, double r) {
    const Vec3 s = frac(p);
    for (const auto& lv : lev) {
      if (lv.head.empty()) continue;
      const double e = r + lv.rmax;
      int lo[3], hi[3];
      for (int k = 0; k < 3; ++k) {
        lo[k] = int(std::floor((s[k] - e / width[k]) * lv.nb[k]));
        hi[k] = int(std::floor((s[k] + e / width[k]) * lv.nb[k]));
        if (hi[k] - lo[k] >= lv.nb[k]) lo[k] = 0, hi[k] = lv.nb[k] - 1;  // covers the whole period
      }
      for (int a = lo[0]; a <= hi[0]; ++a)
        for (int b = lo[1]; b <= hi[1]; ++b)
          for (int c = lo[2]; c <= hi[2]; ++c) {
            const int ia = (a % lv.nb[0] + lv.nb[0]) % lv.nb[0], ib = (b % lv.nb[1] + lv.nb[1]) % lv.nb[1],
                      ic = (c % lv.nb[2] + lv.nb[2]) % lv.nb[2];
            for (int32_t j = lv.head[(std::size_t(ia) * lv.nb[1] + ib) * lv.nb[2] + ic]; j >= 0; j = next[std::size_t(j)]) {
              Vec3 ds = hinv * (x[std::size_t(j)] - p);
              for (int k = 0; k < 3; ++k) ds[k] -= std::round(ds[k]);  // minimum image (all directions periodic)
              const Vec3 d = cell.h * ds;
              const double rc = r + radius[std::size_t(j)];
              if (dot(d, d) < rc * rc) return false;
            }
          }
    }
    return true;
  };
  const auto place = [&](std::size_t i, const Vec3& p) {
    const Vec3 s = frac(p);
    x[i] = cell.origin + cell.h * s;
    auto& lv = lev[std::size_t(level[i])];
    int c[3];
    for (int k = 0; k < 3; ++k) c[k] = std::min(int(s[k] * lv.nb[k]), lv.nb[k] - 1);
    auto& h = lv.head[(std::size_t(c[0]) * lv.nb[1] + c[1]) * lv.nb[2] + c[2]];
    next[i] = h;
    h = int32_t(i);
  };

  // Units: clusters (rigid) and the single particles not in a cluster, largest first.
  std::vector<std::vector<int>> units = clusters;
  std::vector<uint8_t> in_cluster(n, 0);
  for (const auto& c : clusters)
    for (int i : c) in_cluster[std::size_t(i)] = 1;
  for (std::size_t i = 0; i < n; ++i)
    if (!in_cluster[i]) units.push_back({int(i)});
  std::vector<double> bound(units.size());
  for (std::size_t u = 0; u < units.size(); ++u)
    for (int i : units[u]) bound[u] = std::max(bound[u], norm(offsets.empty() ? Vec3{} : offsets[std::size_t(i)]) + radius[std::size_t(i)]);
  std::vector<std::size_t> order(units.size());
  for (std::size_t u = 0; u < order.size(); ++u) order[u] = u;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return bound[a] > bound[b]; });

  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0, 1);
  std::normal_distribution<double> G(0, 1);
  for (std::size_t u : order) {
    bool ok = false;
    for (int attempt = 0; attempt < 20000 && !ok; ++attempt) {
      const Vec3 c = cell.origin + cell.h * Vec3{U(rng), U(rng), U(rng)};
      // Random rotation (uniform quaternion) for clusters.
      double q[4] = {G(rng), G(rng), G(rng), G(rng)};
      const double qn = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
      for (double& v : q) v /= qn;
      const auto rot = [&](const Vec3& v) {
        const Vec3 qv{q[1], q[2], q[3]};
        const Vec3 t = 2 * cross(qv, v);
        return v + q[0] * t + cross(qv, t);
      };
      ok = true;
      for (int i : units[u])
        if (!fits(c + (offsets.empty() ? Vec3{} : rot(offsets[std::size_t(i)])), radius[std::size_t(i)])) {
          ok = false;
          break;
        }
      if (ok)
        for (int i : units[u]) place(std::size_t(i), c + (offsets.empty() ? Vec3{} : rot(offsets[std::size_t(i)])));
    }
    if (!ok)
      throw InputError("", "initial_solid_fraction", "",
                       "random insertion found no free place for a particle after 20000 tries; lower initial_solid_fraction");
  }
  return x;
}

}  // namespace tomodem::geometry
