// Fields from the tools that hold a state in memory (docs/cg.md): tomodem-dem's fields: block
// (the worked example of the docs, run as written: the block's fields of a static lattice are
// tomodem-cg's of the packing the run writes), tomodem-young --fields (the Love stress and the
// imposed strain of a uniform lattice), tomodem-fracture --fields (the state at the peak load).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <utility>
#include <vector>

#include "../../validation/fracture/samples.hpp"
#include "../../validation/mechanics/networks.hpp"
#include "../common/tool_test.hpp"
#include "tomodem/core/h5.hpp"
#include "tomodem/mechanics/network.hpp"

namespace fs = std::filesystem;
using namespace tomodem;

namespace {
class FieldsBlock : public test::ToolTest {
 protected:
  FieldsBlock() : ToolTest("tomodem-fields-e2e") {}
};

/// Largest |a - b| over a dataset, and the largest |b|.
std::pair<double, double> difference(const std::vector<double>& a, const std::vector<double>& b) {
  double d = 0, scale = 0;
  for (std::size_t k = 0; k < std::min(a.size(), b.size()); ++k)
    d = std::max(d, std::abs(a[k] - b[k])), scale = std::max(scale, std::abs(b[k]));
  return {d, scale};
}
}  // namespace

TEST_F(FieldsBlock, WorkedExampleOfTheDocsRunsAsWritten) {
  std::ifstream in(std::string(TOMODEM_SOURCE_DIR) + "/docs/cg.md");
  std::stringstream s;
  s << in.rdbuf();
  const std::string doc = s.str();
  const std::string yaml = test::block_after(doc, "<!-- fields block example -->", "yaml");
  const std::string cmds = test::block_after(doc, "<!-- fields block example -->", "sh");
  ASSERT_FALSE(yaml.empty());
  ASSERT_FALSE(cmds.empty());
  std::ofstream(path("lattice.yaml")) << yaml;
  std::istringstream lines(cmds);
  std::string line;
  int n = 0;
  while (std::getline(lines, line)) {
    if (line.rfind("build/bin/", 0) != 0) continue;
    const std::string cmd = bin(line.substr(10));
    ASSERT_EQ(sh(cmd), 0) << cmd << "\n" << text("stderr.txt");
    ++n;
  }
  EXPECT_EQ(n, 2);
  // The summary keys of the block; five snapshots (steps 0, 50, ..., 200), time-averaged.
  const auto d = json("out/dem.json");
  ASSERT_TRUE(d.contains("fields")) << d.dump(1);
  const auto& f = d["fields"];
  for (const char* k : {"n_points", "snapshots", "mass_error", "divergence_residual", "width_m", "kernel", "state"})
    EXPECT_TRUE(f.contains(k)) << k;
  EXPECT_EQ(f["snapshots"].get<int>(), 5);
  EXPECT_EQ(d["outputs"]["fields"], "out/fields.h5");
  // The numbers the page quotes.
  EXPECT_EQ(f["n_points"].get<int>(), 14 * 14 * 14);
  EXPECT_LT(std::abs(f["mass_error"].get<double>()), 3e-4);
  EXPECT_LT(f["divergence_residual"].get<double>(), 1e-3);
  EXPECT_LT(f["mean_stress_difference"].get<double>(), 1e-4);
  // The static lattice: the block's time average is tomodem-cg's fields of the packing the run
  // wrote, dataset by dataset, to round-off.
  const auto c = json("out/cg.json");
  EXPECT_EQ(c["n_points"], f["n_points"]);
  EXPECT_EQ(c["width_m"], f["width_m"]);
  h5::File a(path("out/fields.h5"), h5::File::Mode::read), b(path("out/cg.h5"), h5::File::Mode::read);
  for (const char* ds : {"/grid/points", "/fields/density", "/fields/stress", "/fields/stress_contact",
                         "/fields/stress_bond", "/fields/divergence_static_stress"}) {
    const auto va = a.read_double(ds), vb = b.read_double(ds);
    ASSERT_EQ(va.size(), vb.size()) << ds;
    const auto [diff, scale] = difference(va, vb);
    EXPECT_LE(diff, 1e-9 * scale + 1e-300) << ds << ": " << diff << " of " << scale;
  }
  // The lattice moves by round-off only (its velocities are ~1e-12 m/s, a different 1e-12 at each
  // snapshot): velocity, momentum and kinetic stress are zero to round-off in both files.
  const double rho = difference(a.read_double("/fields/density"), b.read_double("/fields/density")).second;
  const double sigma = difference(a.read_double("/fields/stress"), b.read_double("/fields/stress")).second;
  for (const auto& [ds, zero] : std::vector<std::pair<const char*, double>>{
           {"/fields/velocity", 1e-9}, {"/fields/momentum", 1e-9 * rho}, {"/fields/stress_kinetic", 1e-12 * sigma}}) {
    const auto va = a.read_double(ds), vb = b.read_double(ds);
    ASSERT_EQ(va.size(), vb.size()) << ds;
    EXPECT_LE(difference(va, vb).first, zero) << ds;
    EXPECT_LE(difference(va, std::vector<double>(va.size(), 0.0)).first, zero) << ds;
  }
  // The contact stress is the lattice's: compressive, the same on the diagonal, and not zero.
  const auto sc = a.read_double("/fields/stress_contact");
  EXPECT_LT(sc[0], 0);
  EXPECT_NEAR(sc[4] / sc[0], 1.0, 1e-6);
  EXPECT_TRUE(a.has_attr("/", "state"));
  EXPECT_NE(a.attr_string("/", "state").find("time average of 5 snapshots"), std::string::npos);
  EXPECT_EQ(a.attr_string("/", "tool"), "tomodem-dem");
}

