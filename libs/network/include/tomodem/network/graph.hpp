#pragma once
// A weighted undirected graph (a resistor network) and its connectivity:
// union-find clusters and the current-carrying backbone between two terminals.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace tomodem::network {

/// Edge list of an undirected graph with a conductance per edge (S).
struct Graph {
  std::size_t n_nodes = 0;
  std::vector<int32_t> i, j;  ///< endpoints, i != j
  std::vector<double> g;      ///< conductance, S (> 0)
  std::size_t n_edges() const { return g.size(); }
  void add_edge(int32_t a, int32_t b, double conductance) {
    i.push_back(a);
    j.push_back(b);
    g.push_back(conductance);
  }
};

/// Connected components: label per node in [0, n_components), numbered by first node.
std::vector<int32_t> connected_components(const Graph& graph, std::size_t* n_components = nullptr);

/// Nodes of the clusters that contain at least one node with terminal == 0 and one with
/// terminal == 1 (terminal: -1 none, 0 low electrode, 1 high electrode).
std::vector<uint8_t> spanning_nodes(const Graph& graph, const std::vector<int8_t>& terminal);

/// The backbone: nodes that can carry current between the two terminals. A node is on the
/// backbone when it lies on a path from a low to a high terminal node that visits no node twice;
/// equivalently, it belongs to the biconnected block that contains the edge S-T of the graph
/// augmented by a source S joined to every low terminal, a sink T joined to every high terminal,
/// and the edge S-T. Nodes of a spanning cluster off the backbone are dead ends: they carry no
/// current whatever the conductances. Iterative (no recursion), O(nodes + edges).
std::vector<uint8_t> backbone_nodes(const Graph& graph, const std::vector<int8_t>& terminal);

}  // namespace tomodem::network
