// tomodem-sinter from the command line: outputs and summary keys of a small free-sintering run,
// and bad input (exit 2 with file, field and value).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "tomodem/core/packing_io.hpp"

namespace fs = std::filesystem;

namespace {

struct Result {
  int code;
  std::string out, err;
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// 32 alumina spheres (FCC, 2³ cells, nearest neighbours overlapping by 0.2 % of d), heated at
// 50 K/s to 1600 K and held; stops at relative density 0.78.
const std::string kScene = R"(materials:
  - {name: alumina, youngs_modulus: 380.0e9, poisson_ratio: 0.22, density: 3950, surface_energy: 1.0}
particles:
  generate: {arrangement: fcc, cells: 2, radius: 1.0e-6, spacing: 2.82277e-6, jitter: 0.01, seed: 3, phase: alumina}
physics: {normal: sintering}
sintering:
  temperature:
    start: 300
    segments: [{rate: 50, to: 1600}, {hold: 5000}]
  phases:
    - {material: alumina, atomic_volume: 8.47e-30, boundary_diffusion: 8.6e-10, activation_energy: 418.0e3, dihedral_angle: 150}
  stop: {relative_density: 0.78}
)";

class SinterCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fs::temp_directory_path() / ("tomodem_sinter_cli_" + std::to_string(::getpid()) + "_" +
                                       ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  void TearDown() override { fs::remove_all(dir); }
  std::string write(const std::string& text) {
    const fs::path p = dir / "scene.yaml";
    std::ofstream(p) << text;
    return p.string();
  }
  Result run(const std::string& scene) {
    const std::string cmd = std::string(TOMODEM_BIN_DIR) + "/tomodem-sinter " + scene + " -o " + (dir / "out").string() +
                            " -q > " + (dir / "stdout.txt").string() + " 2> " + (dir / "stderr.txt").string();
    const int status = std::system(cmd.c_str());
    return {WEXITSTATUS(status), slurp(dir / "stdout.txt"), slurp(dir / "stderr.txt")};
  }
  /// Replaces the first occurrence of `what` in the scene.
  static std::string with(const std::string& what, const std::string& by) {
    std::string s = kScene;
    const auto at = s.find(what);
    EXPECT_NE(at, std::string::npos) << what;
    return s.replace(at, what.size(), by);
  }
  void expect_bad(const std::string& scene, const std::string& field, const std::string& value) {
    const Result r = run(write(scene));
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find("scene.yaml"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(field), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(value), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "out" / "sintered.h5"));
  }
  fs::path dir;
};

}  // namespace

TEST_F(SinterCli, FreeSinteringWritesCurvePackingWithNecksAndSummary) {
  const Result r = run(write(kScene));
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  for (const char* key : {"relative_density", "mean_neck_ratio", "sintering_time_s", "wall_time_s"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["stop_reason"], "target_density");
  EXPECT_GE(j["relative_density"].get<double>(), 0.78);
  EXPECT_LT(j["relative_density"].get<double>(), 0.79);
  EXPECT_GT(j["mean_neck_ratio"].get<double>(), 0.1);
  const std::string csv = slurp(dir / "out" / "densification.csv");
  EXPECT_EQ(csv.rfind("step,time_s,temperature_K,relative_density", 0), 0u) << csv.substr(0, 80);
  const tomodem::Packing p = tomodem::read_packing((dir / "out" / "sintered.h5").string());
  EXPECT_EQ(p.particles.size(), 32u);
  ASSERT_GT(p.bonds.size(), 100u);  // 12 neighbours each: 192 necks
  for (std::size_t b = 0; b < p.bonds.size(); ++b) {
    EXPECT_GT(p.bonds.radius[b], 0.05e-6);
    EXPECT_LT(p.bonds.radius[b], 1.0e-6);
    EXPECT_GT(p.bonds.rest_length[b], 1.0e-6);
  }
}

TEST_F(SinterCli, BadInputExitsTwoNamingFieldAndValue) {
  expect_bad(with("{rate: 50, to: 1600}", "{rate: -50, to: 1600}"), "segments[0].rate", "-50");
  expect_bad(with("start: 300", "start: -300"), "sintering.temperature.start", "-300");
  expect_bad(with(" boundary_diffusion: 8.6e-10,", ""), "boundary_diffusion", "missing");
  expect_bad(with("- {material: alumina,", "- {material: zirconia,"), "sintering.phases[0].material", "zirconia");
  expect_bad(with("relative_density: 0.78", "relative_density: 0.6"), "sintering.stop.relative_density", "0.6");
  expect_bad(with("to: 1600", "to: 700"), "sintering.temperature", "never reaches sintering temperatures");
  expect_bad(with("{normal: sintering}", "{normal: sintering, tangential: mindlin}"), "physics.tangential", "mindlin");
}
