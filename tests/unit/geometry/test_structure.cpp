// Coordination with and without rattlers, per phase pair, and the recursive rattler rule.
#include <gtest/gtest.h>

#include "tomodem/geometry/pack.hpp"

using namespace tomodem;
using namespace tomodem::geometry;

TEST(ContactStructure, RattlersRemovedRecursively) {
  // A tetrahedron of 4 particles (each 3 contacts) plus particle 4 touching 0 only.
  ContactTable c;
  const int pairs[][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}, {0, 4}};
  for (auto& p : pairs) {
    c.i.push_back(p[0]), c.j.push_back(p[1]);
    c.overlap.push_back(1e-6);
    c.normal_force.push_back({0, 0, 1});
    c.tangential_force.push_back({});
  }
  const auto s = contact_structure(5, {0, 0, 1, 1, 0}, 2, c, 3);
  EXPECT_DOUBLE_EQ(s.coordination, 14.0 / 5);
  EXPECT_EQ(s.rattler[4], 1);
  EXPECT_DOUBLE_EQ(s.coordination_no_rattlers, 3.0);
  EXPECT_DOUBLE_EQ(s.rattler_fraction, 0.2);
  // Phase 0 = {0,1,4}: contacts 0-1 (x2 ends), 0-4 (x2), to phase 1: 0-2, 0-3, 1-2, 1-3.
  EXPECT_DOUBLE_EQ(s.z_ij[0][0], 4.0 / 3);
  EXPECT_DOUBLE_EQ(s.z_ij[0][1], 4.0 / 3);
  EXPECT_DOUBLE_EQ(s.z_ij[1][1], 1.0);
  // With a threshold of 4 everything collapses: each removal lowers the neighbours below 4.
  const auto all = contact_structure(5, {0, 0, 1, 1, 0}, 2, c, 4);
  EXPECT_DOUBLE_EQ(all.rattler_fraction, 1.0);
}
