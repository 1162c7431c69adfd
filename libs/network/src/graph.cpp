#include "tomodem/network/graph.hpp"

#include "tomodem/spatial/clusters.hpp"

#include <numeric>

namespace tomodem::network {

std::vector<int32_t> connected_components(const Graph& graph, std::size_t* n_components) {
  spatial::UnionFind uf(graph.n_nodes);
  for (std::size_t e = 0; e < graph.n_edges(); ++e) uf.unite(graph.i[e], graph.j[e]);
  std::vector<int32_t> label(graph.n_nodes, -1), root_label(graph.n_nodes, -1);
  int32_t next = 0;
  for (std::size_t v = 0; v < graph.n_nodes; ++v) {
    const int32_t r = uf.find(static_cast<int32_t>(v));
    if (root_label[r] < 0) root_label[r] = next++;
    label[v] = root_label[r];
  }
  if (n_components) *n_components = static_cast<std::size_t>(next);
  return label;
}

std::vector<uint8_t> spanning_nodes(const Graph& graph, const std::vector<int8_t>& terminal) {
  std::size_t nc = 0;
  const std::vector<int32_t> label = connected_components(graph, &nc);
  std::vector<uint8_t> has_low(nc, 0), has_high(nc, 0), out(graph.n_nodes, 0);
  for (std::size_t v = 0; v < graph.n_nodes; ++v) {
    if (terminal[v] == 0) has_low[label[v]] = 1;
    if (terminal[v] == 1) has_high[label[v]] = 1;
  }
  for (std::size_t v = 0; v < graph.n_nodes; ++v) out[v] = has_low[label[v]] && has_high[label[v]];
  return out;
}

std::vector<uint8_t> backbone_nodes(const Graph& graph, const std::vector<int8_t>& terminal) {
  // Augmented graph: S = n, T = n + 1, edges: the graph's, S-low, T-high, and S-T (last).
  const int32_t n = static_cast<int32_t>(graph.n_nodes), S = n, T = n + 1, nn = n + 2;
  std::vector<int32_t> ea(graph.i), eb(graph.j);
  for (int32_t v = 0; v < n; ++v) {
    if (terminal[v] == 0) { ea.push_back(S); eb.push_back(v); }
    if (terminal[v] == 1) { ea.push_back(T); eb.push_back(v); }
  }
  const int32_t st_edge = static_cast<int32_t>(ea.size());
  ea.push_back(S);
  eb.push_back(T);
  const std::size_t m = ea.size();
  // CSR adjacency.
  std::vector<int64_t> start(nn + 1, 0);
  for (std::size_t e = 0; e < m; ++e) { ++start[ea[e] + 1]; ++start[eb[e] + 1]; }
  for (int32_t v = 0; v < nn; ++v) start[v + 1] += start[v];
  std::vector<int32_t> adj_edge(2 * m), fill(start.begin(), start.end() - 1);
  for (std::size_t e = 0; e < m; ++e) {
    adj_edge[fill[ea[e]]++] = static_cast<int32_t>(e);
    adj_edge[fill[eb[e]]++] = static_cast<int32_t>(e);
  }
  std::vector<int32_t> disc(nn, -1), low(nn, 0), parent_edge(nn, -1);
  std::vector<int64_t> pos(start.begin(), start.end() - 1);
  std::vector<int32_t> stack, edge_stack;
  std::vector<uint8_t> out(graph.n_nodes, 0);
  int32_t clock = 0;
  disc[S] = low[S] = clock++;
  stack.push_back(S);
  while (!stack.empty()) {
    const int32_t v = stack.back();
    if (pos[v] < start[v + 1]) {
      const int32_t e = adj_edge[pos[v]++];
      if (e == parent_edge[v]) continue;
      const int32_t w = ea[e] == v ? eb[e] : ea[e];
      if (disc[w] < 0) {
        parent_edge[w] = e;
        edge_stack.push_back(e);
        disc[w] = low[w] = clock++;
        stack.push_back(w);
      } else if (disc[w] < disc[v]) {  // back edge to an ancestor
        edge_stack.push_back(e);
        if (disc[w] < low[v]) low[v] = disc[w];
      }
      continue;
    }
    stack.pop_back();
    if (stack.empty()) break;
    const int32_t u = stack.back();
    if (low[v] < low[u]) low[u] = low[v];
    if (low[v] >= disc[u]) {  // u separates the block below it: pop the block's edges
      const std::size_t mark = edge_stack.size();
      std::size_t first = mark;
      bool has_st = false;
      while (first > 0) {
        const int32_t e = edge_stack[--first];
        if (e == st_edge) has_st = true;
        if (e == parent_edge[v]) break;
      }
      if (has_st)
        for (std::size_t k = first; k < mark; ++k) {
          const int32_t e = edge_stack[k];
          if (ea[e] < n) out[ea[e]] = 1;
          if (eb[e] < n) out[eb[e]] = 1;
        }
      edge_stack.resize(first);
    }
  }
  return out;
}

}  // namespace tomodem::network
