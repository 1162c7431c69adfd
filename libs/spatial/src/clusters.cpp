// Union-find for plain components. Periodic clusters by a depth-first walk that carries each particle's lattice offset from the
// component's first particle; an edge that closes a loop with another offset is a winding.
#include "tomodem/spatial/clusters.hpp"

#include <array>
#include <cmath>
#include <cstdlib>
#include <numeric>
#include <utility>

namespace tomodem::spatial {

UnionFind::UnionFind(std::size_t n) : parent_(n), size_(n, 1) { std::iota(parent_.begin(), parent_.end(), 0); }

int32_t UnionFind::find(int32_t a) {
  while (parent_[std::size_t(a)] != a) {
    parent_[std::size_t(a)] = parent_[std::size_t(parent_[std::size_t(a)])];
    a = parent_[std::size_t(a)];
  }
  return a;
}

bool UnionFind::unite(int32_t a, int32_t b) {
  a = find(a);
  b = find(b);
  if (a == b) return false;
  if (size_[std::size_t(a)] < size_[std::size_t(b)]) std::swap(a, b);
  parent_[std::size_t(b)] = a;
  size_[std::size_t(a)] += size_[std::size_t(b)];
  return true;
}

namespace {
// Rank of a set of integer vectors (Gaussian elimination in doubles; entries are small).
int rank_of(std::vector<std::array<double, 3>> v) {
  int rank = 0;
  for (int col = 0; col < 3 && rank < int(v.size()); ++col) {
    std::size_t piv = std::size_t(rank);
    for (std::size_t r = std::size_t(rank); r < v.size(); ++r)
      if (std::abs(v[r][col]) > std::abs(v[piv][col])) piv = r;
    if (std::abs(v[piv][col]) < 1e-9) continue;
    std::swap(v[piv], v[std::size_t(rank)]);
    for (std::size_t r = 0; r < v.size(); ++r)
      if (r != std::size_t(rank)) {
        const double f = v[r][col] / v[std::size_t(rank)][col];
        for (int k = 0; k < 3; ++k) v[r][k] -= f * v[std::size_t(rank)][k];
      }
    ++rank;
  }
  return rank;
}

/// Main cluster and the counts of Clusters from labels, sizes and wrap ranks.
void summarise(Clusters& c, std::size_t n) {
  int best = -1, largest = -1;
  for (int k = 0; k < int(c.size.size()); ++k) {
    if (c.size[std::size_t(k)] == 1) ++c.isolated;
    if (c.wrap_rank[std::size_t(k)] == 3) {
      ++c.spanning_clusters;
      if (best < 0 || c.size[std::size_t(k)] > c.size[std::size_t(best)]) best = k;
    }
    if (largest < 0 || c.size[std::size_t(k)] > c.size[std::size_t(largest)]) largest = k;
  }
  c.main = best >= 0 ? best : largest;
  c.outside_main = c.main >= 0 ? long(n) - long(c.size[std::size_t(c.main)]) : 0;
}
}  // namespace

Clusters find_clusters(std::size_t n, const std::vector<int32_t>& ei, const std::vector<int32_t>& ej,
                       const std::vector<Image>& image, const std::vector<uint8_t>& active) {
  const std::size_t m = ei.size();
  const auto on = [&](std::size_t e) { return active.empty() || active[e] != 0; };
  // Adjacency (CSR): (other end, signed edge: +e+1 from i to j, −(e+1) from j to i).
  std::vector<int64_t> start(n + 1, 0);
  for (std::size_t e = 0; e < m; ++e)
    if (on(e)) ++start[std::size_t(ei[e]) + 1], ++start[std::size_t(ej[e]) + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<int64_t> fill(start.begin(), start.end() - 1);
  std::vector<std::pair<int32_t, int32_t>> adj(std::size_t(start[n]));
  for (std::size_t e = 0; e < m; ++e)
    if (on(e)) {
      adj[std::size_t(fill[std::size_t(ei[e])]++)] = {ej[e], int32_t(e + 1)};
      adj[std::size_t(fill[std::size_t(ej[e])]++)] = {ei[e], -int32_t(e + 1)};
    }
  Clusters c;
  c.label.assign(n, -1);
  std::vector<Image> offset(n, Image{0, 0, 0});
  std::vector<int32_t> stack;
  for (std::size_t s = 0; s < n; ++s) {
    if (c.label[s] >= 0) continue;
    const int id = int(c.size.size());
    c.size.push_back(0);
    std::vector<std::array<double, 3>> windings;
    c.label[s] = id;
    stack.push_back(int32_t(s));
    while (!stack.empty()) {
      const int32_t u = stack.back();
      stack.pop_back();
      ++c.size[std::size_t(id)];
      for (int64_t a = start[std::size_t(u)]; a < start[std::size_t(u) + 1]; ++a) {
        const auto [v, se] = adj[std::size_t(a)];
        const Image& w = image[std::size_t(std::abs(se) - 1)];
        Image expect = offset[std::size_t(u)];
        for (int k = 0; k < 3; ++k) expect[k] += se > 0 ? w[k] : -w[k];
        if (c.label[std::size_t(v)] < 0) {
          c.label[std::size_t(v)] = id;
          offset[std::size_t(v)] = expect;
          stack.push_back(v);
        } else if (expect != offset[std::size_t(v)] && windings.size() < 3) {
          // A closed loop that picks up a lattice vector: kept when it is independent.
          const Image& o = offset[std::size_t(v)];
          windings.push_back({double(expect[0] - o[0]), double(expect[1] - o[1]), double(expect[2] - o[2])});
          if (rank_of(windings) < int(windings.size())) windings.pop_back();
        }
      }
    }
    c.wrap_rank.push_back(windings.empty() ? 0 : rank_of(windings));
    // Every winding of the cluster is a combination of the independent ones kept, so an axis
    // some winding has a component along is one a kept winding has a component along.
    std::array<uint8_t, 3> along{0, 0, 0};
    for (const auto& w : windings)
      for (int k = 0; k < 3; ++k) along[k] = uint8_t(along[k] || w[k] != 0);
    c.wraps.push_back(along);
  }
  summarise(c, n);
  return c;
}

}  // namespace tomodem::spatial
