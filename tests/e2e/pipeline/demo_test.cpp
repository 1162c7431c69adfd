// The demo pipeline (pipelines/demo.yaml) end to end, small: the real scan, a 400-particle
// packing and two neck ratios, run in a copy of the pipeline so the source tree stays clean.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <sstream>

#include "../../unit/pipeline/scratch.hpp"
#include "tomodem/core/plot.hpp"

using tomodem::test::Scratch;
namespace fs = std::filesystem;

namespace {
const std::string kBin = TOMODEM_BIN_DIR;

int run(const Scratch& s, const std::string& args) {
  const std::string cmd = "cd '" + s.dir + "' && OMP_WAIT_POLICY=PASSIVE '" + kBin + "/tomodem-run' " + args +
                          " > .stdout 2> .stderr";
  const int st = std::system(cmd.c_str());
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

// table.csv as one map column -> value per row.
std::vector<std::map<std::string, std::string>> table(const std::string& text) {
  std::istringstream in(text);
  std::string line;
  std::vector<std::string> head;
  std::getline(in, line);
  std::istringstream h(line);
  for (std::string c; std::getline(h, c, ',');) head.push_back(c);
  std::vector<std::map<std::string, std::string>> rows;
  while (std::getline(in, line)) {
    std::istringstream l(line);
    std::map<std::string, std::string> r;
    std::size_t k = 0;
    for (std::string c; std::getline(l, c, ',') && k < head.size(); ++k) r[head[k]] = c;
    rows.push_back(r);
  }
  return rows;
}
}  // namespace

TEST(Demo, SmallDemoRunsEveryToolThenNothingOnASecondRun) {
  for (const char* tool : {"segment", "pack", "carve", "bond", "young", "fracture", "conduct"}) {
    const std::string exe = kBin + "/tomodem-" + tool;
    const bool wired = std::system(("grep -q 'tool: " + std::string(tool) + "' '" + TOMODEM_SOURCE_DIR +
                                    "/pipelines/demo.yaml'").c_str()) == 0;
    if (wired && ::access(exe.c_str(), X_OK) != 0) GTEST_SKIP() << "tomodem-" << tool << " is not built";
  }
  // The README's install script installs gnuplot: a missing one is a broken install, not a skip.
  ASSERT_TRUE(tomodem::plotting_available()) << "gnuplot is not installed (Debian package gnuplot-nox)";
  Scratch s;
  fs::copy_file(std::string(TOMODEM_SOURCE_DIR) + "/pipelines/demo.yaml", s.path("demo.yaml"));
  fs::copy(std::string(TOMODEM_SOURCE_DIR) + "/pipelines/demo", s.path("demo"), fs::copy_options::recursive);
  const std::string args = "demo.yaml -j 2 --set scan=" + std::string(TOMODEM_TEST_DATA) +
                           "/soil-sand-xct/corner100.mhd --set out=out --set particles=400 --set 'necks=[0.1,0.3]'";
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_EQ(run(s, args + " --json summary.json"), 0) << s.read(".stderr");
  std::cout << "small demo: " << std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()
            << " s\n";
  EXPECT_NE(s.read(".stderr").find("done report"), std::string::npos) << s.read(".stderr");  // progress shown
  const auto rows = table(s.read("out/report/table.csv"));
  ASSERT_EQ(rows.size(), 2u);
  for (const char* f : {"index.html", "stiffness.png", "stiffness.svg", "conductivity.png", "conductivity.svg"})
    EXPECT_TRUE(fs::exists(s.path(std::string("out/report/") + f))) << f;
  // One network, two neck radii. Every edge of the resistor network is a bond of conductance
  // 2 sigma a (docs/conduct.md), linear in a, so sigma_eff scales exactly with the neck ratio:
  // 0.3 / 0.1 = 3, up to the CG tolerance of the two solves (1e-4 is far above it).
  const double s1 = std::stod(rows[0].at("sigma_rel_x")), s3 = std::stod(rows[1].at("sigma_rel_x"));
  EXPECT_NEAR(s3 / s1, 3.0, 3e-4) << s1 << " " << s3;
  // E grows with the neck: bond stiffnesses rise as a (normal, shear) and a^3 (bending).
  EXPECT_GT(std::stod(rows[1].at("E_rel")), std::stod(rows[0].at("E_rel")));
  EXPECT_EQ(rows[0].at("neck_ratio"), "0.1");
  // Nothing changed: nothing runs.
  ASSERT_EQ(run(s, args + " --json again.json"), 0) << s.read(".stderr");
  EXPECT_NE(s.read("again.json").find("\"ran\": 0"), std::string::npos) << s.read("again.json");
}
