// tomodem-dem from the command line: summaries, bad input (exit 2, no output), restart.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "../common/tool_test.hpp"
#include "tomodem/core/h5.hpp"
#include "tomodem/core/packing_io.hpp"

namespace fs = std::filesystem;

namespace {

struct Result {
  int code;
  std::string err;
};

class DemCli : public tomodem::test::ToolTest {
 protected:
  DemCli() : ToolTest("tomodem_dem_cli") {}

  std::string write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p.string();
  }
  Result run(const std::string& args) {
    const int code = sh(bin("tomodem-dem") + " " + args + " -q");
    return {code, text("stderr.txt")};
  }
  /// Files in the output folder other than the scene inputs and captured streams.
  int outputs(const std::string& out) {
    int n = 0;
    if (!fs::exists(out)) return 0;
    for (const auto& e : fs::directory_iterator(out)) (void)e, ++n;
    return n;
  }
};

// A small periodic FCC packing, compressed so that contacts exist (Hertz–Mindlin).
const char* kScene = R"(materials:
  - {name: glass, youngs_modulus: 1.0e8, poisson_ratio: 0.25, density: 2500}
particles:
  generate: {arrangement: fcc, cells: 4, radius: 0.5e-3, solid_fraction: 0.76, velocity: 0.05, seed: 3, phase: glass}
physics: {normal: hertz, tangential: mindlin, restitution: 0.5, friction: 0.5}
protocol: {timestep: auto, steps: 400, output_interval: 100}
output: {packing: out.h5, series: series.csv, checkpoint: ck.h5}
)";

std::string replace(std::string s, const std::string& from, const std::string& to) {
  const auto k = s.find(from);
  EXPECT_NE(k, std::string::npos) << from;
  if (k != std::string::npos) s.replace(k, from.size(), to);
  return s;
}

}  // namespace

