#include "tomodem/spatial/grid.hpp"

#include "tomodem/spatial/overlap.hpp"

#include <omp.h>

#include <cstdlib>
#include <cstring>
#include <set>
#include <sstream>
#include "tomodem/core/error.hpp"

namespace tomodem::spatial {

namespace {
NeighborSearch g_search = [] {
  const char* e = std::getenv("TOMODEM_NEIGHBOR_SEARCH");
  if (e && std::strcmp(e, "hgrid") == 0) return NeighborSearch::hgrid;
  if (e && std::strcmp(e, "cells") == 0) return NeighborSearch::linked_cells;
  return NeighborSearch::automatic;
}();

struct Triple {
  int32_t owner, partner;
  uint8_t code;
};
}  // namespace

// A cell-size ratio of 2 between levels is the optimum Ogarko & Luding report for wide
// distributions (their Fig. 6: cost flat between ratios 1.5 and 3).
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

std::vector<Image> wrap_into_cell(std::vector<Vec3>& x, const Cell& cell) {
  std::vector<Image> w(x.size(), Image{0, 0, 0});
  if (!(cell.periodic[0] || cell.periodic[1] || cell.periodic[2])) return w;
  const Mat3 hinv = cell.h.inverse();
  for (std::size_t i = 0; i < x.size(); ++i) {
    Vec3 s = hinv * (x[i] - cell.origin);
    bool moved = false;
    for (int k = 0; k < 3; ++k)
      if (cell.periodic[k]) {
        const double fl = std::floor(s[k]);
        if (fl != 0) {
          s[k] -= fl;
          w[i][k] = int32_t(fl);
          moved = true;
        }
      }
    if (moved) x[i] = cell.origin + cell.h * s;
  }
  return w;
}

std::array<Vec3, kImageCodes> image_shifts(const Mat3& h) {
  std::array<Vec3, kImageCodes> s;
  for (int c = 0; c < kImageCodes; ++c) s[std::size_t(c)] = h * image_vector(c);
  return s;
}

Grid::Grid(const std::vector<Vec3>& x, const std::vector<double>& r, const Cell& cell, double extra, bool hierarchical)
    : extra_(extra), r_(r.data()) {
  const std::size_t n = r.size();
  for (int k = 0; k < 3; ++k) periodic_[k] = cell.periodic[k], lo_[k] = 0, span_[k] = 1, width_[k] = 1;
  level_.assign(n, 0);
  if (n == 0) return;
  const auto [mnp, mxp] = std::minmax_element(r.begin(), r.end());
  const int L = hierarchical ? level_count(*mnp, *mxp) : 1;

  // Fractional coordinates and the extent of the grid (periodic: the unit cube).
  const Mat3 hinv = cell.h.inverse();
  s_.resize(n);
  for (std::size_t i = 0; i < n; ++i) s_[i] = hinv * (x[i] - cell.origin);
  const double vol = cell.volume();
  for (int k = 0; k < 3; ++k) {
    width_[k] = vol / norm(cross(cell.h.col((k + 1) % 3), cell.h.col((k + 2) % 3)));  // perpendicular width
    if (!periodic_[k]) {
      double smin = s_[0][k], smax = s_[0][k];
      for (const auto& si : s_) smin = std::min(smin, si[k]), smax = std::max(smax, si[k]);
      lo_[k] = smin;
      span_[k] = std::max(smax - smin, 1e-12);
    }
  }

  // Levels: members' largest radius, bins (CSR of particle indices per bin).
  lev_.resize(std::size_t(L));
  std::vector<std::size_t> count(std::size_t(L), 0);
  for (std::size_t i = 0; i < n; ++i) {
    level_[i] = L > 1 ? level_of(r[i], *mnp, L) : 0;
    Level& lv = lev_[std::size_t(level_[i])];
    lv.rmax = std::max(lv.rmax, r[i]);
    ++count[std::size_t(level_[i])];
  }
  std::vector<int32_t> bin_of(n);
  for (int l = 0; l < L; ++l) {
    Level& lv = lev_[std::size_t(l)];
    if (count[std::size_t(l)] == 0) continue;
    const double size = 2 * lv.rmax + extra;
    // Capped so a sparse open scene cannot ask for huge memory.
    const int cap = std::max(1, int(4 * std::cbrt(double(count[std::size_t(l)]))) + 1);
    for (int k = 0; k < 3; ++k) lv.nb[k] = std::min(std::max(1, int(std::floor(span_[k] * width_[k] / size))), cap);
    const std::size_t nbins = std::size_t(lv.nb[0]) * lv.nb[1] * lv.nb[2];
    lv.bin_start.assign(nbins + 1, 0);
  }
  for (std::size_t i = 0; i < n; ++i) {
    Level& lv = lev_[std::size_t(level_[i])];
    int c[3];
    for (int k = 0; k < 3; ++k)
      c[k] = std::clamp(int(std::floor((s_[i][k] - lo_[k]) / span_[k] * lv.nb[k])), 0, lv.nb[k] - 1);
    bin_of[i] = (c[0] * lv.nb[1] + c[1]) * lv.nb[2] + c[2];
    ++lv.bin_start[std::size_t(bin_of[i]) + 1];
  }
  for (int l = 0; l < L; ++l) {
    Level& lv = lev_[std::size_t(l)];
    for (std::size_t b = 0; b + 1 < lv.bin_start.size(); ++b) lv.bin_start[b + 1] += lv.bin_start[b];
    lv.items.resize(count[std::size_t(l)]);
  }
  std::vector<std::vector<int32_t>> fill(static_cast<std::size_t>(L));
  for (int l = 0; l < L; ++l)
    if (!lev_[std::size_t(l)].bin_start.empty())
      fill[std::size_t(l)].assign(lev_[std::size_t(l)].bin_start.begin(), lev_[std::size_t(l)].bin_start.end() - 1);
  for (std::size_t i = 0; i < n; ++i)
    lev_[std::size_t(level_[i])].items[std::size_t(fill[std::size_t(level_[i])][std::size_t(bin_of[i])]++)] = int32_t(i);
}

void half_list(const Grid& grid, const std::vector<Vec3>& x, const std::vector<double>& r, const Vec3* shift,
               double extra, std::vector<int32_t>& start, std::vector<int32_t>& jout, std::vector<uint8_t>& image,
               int threads) {
  const std::size_t n = r.size();
  start.assign(n + 1, 0);
  jout.clear();
  image.clear();
  if (n == 0) return;
  // Pairs of particle a: canonical orientation, owner i = the smaller index (image negated when
  // swapped); a pair of one level is seen from both ends and kept from its owner only.
  const auto search_from = [&](std::size_t a, std::vector<Triple>& found) {
    const int la = grid.level(a);
    grid.visit(a, [&](int32_t b, int code) {
      int32_t i = int32_t(a), j = b;
      int c = code;
      if (b < int32_t(a)) i = b, j = int32_t(a), c = opposite_image(code);
      if (i == j && c <= kCentreImage) return;  // self images once, positive half
      if (grid.level(std::size_t(b)) == la && i != int32_t(a)) return;
      const Vec3 d = x[std::size_t(j)] + shift[c] - x[std::size_t(i)];
      const double rc = r[std::size_t(i)] + r[std::size_t(j)] + extra;
      if (dot(d, d) < rc * rc) found.push_back({i, j, uint8_t(c)});
    });
  };
  // Threads collect pairs separately; the rows are sorted at the end, so the list does not
  // depend on the thread count or the schedule.
  threads = std::max(1, threads);
  std::vector<std::vector<Triple>> found_by(static_cast<std::size_t>(threads));
#pragma omp parallel num_threads(threads) if (threads > 1)
  {
    std::vector<Triple>& found = found_by[std::size_t(omp_get_thread_num())];
    found.reserve(8 * n / std::size_t(threads));
#pragma omp for schedule(dynamic, 4096)
    for (long ai = 0; ai < long(n); ++ai) search_from(std::size_t(ai), found);
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
    const int32_t b = start[std::size_t(ii)], e = start[std::size_t(ii) + 1];
    if (e - b < 2) continue;
    row.clear();
    for (int32_t k = b; k < e; ++k) row.emplace_back(jout[std::size_t(k)], image[std::size_t(k)]);
    std::sort(row.begin(), row.end());
    for (int32_t k = b; k < e; ++k)
      jout[std::size_t(k)] = row[std::size_t(k - b)].first, image[std::size_t(k)] = row[std::size_t(k - b)].second;
  }
}

std::vector<Pair> pairs_within(const std::vector<Vec3>& x0, const std::vector<double>& r, const Cell& cell,
                               double extra, int threads) {
  std::vector<Pair> out;
  if (x0.size() < 2) return out;
  std::vector<Vec3> x = x0;
  const std::vector<Image> w = wrap_into_cell(x, cell);
  const Grid grid(x, r, cell, extra);
  const auto shift = image_shifts(cell.h);
  std::vector<int32_t> start, nj;
  std::vector<uint8_t> code;
  half_list(grid, x, r, shift.data(), extra, start, nj, code, threads);
  out.reserve(nj.size());
  for (std::size_t i = 0; i + 1 < start.size(); ++i)
    for (int32_t k = start[i]; k < start[i + 1]; ++k) {
      const std::size_t j = std::size_t(nj[std::size_t(k)]);
      if (j == i) continue;
      const int c = code[std::size_t(k)];
      // The image of the given positions: x0_j + H n0 − x0_i = x_j + H n − x_i, x0 = x + H w.
      Image n0 = image_of_code(c);
      for (int a = 0; a < 3; ++a) n0[std::size_t(a)] += w[i][std::size_t(a)] - w[j][std::size_t(a)];
      out.push_back({int32_t(i), int32_t(j), n0, norm(x[j] + shift[std::size_t(c)] - x[i])});
    }
  return out;
}

std::vector<Pair> contacts_within(const std::vector<Vec3>& x, const std::vector<double>& r, const Cell& cell,
                                  double tolerance, int threads) {
  std::vector<Pair> out;
  if (x.size() < 2) return out;
  const double rmax = *std::max_element(r.begin(), r.end());
  for (const Pair& q : pairs_within(x, r, cell, contact_reach(rmax, tolerance), threads))
    if (in_contact(q.distance, r[std::size_t(q.i)], r[std::size_t(q.j)], tolerance)) out.push_back(q);
  return out;
}

void check_start_overlaps(const std::vector<Vec3>& x, const std::vector<double>& r, const Cell& cell,
                          const std::string& file, const BondTable* bonds, const std::string& dataset, double limit,
                          int threads) {
  std::set<std::pair<int32_t, int32_t>> necks;
  if (bonds)
    for (std::size_t k = 0; k < bonds->size(); ++k)
      if (bonds->state[k] == BondTable::intact) necks.insert(std::minmax(bonds->i[k], bonds->j[k]));
  for (const Pair& q : pairs_within(x, r, cell, 0, threads)) {
    if (necks.count(std::minmax(q.i, q.j))) continue;
    const double ri = r[std::size_t(q.i)], rj = r[std::size_t(q.j)];
    const double ratio = (ri + rj - q.distance) / std::min(ri, rj);
    if (ratio > limit) {
      std::ostringstream s;
      s << "particles " << q.i << " and " << q.j << " overlap by " << ratio << " of the smaller radius at start (limit "
        << limit << ")" << (q.distance == 0 ? ": they are at the same position" : "");
      std::ostringstream v;
      v << ratio;
      throw InputError(file, dataset, v.str(), s.str());
    }
  }
}

}  // namespace tomodem::spatial
