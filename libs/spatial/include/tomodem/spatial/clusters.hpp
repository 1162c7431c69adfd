#pragma once
// Connected components of a contact or bond graph in a periodic cell, and whether each one wraps
// around the cell (a closed loop of edges that adds up to a non-zero lattice vector).
#include <array>
#include <cstdint>
#include <vector>

#include "tomodem/spatial/image.hpp"

namespace tomodem::spatial {

/// Disjoint sets with path halving and union by size: components when the periodic images do
/// not matter (terminals of a graph, fragments of a sample).
class UnionFind {
 public:
  explicit UnionFind(std::size_t n);
  int32_t find(int32_t a);
  /// Returns true when a and b were in different sets.
  bool unite(int32_t a, int32_t b);

 private:
  std::vector<int32_t> parent_, size_;
};

/// A cluster "wraps" the periodic cell along the lattice vectors its closed loops pick up;
/// wrap_rank = 3 means it spans the cell in 3-D.
struct Clusters {
  std::vector<int32_t> label;   ///< per particle, cluster index (isolated particles have their own)
  std::vector<int64_t> size;    ///< particles per cluster
  std::vector<int> wrap_rank;   ///< 0..3 per cluster
  /// per cluster, the cell vectors k along which it wraps (a closed loop whose lattice vector has
  /// a non-zero component k); what a periodic transport solve along k needs
  std::vector<std::array<uint8_t, 3>> wraps;
  int main = -1;                ///< largest cluster with wrap_rank 3, else the largest cluster
  long isolated = 0;            ///< particles without edges (rattlers, floating particles)
  long spanning_clusters = 0;   ///< clusters with wrap_rank 3
  long outside_main = 0;        ///< particles not in the main cluster
};

/// Components of the graph on n particles with edges i[e] – j[e], j seen from i through
/// image[e]; edges with active[e] == 0 are left out (`active` empty: all edges count).
Clusters find_clusters(std::size_t n, const std::vector<int32_t>& i, const std::vector<int32_t>& j,
                       const std::vector<Image>& image, const std::vector<uint8_t>& active = {});

}  // namespace tomodem::spatial