TEST_F(FieldsBlock, YoungFieldsOfAUniformLatticeAreTheLoveStressAndTheImposedStrain) {
  // A simple cubic lattice bonded to its 6 neighbours: under uniaxial stress along z its lateral
  // strains are 0 (no bond couples the axes), each z bond carries k_n ε a, so σ_zz = k_n ε / a =
  // E ε exactly (the (1 + ε) of the branch and of the volume cancel). The CG displacement of the
  // affine field u = (I - F⁻¹)(x - c) gives the strain 1 - 1/(1 + ε) at every node.
  mechanics::Network net;
  net.packing = mechanics::test::lattice("simple_cubic", 6, 1e-3, 0.5e-3);
  mechanics::test::bond_ratio(net, 0.2);
  mechanics::write_network(path("lattice.h5"), net);
  ASSERT_EQ(sh(bin("tomodem-young") + " lattice.h5 --json y.json --fields f.h5 --fields-width 1.5 --fields-cutoff 6 "
                                      "--fields-vdb f.vdb -q"),
            0)
      << text("stderr.txt");
  const auto y = json("y.json");
  const double E = y["E"], eps = 1e-4;  // --strain's default
  ASSERT_TRUE(y.contains("fields"));
  EXPECT_EQ(y["fields"]["snapshots"], 1);
  EXPECT_EQ(y["outputs"]["fields"], "f.h5");
  EXPECT_TRUE(fs::exists(path("f.xdmf")) && fs::exists(path("f.vdb")));
  h5::File f(path("f.h5"), h5::File::Mode::read);
  EXPECT_NE(f.attr_string("/", "state").find("uniaxial stress along z"), std::string::npos);
  const auto sigma = f.read_double("/fields/stress"), strain = f.read_double("/fields/strain");
  const auto interior = f.read_uint8("/fields/interior");
  const auto& love = y["fields"]["love_static_stress_Pa"];
  EXPECT_NEAR(love[2][2].get<double>() / (E * eps), 1.0, 1e-9);
  const std::size_t N = sigma.size() / 9;
  ASSERT_GT(N, 0u);
  double worst_stress = 0, worst_strain = 0, worst_other = 0;
  for (std::size_t k = 0; k < N; ++k) {
    if (!interior[k]) continue;
    worst_stress = std::max(worst_stress, std::abs(sigma[9 * k + 8] / (E * eps) - 1));
    for (int c = 0; c < 8; ++c) worst_other = std::max(worst_other, std::abs(sigma[9 * k + c]) / (E * eps));
    worst_strain = std::max(worst_strain, std::abs(strain[9 * k + 8] / (1 - 1 / (1 + eps)) - 1));
    EXPECT_NEAR(strain[9 * k + 8], eps, 2e-4 * eps);  // the imposed strain, to its own square
    for (int c = 0; c < 8; ++c) EXPECT_LT(std::abs(strain[9 * k + c]), 1e-6 * eps);
  }
  EXPECT_LT(worst_stress, 1e-6);
  EXPECT_LT(worst_other, 1e-6);
  EXPECT_LT(worst_strain, 1e-6);
}

TEST_F(FieldsBlock, FractureFieldsAreThePeakState) {
  mechanics::write_network(path("net.h5"), mechanics::test::slab(12, 3, 18, 11));
  ASSERT_EQ(sh(bin("tomodem-fracture") + " net.h5 --a-over-w 0.2 --stop-fraction 0.5 --no-elastic --json out.json "
                                         "--fields f.h5 -q"),
            0)
      << text("stderr.txt");
  const auto j = json("out.json");
  ASSERT_TRUE(j.contains("fields"));
  const auto& fj = j["fields"];
  for (const char* k : {"n_points", "snapshots", "mass_error", "divergence_residual", "state", "peak_opening_m"})
    EXPECT_TRUE(fj.contains(k)) << k;
  h5::File f(path("f.h5"), h5::File::Mode::read);
  EXPECT_NE(f.attr_string("/", "state").find("peak load"), std::string::npos);
  // The state is the peak's: its grip force is the peak load, its opening the peak opening.
  const double peak_force = j["sla"]["peak_force"], peak_opening = j["sla"]["peak_opening"];
  EXPECT_NEAR(std::stod(f.attr_string("/", "grip_force_of_the_state_N")) / peak_force, 1.0, 1e-3);
  EXPECT_NEAR(std::stod(f.attr_string("/", "peak_opening_m")) / peak_opening, 1.0, 1e-3);
  // The displacement along z (the load) lies between the grips': 0 and the opening.
  const auto u = f.read_double("/fields/displacement");
  double umin = 1e300, umax = -1e300;
  for (std::size_t k = 0; k < u.size() / 3; ++k) umin = std::min(umin, u[3 * k + 2]), umax = std::max(umax, u[3 * k + 2]);
  EXPECT_GE(umin, -0.05 * peak_opening);
  EXPECT_LE(umax, peak_opening * (1 + 1e-6));
  EXPECT_GT(umax, 0.5 * peak_opening);
  // Tension across the ligament: the mean bond stress σ_zz is positive.
  const auto sb = f.read_double("/fields/stress_bond");
  double zz = 0;
  for (std::size_t k = 0; k < sb.size() / 9; ++k) zz += sb[9 * k + 8];
  EXPECT_GT(zz, 0);
}
