// Clusters of small graphs whose components and windings are known by construction.
#include <gtest/gtest.h>

#include "tomodem/spatial/clusters.hpp"

using namespace tomodem::spatial;

TEST(SpatialClusters, ChainThroughThePeriodicFaceWrapsOnce) {
  // 0-1-2-3 along x, 3 back to 0 through the +x image: one loop that picks up (1, 0, 0).
  const std::vector<int32_t> i = {0, 1, 2, 3}, j = {1, 2, 3, 0};
  const std::vector<Image> im = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {1, 0, 0}};
  const Clusters c = find_clusters(5, i, j, im);
  ASSERT_EQ(c.size.size(), 2u);  // the chain and particle 4
  EXPECT_EQ(c.size[0], 4);
  EXPECT_EQ(c.wrap_rank[0], 1);
  EXPECT_EQ(c.isolated, 1);
  EXPECT_EQ(c.main, 0);  // no cluster spans in 3-D: the largest
  EXPECT_EQ(c.outside_main, 1);
  // The same chain closed inside the cell does not wrap.
  const Clusters d = find_clusters(5, i, j, {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}});
  EXPECT_EQ(d.wrap_rank[0], 0);
}

TEST(SpatialClusters, SimpleCubicUnitCellSpansInThreeDimensions) {
  // One particle bonded to its own images along x, y and z, and a second component of two
  // particles; an inactive edge must not join them.
  const std::vector<int32_t> i = {0, 0, 0, 1, 0}, j = {0, 0, 0, 2, 1};
  const std::vector<Image> im = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, 0, 0}, {0, 0, 0}};
  const Clusters c = find_clusters(3, i, j, im, {1, 1, 1, 1, 0});
  ASSERT_EQ(c.size.size(), 2u);
  EXPECT_EQ(c.wrap_rank[std::size_t(c.label[0])], 3);
  EXPECT_EQ(c.wrap_rank[std::size_t(c.label[1])], 0);
  EXPECT_EQ(c.label[1], c.label[2]);
  EXPECT_EQ(c.spanning_clusters, 1);
  EXPECT_EQ(c.main, c.label[0]);  // the spanning cluster, though smaller
  EXPECT_EQ(c.outside_main, 2);
  // Two windings along the same direction count once.
  const Clusters d = find_clusters(1, {0, 0}, {0, 0}, {{1, 0, 0}, {2, 0, 0}});
  EXPECT_EQ(d.wrap_rank[0], 1);
}

TEST(SpatialClusters, WrapsNamesTheCellVectorsOfTheWindings) {
  // A chain closed through the +x image wraps along x only; a chain closed through the (1, 1, 0)
  // image has one winding (rank 1) with components along x and y, so a transport solve along x
  // or y finds it connected and one along z does not.
  const std::vector<int32_t> i = {0, 1, 2, 3}, j = {1, 2, 0, 3};
  const std::vector<Image> im = {{0, 0, 0}, {0, 0, 0}, {1, 0, 0}, {1, 1, 0}};
  const Clusters c = find_clusters(4, i, j, im);
  ASSERT_EQ(c.size.size(), 2u);
  EXPECT_EQ(c.wraps[std::size_t(c.label[0])], (std::array<uint8_t, 3>{1, 0, 0}));
  EXPECT_EQ(c.wrap_rank[std::size_t(c.label[3])], 1);
  EXPECT_EQ(c.wraps[std::size_t(c.label[3])], (std::array<uint8_t, 3>{1, 1, 0}));
  // Closed inside the cell: no axis.
  const Clusters d = find_clusters(3, {0, 1, 2}, {1, 2, 0}, {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}});
  EXPECT_EQ(d.wraps[0], (std::array<uint8_t, 3>{0, 0, 0}));
}

TEST(SpatialUnionFind, JoinsSetsAndReportsWhetherTheyWereApart) {
  UnionFind uf(5);
  EXPECT_TRUE(uf.unite(0, 1));
  EXPECT_TRUE(uf.unite(3, 4));
  EXPECT_FALSE(uf.unite(1, 0));  // already one set
  EXPECT_TRUE(uf.unite(1, 4));
  EXPECT_EQ(uf.find(0), uf.find(3));
  EXPECT_NE(uf.find(0), uf.find(2));
  EXPECT_EQ(uf.find(2), 2);  // a singleton is its own root
}
