// tomodem-cg --vdb: the VDB file read back with OpenVDB holds the HDF5 values at the nodes, and
// its transform maps node (i0, i1, i2) to the node's position in metres, sheared cells included.
#include <gtest/gtest.h>
#include <openvdb/openvdb.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "../../validation/fields/lattices.hpp"
#include "../common/tool_test.hpp"
#include "tomodem/core/h5.hpp"
#include "tomodem/core/packing_io.hpp"

namespace fs = std::filesystem;
using namespace tomodem;

namespace {
class FieldsVdb : public test::ToolTest {
 protected:
  FieldsVdb() : ToolTest("tomodem-fields-vdb") {}
};
}  // namespace

TEST_F(FieldsVdb, ReadBackMatchesTheHdf5AtTheNodesInMetres) {
  // A sheared, strained spring lattice with velocities: every scalar and vector field is non-trivial.
  Mat3 F = Mat3::diagonal({1.002, 0.999, 1});
  F(0, 1) = 0.05;
  Packing p = fields::test::spring_lattice(5, 1e-3, F, 1e4);
  for (std::size_t i = 0; i < p.particles.size(); ++i)
    p.particles.velocity.push_back({1e-3 * std::sin(double(i)), 2e-3 * std::cos(double(i)), 0.5e-3});
  write_packing(path("lattice.h5"), p);
  ASSERT_EQ(sh(std::string(TOMODEM_BIN_DIR) + "/tomodem-cg lattice.h5 -o f.h5 --vdb f.vdb --nodes 6,7,8 --json f.json -q"), 0)
      << text("stderr.txt");
  const auto j = nlohmann::json::parse(text("f.json"));
  EXPECT_EQ(j["outputs"]["vdb"], "f.vdb");
  h5::File h(path("f.h5"), h5::File::Mode::read);
  const auto points = h.read_double("/grid/points"), density = h.read_double("/fields/density");
  const auto stress = h.read_double("/fields/stress"), velocity = h.read_double("/fields/velocity");
  const std::size_t N = density.size();
  ASSERT_EQ(N, 6u * 7u * 8u);

  openvdb::initialize();
  openvdb::io::File file(path("f.vdb"));
  file.open();
  EXPECT_EQ(file.getMetadata()->metaValue<std::string>("length_unit"), "m");
  EXPECT_EQ(file.getMetadata()->metaValue<std::string>("tool"), "tomodem-cg");
  auto rho = openvdb::gridPtrCast<openvdb::DoubleGrid>(file.readGrid("density"));
  auto pressure = openvdb::gridPtrCast<openvdb::DoubleGrid>(file.readGrid("pressure"));
  auto mises = openvdb::gridPtrCast<openvdb::DoubleGrid>(file.readGrid("von_mises"));
  auto speed = openvdb::gridPtrCast<openvdb::DoubleGrid>(file.readGrid("speed"));
  auto vel = openvdb::gridPtrCast<openvdb::Vec3DGrid>(file.readGrid("velocity"));
  ASSERT_TRUE(rho && pressure && mises && speed && vel);
  file.close();
  EXPECT_EQ(rho->metaValue<std::string>("unit"), "kg/m^3");
  EXPECT_EQ(rho->metaValue<std::string>("length_unit"), "m");
  EXPECT_EQ(pressure->metaValue<std::string>("unit"), "Pa");
  EXPECT_EQ(rho->activeVoxelCount(), openvdb::Index64(N));
  const double L = 5e-3;
  for (std::size_t k = 0; k < N; ++k) {
    const openvdb::Coord ijk(int(k / 56), int((k / 8) % 7), int(k % 8));
    const openvdb::Vec3d x = rho->transform().indexToWorld(ijk);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(x[c], points[3 * k + c], 1e-12 * L) << "node " << k;
    EXPECT_EQ(rho->tree().getValue(ijk), density[k]);
    const double* s = &stress[9 * k];
    EXPECT_NEAR(pressure->tree().getValue(ijk), -(s[0] + s[4] + s[8]) / 3, 1e-12 * std::abs(s[0]));
    const openvdb::Vec3d v = vel->tree().getValue(ijk);
    for (int c = 0; c < 3; ++c) EXPECT_EQ(v[c], velocity[3 * k + c]);
    EXPECT_NEAR(speed->tree().getValue(ijk), std::hypot(velocity[3 * k], velocity[3 * k + 1], velocity[3 * k + 2]), 1e-15);
    EXPECT_GE(mises->tree().getValue(ijk), 0.0);
  }
}
