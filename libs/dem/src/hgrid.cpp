#include "hgrid.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>

namespace tomodem::dem {

namespace {
NeighborSearch g_search = [] {
  const char* e = std::getenv("TOMODEM_NEIGHBOR_SEARCH");
  if (e && std::strcmp(e, "hgrid") == 0) return NeighborSearch::hgrid;
  if (e && std::strcmp(e, "cells") == 0) return NeighborSearch::linked_cells;
  return NeighborSearch::automatic;
}();

constexpr int kCentre = 13;

/// Level of a radius: level l holds radii in (rmin 2^l, rmin 2^(l+1)]; level 0 starts at rmin.
/// A cell-size ratio of 2 between levels is the optimum Ogarko & Luding report for wide
/// distributions (their Fig. 6: cost flat between ratios 1.5 and 3).
int level_of(double r, double rmin, int levels) {
  int l = 0;
  double up = 2 * rmin;
  while (l < levels - 1 && r > up) ++l, up *= 2;
  return l;
}

int level_count(double rmin, double rmax) {
  int L = 1;
  double up = 2 * rmin;
  while (rmax > up) ++L, up *= 2;
  return L;
}

struct Triple {
  int32_t owner, partner;
  uint8_t code;
};
}  // namespace

void set_neighbor_search(NeighborSearch s) { g_search = s; }
NeighborSearch neighbor_search() { return g_search; }

bool use_hgrid(const std::vector<double>& r) {
  if (g_search != NeighborSearch::automatic) return g_search == NeighborSearch::hgrid;
  if (r.empty()) return false;
  const auto [mn, mx] = std::minmax_element(r.begin(), r.end());
  return *mx >= kHgridSizeRatio * *mn;
}

std::vector<double> hgrid_levels(const std::vector<double>& r) {
  if (r.empty()) return {};
  const auto [mn, mx] = std::minmax_element(r.begin(), r.end());
  const int L = level_count(*mn, *mx);
  std::vector<double> up(std::size_t(L), 0.0);
  for (double ri : r) {
    double& u = up[std::size_t(level_of(ri, *mn, L))];
    u = std::max(u, ri);
  }
  return up;
}

void hgrid_half_list(const std::vector<Vec3>& x, const std::vector<double>& r, const Cell& cell, const Vec3* shift,
                     double skin, double reach, std::vector<int32_t>& start, std::vector<int32_t>& jout,
                     std::vector<uint8_t>& image, int threads) {
  const std::size_t n = r.size();
  start.assign(n + 1, 0);
  jout.clear();
  image.clear();
  if (n == 0) return;
  const auto [mnp, mxp] = std::minmax_element(r.begin(), r.end());
  const double rmin = *mnp, rmax = *mxp;
  const int L = level_count(rmin, rmax);
  const double extra = skin + reach;

  // Fractional coordinates and the extent of the grid (periodic: the unit cube).
  const Mat3 hinv = cell.h.inverse();
  std::vector<Vec3> s(n);
  for (std::size_t i = 0; i < n; ++i) s[i] = hinv * (x[i] - cell.origin);
  double lo[3], span[3], width[3];
  const double vol = cell.volume();
  for (int k = 0; k < 3; ++k) {
    const Vec3 a = cell.h.col((k + 1) % 3), b = cell.h.col((k + 2) % 3);
    width[k] = vol / norm(cross(a, b));  // perpendicular width of the cell along k
    if (cell.periodic[k]) {
      lo[k] = 0;
      span[k] = 1;
    } else {
      double smin = s[0][k], smax = s[0][k];
      for (const auto& si : s) smin = std::min(smin, si[k]), smax = std::max(smax, si[k]);
      lo[k] = smin;
      span[k] = std::max(smax - smin, 1e-12);
    }
  }

  // Levels: members, largest radius, bins (CSR of particle indices per bin).
  struct Level {
    std::vector<int32_t> members;
    double rmax = 0;
    int nb[3] = {1, 1, 1};
    std::vector<int32_t> bin_start, items;
  };
  std::vector<Level> lev(static_cast<std::size_t>(L));
  std::vector<int32_t> level(n);
  for (std::size_t i = 0; i < n; ++i) {
    level[i] = level_of(r[i], rmin, L);
    auto& lv = lev[std::size_t(level[i])];
    lv.members.push_back(int32_t(i));
    lv.rmax = std::max(lv.rmax, r[i]);
  }
  std::vector<int32_t> bin_of(n);
  for (auto& lv : lev) {
    if (lv.members.empty()) continue;
    const double size = 2 * lv.rmax + extra;
    const int cap = std::max(1, int(4 * std::cbrt(double(lv.members.size()))) + 1);
    for (int k = 0; k < 3; ++k) lv.nb[k] = std::min(std::max(1, int(std::floor(span[k] * width[k] / size))), cap);
    const std::size_t nbins = std::size_t(lv.nb[0]) * lv.nb[1] * lv.nb[2];
    lv.bin_start.assign(nbins + 1, 0);
    for (int32_t i : lv.members) {
      int c[3];
      for (int k = 0; k < 3; ++k)
        c[k] = std::clamp(int(std::floor((s[i][k] - lo[k]) / span[k] * lv.nb[k])), 0, lv.nb[k] - 1);
      bin_of[i] = (c[0] * lv.nb[1] + c[1]) * lv.nb[2] + c[2];
      ++lv.bin_start[std::size_t(bin_of[i]) + 1];
    }
    for (std::size_t b = 0; b < nbins; ++b) lv.bin_start[b + 1] += lv.bin_start[b];
    lv.items.resize(lv.members.size());
    std::vector<int32_t> fill(lv.bin_start.begin(), lv.bin_start.end() - 1);
    for (int32_t i : lv.members) lv.items[std::size_t(fill[std::size_t(bin_of[i])]++)] = i;
  }

  // Pairs of particle a with its own level and the levels of larger particles.
  const auto search_from = [&](std::size_t a, std::vector<Triple>& found) {
    const int la = level[a];
    for (int h = la; h < L; ++h) {
      const Level& lv = lev[std::size_t(h)];
      if (lv.members.empty()) continue;
      // Any partner b of level h is within r_a + r_max(h) + extra (strict test below), with a
      // relative margin so round-off in the fractional coordinates cannot drop a pair.
      const double e = (r[a] + lv.rmax + extra) * (1 + 1e-9);
      int from[3], to[3];
      bool empty = false;
      for (int k = 0; k < 3; ++k) {
        const double ek = e / width[k];
        // Clamped in floating point first: a degenerate span (all particles in one plane) would
        // overflow the integer conversion.
        const double f = std::floor((s[a][k] - ek - lo[k]) / span[k] * lv.nb[k]);
        const double t = std::floor((s[a][k] + ek - lo[k]) / span[k] * lv.nb[k]);
        from[k] = int(std::clamp(f, -2.0 * lv.nb[k], 3.0 * lv.nb[k]));
        to[k] = int(std::clamp(t, -2.0 * lv.nb[k], 3.0 * lv.nb[k]));
        if (cell.periodic[k]) {
          // Images −1..1 only (as the linked cells); a range wider than three cells repeats bins.
          from[k] = std::max(from[k], -lv.nb[k]);
          to[k] = std::min(to[k], 2 * lv.nb[k] - 1);
        } else {
          from[k] = std::max(from[k], 0);
          to[k] = std::min(to[k], lv.nb[k] - 1);
        }
        if (from[k] > to[k]) empty = true;
      }
      if (empty) continue;
      for (int c0 = from[0]; c0 <= to[0]; ++c0) {
        const int i0 = c0 < 0 ? -1 : (c0 >= lv.nb[0] ? 1 : 0), b0 = c0 - i0 * lv.nb[0];
        for (int c1 = from[1]; c1 <= to[1]; ++c1) {
          const int i1 = c1 < 0 ? -1 : (c1 >= lv.nb[1] ? 1 : 0), b1 = c1 - i1 * lv.nb[1];
          for (int c2 = from[2]; c2 <= to[2]; ++c2) {
            const int i2 = c2 < 0 ? -1 : (c2 >= lv.nb[2] ? 1 : 0), b2 = c2 - i2 * lv.nb[2];
            const int code = (i0 + 1) * 9 + (i1 + 1) * 3 + (i2 + 1);
            const std::size_t bin = (std::size_t(b0) * lv.nb[1] + std::size_t(b1)) * lv.nb[2] + std::size_t(b2);
            for (int32_t q = lv.bin_start[bin]; q < lv.bin_start[bin + 1]; ++q) {
              const int32_t b = lv.items[std::size_t(q)];
              // Canonical orientation: owner i = min index (image negated when swapped).
              int32_t i = int32_t(a), j = b;
              int c = code;
              if (b < int32_t(a)) i = b, j = int32_t(a), c = 26 - code;
              if (i == j && c <= kCentre) continue;  // self images once, positive half
              // Same level: the pair is seen from both ends; keep it from its owner only.
              if (h == la && i != int32_t(a)) continue;
              const Vec3 d = x[std::size_t(j)] + shift[c] - x[std::size_t(i)];
              const double rc = r[std::size_t(i)] + r[std::size_t(j)] + skin + reach;
              if (dot(d, d) < rc * rc) found.push_back({i, j, uint8_t(c)});
            }
          }
        }
      }
    }
  };

  // Search: each particle looks into its own level and the levels of larger particles. Threads
  // collect pairs separately; the rows are sorted at the end, so the list does not depend on
  // the thread count or the schedule.
  threads = std::max(1, threads);
  std::vector<std::vector<Triple>> found_by(static_cast<std::size_t>(threads));
#pragma omp parallel num_threads(threads) if (threads > 1)
  {
    std::vector<Triple>& found = found_by[std::size_t(omp_get_thread_num())];
    found.reserve(8 * n / std::size_t(threads));
#pragma omp for schedule(dynamic, 4096)
    for (long ai = 0; ai < long(n); ++ai) {
      search_from(std::size_t(ai), found);
    }
  }

  // CSR by owner, each row sorted by (j, image).
  for (const auto& found : found_by)
    for (const auto& t : found) ++start[std::size_t(t.owner) + 1];
  for (std::size_t i = 0; i < n; ++i) start[i + 1] += start[i];
  jout.resize(std::size_t(start[n]));
  image.resize(std::size_t(start[n]));
  {
    std::vector<int32_t> fill(start.begin(), start.end() - 1);
    for (auto& found : found_by) {
      for (const auto& t : found) {
        const int32_t k = fill[std::size_t(t.owner)]++;
        jout[std::size_t(k)] = t.partner;
        image[std::size_t(k)] = t.code;
      }
      std::vector<Triple>().swap(found);
    }
  }
  std::vector<std::pair<int32_t, uint8_t>> row;
#pragma omp parallel for num_threads(threads) if (threads > 1) schedule(static) private(row)
  for (long ii = 0; ii < long(n); ++ii) {
    const std::size_t i = std::size_t(ii);
    const int32_t b = start[i], e = start[i + 1];
    if (e - b < 2) continue;
    row.clear();
    for (int32_t k = b; k < e; ++k) row.emplace_back(jout[std::size_t(k)], image[std::size_t(k)]);
    std::sort(row.begin(), row.end());
    for (int32_t k = b; k < e; ++k) jout[std::size_t(k)] = row[std::size_t(k - b)].first, image[std::size_t(k)] = row[std::size_t(k - b)].second;
  }
}

}  // namespace tomodem::dem