TEST_F(DemCli, SummaryHasTheDocumentedKeysInSIUnits) {
  const std::string scene = write("scene.yaml", kScene);
  const std::string out = (dir_ / "out").string();
  ASSERT_EQ(run(scene + " --output-dir " + out + " --json " + out + "/summary.json").code, 0);
  std::ifstream in(out + "/summary.json");
  const auto j = nlohmann::json::parse(in);
  for (const char* key : {"steps", "wall_time_s", "particle_steps_per_second", "threads", "stress", "coordination",
                          "kinetic_energy", "pressure"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["steps"].get<long>(), 400);
  EXPECT_EQ(j["stress"].size(), 3u);
  // Pressure = -tr(stress)/3 by definition; the FCC packing at φ = 0.76 > 0.7405 is compressed.
  const double p = j["pressure"].get<double>();
  const double tr = j["stress"][0][0].get<double>() + j["stress"][1][1].get<double>() + j["stress"][2][2].get<double>();
  EXPECT_NEAR(p, -tr / 3, 1e-9 * std::abs(p));
  EXPECT_GT(p, 0);
  EXPECT_GT(j["coordination"].get<double>(), 11.0);  // FCC: 12 neighbours
  EXPECT_TRUE(fs::exists(out + "/out.h5"));
  EXPECT_TRUE(fs::exists(out + "/out.xdmf"));
  EXPECT_TRUE(fs::exists(out + "/series.csv"));
  // The packing file holds contacts with their forces: Σ over contacts of F ⊗ l matches the stress.
  const tomodem::Packing pk = tomodem::read_packing(out + "/out.h5");
  EXPECT_GT(pk.contacts.size(), 0u);
  EXPECT_EQ(pk.contacts.normal_force.size(), pk.contacts.size());
}

TEST_F(DemCli, RestartReproducesTheUninterruptedRunBitForBit) {
  const std::string scene = write("scene.yaml", kScene);
  const std::string full = (dir_ / "full").string(), half = (dir_ / "half").string(), rest = (dir_ / "rest").string();
  ASSERT_EQ(run(scene + " --output-dir " + full).code, 0);
  ASSERT_EQ(run(scene + " --output-dir " + half + " --steps 200").code, 0);
  ASSERT_EQ(run(scene + " --output-dir " + rest + " --restart " + half + "/ck.h5").code, 0);
  const tomodem::Packing a = tomodem::read_packing(full + "/out.h5");
  const tomodem::Packing b = tomodem::read_packing(rest + "/out.h5");
  ASSERT_EQ(a.particles.size(), b.particles.size());
  for (std::size_t i = 0; i < a.particles.size(); ++i) {
    EXPECT_EQ(a.particles.position[i].x, b.particles.position[i].x) << i;  // exact, not near
    EXPECT_EQ(a.particles.velocity[i].y, b.particles.velocity[i].y) << i;
    EXPECT_EQ(a.particles.angular_velocity[i].z, b.particles.angular_velocity[i].z) << i;
  }
}

// Each malformed scene: exit code 2, a message naming the file, the field and the value,
// and no output in the output folder.
struct BadCase {
  const char* name;
  std::string scene;
  std::string expect_field, expect_value;
};

TEST_F(DemCli, BadInputExitsWithCode2AndLeavesNoOutput) {
  const std::string base = kScene;
  const std::vector<BadCase> cases = {
      {"bad_yaml", "materials: [unclosed\n", "line", ""},
      {"unknown_key", replace(base, "protocol: {", "protocol: {frobnicate: 3, "), "protocol.frobnicate", "frobnicate"},
      {"unknown_physics", replace(base, "normal: hertz", "normal: hertzz"), "physics.normal", "hertzz"},
      {"negative_radius", replace(base, "radius: 0.5e-3", "radius: -0.5e-3"), "radius", "-0.5e-3"},
      {"nan_radius", replace(base, "radius: 0.5e-3", "radius: .nan"), "radius", ".nan"},
      {"missing_file", replace(base, "generate: {arrangement: fcc, cells: 4, radius: 0.5e-3, solid_fraction: 0.76, "
                                     "velocity: 0.05, seed: 3, phase: glass}",
                               "file: nowhere.h5"),
       "nowhere.h5", ""},
      {"overlap", replace(base, "solid_fraction: 0.76", "solid_fraction: 0.76, spacing: 0.4e-3"), "particles.position", ""},
      {"timestep_too_large", replace(base, "timestep: auto", "timestep: 1.0"), "protocol.timestep", "1.0"},
  };
  for (const auto& c : cases) {
    const std::string scene = write(std::string(c.name) + ".yaml", c.scene);
    const std::string out = (dir_ / (std::string("out_") + c.name)).string();
    const Result r = run(scene + " --output-dir " + out);
    EXPECT_EQ(r.code, 2) << c.name << ": " << r.err;
    EXPECT_NE(r.err.find(c.expect_field), std::string::npos) << c.name << ": " << r.err;
    if (!c.expect_value.empty()) EXPECT_NE(r.err.find(c.expect_value), std::string::npos) << c.name << ": " << r.err;
    if (std::string(c.name) != "missing_file")
      EXPECT_NE(r.err.find(scene), std::string::npos) << c.name << " does not name the file: " << r.err;
    EXPECT_EQ(outputs(out), 0) << c.name << " left output behind";
  }
}

TEST_F(DemCli, HelpAndVersion) {
  EXPECT_EQ(run("--help").code, 0);
  EXPECT_EQ(run("--version").code, 0);
  EXPECT_EQ(run("--no-such-flag").code, 2);
}

// --list-laws prints the registry's table, the one docs/dem.md holds between its markers.
TEST_F(DemCli, ListLawsPrintsTheDocsTable) {
  ASSERT_EQ(run("--list-laws").code, 0);
  std::ifstream out(dir_ / "stdout.txt"), doc(fs::path(TOMODEM_SOURCE_DIR) / "docs" / "dem.md");
  std::stringstream o, d;
  o << out.rdbuf();
  d << doc.rdbuf();
  const std::string begin = "<!-- law table: generated by tomodem-dem --list-laws -->\n";
  const auto b = d.str().find(begin), e = d.str().find("<!-- end of law table -->");
  ASSERT_TRUE(b != std::string::npos && e != std::string::npos);
  EXPECT_EQ(o.str(), d.str().substr(b + begin.size(), e - b - begin.size()));
  EXPECT_NE(o.str().find("| normal | `luding` |"), std::string::npos);
}
