// Connectivity: union-find clusters, spanning clusters and the current-carrying backbone.
#include <gtest/gtest.h>

#include "tomodem/network/graph.hpp"

using namespace tomodem::network;

TEST(Graph, ComponentsOfTwoChainsAndASingleton) {
  Graph g;
  g.n_nodes = 6;
  g.add_edge(0, 1, 1);
  g.add_edge(1, 2, 1);
  g.add_edge(3, 4, 1);
  std::size_t nc = 0;
  const auto label = connected_components(g, &nc);
  EXPECT_EQ(nc, 3u);
  EXPECT_EQ(label[0], label[2]);
  EXPECT_EQ(label[3], label[4]);
  EXPECT_NE(label[0], label[3]);
  EXPECT_NE(label[5], label[0]);
}

TEST(Graph, SpanningNodesNeedBothTerminals) {
  Graph g;
  g.n_nodes = 6;
  g.add_edge(0, 1, 1);  // 0 (low) - 1 - 2 (high): spans
  g.add_edge(1, 2, 1);
  g.add_edge(3, 4, 1);  // 3 (low) - 4: touches one face only
  const std::vector<int8_t> term = {0, -1, 1, 0, -1, -1};
  const auto s = spanning_nodes(g, term);
  EXPECT_EQ(s, (std::vector<uint8_t>{1, 1, 1, 0, 0, 0}));
}

// low(0) - 1 - 2 - high(3), with a dangling branch 1 - 4 - 5 and a loop 2 - 6 - 7 - 2 hanging
// off node 2 (a loop that returns to the same node carries no current either).
TEST(Graph, BackboneExcludesDanglingBranchesAndLoopsThroughOneNode) {
  Graph g;
  g.n_nodes = 8;
  g.add_edge(0, 1, 1);
  g.add_edge(1, 2, 1);
  g.add_edge(2, 3, 1);
  g.add_edge(1, 4, 1);
  g.add_edge(4, 5, 1);
  g.add_edge(2, 6, 1);
  g.add_edge(6, 7, 1);
  g.add_edge(7, 2, 1);
  const std::vector<int8_t> term = {0, -1, -1, 1, -1, -1, -1, -1};
  const auto b = backbone_nodes(g, term);
  EXPECT_EQ(b, (std::vector<uint8_t>{1, 1, 1, 1, 0, 0, 0, 0}));
}

// Two parallel paths between the electrodes are both backbone; a bridge between them too.
TEST(Graph, BackboneKeepsParallelPathsAndBridges) {
  Graph g;
  g.n_nodes = 6;  // 0 low, 5 high; paths 0-1-2-5 and 0-3-4-5, rung 1-3
  g.add_edge(0, 1, 1);
  g.add_edge(1, 2, 1);
  g.add_edge(2, 5, 1);
  g.add_edge(0, 3, 1);
  g.add_edge(3, 4, 1);
  g.add_edge(4, 5, 1);
  g.add_edge(1, 3, 1);
  const std::vector<int8_t> term = {0, -1, -1, -1, -1, 1};
  const auto b = backbone_nodes(g, term);
  EXPECT_EQ(b, (std::vector<uint8_t>(6, 1)));
}

// Several low terminals: a path between two low electrode particles that reaches the high face
// only through them is still backbone (it joins electrode particles at the same potential, so
// it is a simple S-T path in the augmented graph), while a branch hanging off is not.
TEST(Graph, BackboneWithManyTerminals) {
  Graph g;
  g.n_nodes = 5;  // lows 0, 1; high 4; 0-2-4, 1-2, 2-3 (dangling)
  g.add_edge(0, 2, 1);
  g.add_edge(1, 2, 1);
  g.add_edge(2, 4, 1);
  g.add_edge(2, 3, 1);
  const std::vector<int8_t> term = {0, 0, -1, -1, 1};
  const auto b = backbone_nodes(g, term);
  EXPECT_EQ(b, (std::vector<uint8_t>{1, 1, 1, 0, 1}));
}
