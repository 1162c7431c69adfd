// tomodem-dem started by mpirun on 1, 2 and 3 ranks against the same scene run without mpirun
// (docs/dem.md, "Running on several ranks"). This test is not itself an MPI program: it starts
// the tool, as a user would, and compares the files and summaries it writes.
//
// What must be equal, and why:
//  - the final particles (positions, velocities, spins) and the contact table (pairs, overlaps,
//    forces), bit for bit: with one thread per rank the decomposed engine sums each particle's
//    contacts in the serial order (tests/mpi/dem/test_decomposition.cpp shows the engine side);
//  - counts (contacts, coordination, steps, rebuilds), exactly;
//  - sums over the whole cell (stress, energies, unbalanced-force ratio): the ranks' parts are
//    added in rank order, not in the serial order, so they agree to round-off: relative 1e-12,
//    the reordering bound n·ε of a sum of n ~ 10^3 same-sign terms (ε = 2.2e-16) with margin;
//    the CSV prints 10 significant digits, so its text is compared to 1e-9 of the value.
// A scene with what is not decomposed yet is refused on 2 ranks with exit 2, one message, and
// no output folder.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tomodem/core/packing_io.hpp"

namespace fs = std::filesystem;
using json = nlohmann::json;
using tomodem::Packing;
using tomodem::read_packing;

namespace {

const std::string kDem = std::string(TOMODEM_BIN_DIR) + "/tomodem-dem";

struct Ran {
  int code = -1;
  std::string out, err;
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Runs a tool with stdout and stderr captured; ranks 0: without mpirun.
Ran run_tool(const std::string& exe, const fs::path& dir, int ranks, const std::string& args) {
  const std::string launch = ranks > 0 ? std::string(TOMODEM_MPIEXEC) + " --oversubscribe -np " + std::to_string(ranks) + " " : "";
  const std::string cmd = "cd '" + dir.string() + "' && OMP_NUM_THREADS=1 OMPI_ALLOW_RUN_AS_ROOT=1 "
                          "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 " + launch + exe + " " + args + " >stdout.txt 2>stderr.txt";
  Ran r;
  const int st = std::system(cmd.c_str());
  r.code = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  r.out = slurp(dir / "stdout.txt");
  r.err = slurp(dir / "stderr.txt");
  return r;
}
Ran run(const fs::path& dir, int ranks, const std::string& args) { return run_tool(kDem, dir, ranks, args); }

/// Scene A of docs/dem.md at 12³ spheres (the lattice planes fall on the sub-domain faces of 2
/// and 3 ranks, so particles migrate from the first steps), a small skin so the list is rebuilt
/// every few steps, and optionally the cell sheared (the affine field and image velocities).
std::string scene(bool sheared, const std::string& extra = "") {
  std::string s = R"(materials:
  - {name: glass, youngs_modulus: 1.0e8, poisson_ratio: 0.25, density: 2500}
particles:
  generate: {arrangement: simple_cubic, cells: 12, radius: 0.5e-3, spacing: 0.9837e-3, jitter: 0.015, velocity: 0.1, seed: 3, phase: glass}
physics: {normal: hertz, tangential: mindlin, restitution: 0.5, friction: 0.5}
protocol: {timestep: 1.35e-6, steps: 300, output_interval: 50}
settings: {skin: 2.0e-5, threads: 1)" + extra + R"(}
output: {packing: out.h5, series: series.csv}
)";
  if (sheared) s += "boundary: {strain_rate: {xy: 40.0}}\n";
  return s;
}

std::vector<std::vector<double>> csv(const fs::path& p) {
  std::ifstream in(p);
  std::string line;
  std::getline(in, line);  // header
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::stringstream s(line);
    std::string cell;
    while (std::getline(s, cell, ',')) row.push_back(std::stod(cell));
    rows.push_back(row);
  }
  return rows;
}

bool same_bits(const tomodem::Vec3& a, const tomodem::Vec3& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

void near_relative(double a, double b, double rel, const std::string& what) {
  EXPECT_LE(std::abs(a - b), rel * std::max(std::abs(a), std::abs(b)) + 1e-300) << what << ": " << a << " vs " << b;
}

class DemToolOnRanks : public ::testing::TestWithParam<bool> {};

TEST_P(DemToolOnRanks, OutputsEqualTheSerialRun) {
  const bool sheared = GetParam();
  const fs::path root = fs::temp_directory_path() / ("tomodem_dem_tool_ranks_" + std::to_string(::getpid()) + (sheared ? "_shear" : "_a"));
  fs::remove_all(root);
  fs::create_directories(root);
  std::ofstream(root / "scene.yaml") << scene(sheared);

  const Ran serial = run(root, 0, "scene.yaml --output-dir serial --json serial.json -q");
  ASSERT_EQ(serial.code, 0) << serial.err;
  const tomodem::Packing ref = tomodem::read_packing((root / "serial/out.h5").string());
  const json jref = json::parse(slurp(root / "serial.json"));
  const auto ref_rows = csv(root / "serial/series.csv");
  ASSERT_EQ(ref_rows.size(), 7u);  // steps 0, 50, ..., 300
  ASSERT_GT(ref.contacts.size(), 5000u);

  for (int ranks : {1, 2, 3}) {
    SCOPED_TRACE(std::to_string(ranks) + " ranks" + (sheared ? ", sheared cell" : ""));
    const std::string dir = "r" + std::to_string(ranks);
    const Ran r = run(root, ranks, "scene.yaml --output-dir " + dir + " --json " + dir + ".json -q");
    ASSERT_EQ(r.code, 0) << r.err;
    const tomodem::Packing got = tomodem::read_packing((root / dir / "out.h5").string());
    const auto& P = ref.particles;
    const auto& Q = got.particles;
    ASSERT_EQ(P.position.size(), Q.position.size());
    long differ = 0;
    for (std::size_t i = 0; i < P.position.size(); ++i)
      differ += !same_bits(P.position[i], Q.position[i]) || !same_bits(P.velocity[i], Q.velocity[i]) ||
                !same_bits(P.angular_velocity[i], Q.angular_velocity[i]) || P.radius[i] != Q.radius[i];
    EXPECT_EQ(differ, 0) << "particles not bitwise the serial ones";
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) EXPECT_EQ(ref.cell.h(a, b), got.cell.h(a, b));
    ASSERT_EQ(ref.contacts.size(), got.contacts.size());
    long cdiff = 0;
    for (std::size_t c = 0; c < ref.contacts.size(); ++c)
      cdiff += ref.contacts.i[c] != got.contacts.i[c] || ref.contacts.j[c] != got.contacts.j[c] ||
               ref.contacts.overlap[c] != got.contacts.overlap[c] ||
               !same_bits(ref.contacts.normal_force[c], got.contacts.normal_force[c]) ||
               !same_bits(ref.contacts.tangential_force[c], got.contacts.tangential_force[c]);
    EXPECT_EQ(cdiff, 0) << "contact table not bitwise the serial one";
    // The whole series, at full precision, from the packing's results.
    const auto& sref = ref.results.series.at("dem");
    const auto& sgot = got.results.series.at("dem");
    ASSERT_EQ(sref.size(), sgot.size());
    for (const auto& [name, col] : sref) {
      const auto& g = sgot.at(name);
      ASSERT_EQ(col.size(), g.size()) << name;
      for (std::size_t k = 0; k < col.size(); ++k) near_relative(col[k], g[k], 1e-12, name + "[" + std::to_string(k) + "]");
    }
    const auto rows = csv(root / dir / "series.csv");
    ASSERT_EQ(rows.size(), ref_rows.size());
    for (std::size_t k = 0; k < rows.size(); ++k)
      for (std::size_t c = 0; c < rows[k].size(); ++c) near_relative(ref_rows[k][c], rows[k][c], 1e-9, "series.csv row " + std::to_string(k));
    const json j = json::parse(slurp(root / (dir + ".json")));
    for (const char* k : {"n_particles", "steps", "step", "contacts", "coordination", "neighbor_rebuilds", "stop_reason"})
      EXPECT_EQ(j.at(k), jref.at(k)) << k;
    for (const char* k : {"pressure", "kinetic_energy", "elastic_energy", "unbalanced_force_ratio", "time_step_s", "critical_time_step_s"})
      near_relative(jref.at(k).get<double>(), j.at(k).get<double>(), 1e-12, k);
    if (ranks > 1) EXPECT_EQ(j.at("ranks"), ranks);
    // One summary, from rank 0 only (it went to the --json file: nothing on stdout).
    EXPECT_EQ(r.out, "");
  }
  fs::remove_all(root);
}

INSTANTIATE_TEST_SUITE_P(SceneA, DemToolOnRanks, ::testing::Values(false, true),
                         [](const auto& info) { return info.param ? std::string("ShearedCell") : std::string("Still"); });

TEST(DemToolOnRanks, WhatIsNotDecomposedIsRefusedOnceWithNothingWritten) {
  const fs::path root = fs::temp_directory_path() / ("tomodem_dem_tool_refused_" + std::to_string(::getpid()));
  fs::remove_all(root);
  fs::create_directories(root);
  // Walls and track_energy are decomposed (test_walls_decomposed.cpp). Too many ranks for the
  // sample (3 sub-domains along a 3-sphere cell): refused, named, by one rank, nothing written.
  std::string tiny = scene(false);
  tiny.replace(tiny.find("cells: 12"), 9, "cells: 3");
  std::ofstream(root / "tiny.yaml") << tiny;
  const Ran t = run(root, 3, "tiny.yaml --output-dir out --json out.json");
  EXPECT_EQ(t.code, 2) << t.err;
  const std::string msg = "tiny.yaml: field 'mpirun -np': value '3 (3x1x1)'";
  const std::size_t at = t.err.find(msg);
  EXPECT_NE(at, std::string::npos) << t.err;
  if (at != std::string::npos) EXPECT_EQ(t.err.find(msg, at + 1), std::string::npos) << "said by more than one rank:\n" << t.err;
  EXPECT_FALSE(fs::exists(root / "out"));
  EXPECT_FALSE(fs::exists(root / "out.json"));
  // Checkpoints on ranks are written and read (test_checkpoint_ranks.cpp).
  fs::remove_all(root);
}

// tomodem-sinter with snapshots on 2 ranks against the run without mpirun: 256 alumina spheres (the
// worked example of docs/sintering.md at 4³ FCC cells) from 0.74, a snapshot at 0.75, stop at 0.77.
// Every rank takes the snapshot at the same step (the density is a sum in id order on any rank
// count), so the step, the neck pairs and the counts are equal; positions and neck radii agree to
// round-off (the cell servo reads a stress summed in rank order: 1e-9 relative, as the engine test
// dem_decomposition_sinter_tests bounds the whole run).
TEST(DemToolOnRanks, SinteringSnapshotsEqualTheSerialRun) {
  const fs::path root = fs::temp_directory_path() / ("tomodem_sinter_ranks_" + std::to_string(::getpid()));
  fs::remove_all(root);
  const std::string kSinter = std::string(TOMODEM_BIN_DIR) + "/tomodem-sinter";
  const std::string scene = R"(materials:
  - {name: alumina, youngs_modulus: 380.0e9, poisson_ratio: 0.22, density: 3950, surface_energy: 1.0}
particles:
  generate: {arrangement: fcc, cells: 4, radius: 1.0e-6, spacing: 2.82277e-6, jitter: 0.01, phase: alumina}
physics: {normal: sintering, tangential: none}
settings: {threads: 1}
sintering:
  temperature:
    start: 300
    segments: [{rate: 50, to: 1600}, {hold: 5000}]
  phases:
    - {material: alumina, atomic_volume: 8.47e-30, boundary_diffusion: 8.6e-10,
       activation_energy: 418.0e3, dihedral_angle: 150}
  stop: {relative_density: 0.77}
)";
  Packing snap[2];
  json summary[2];
  for (int k = 0; k < 2; ++k) {
    const fs::path dir = root / (k == 0 ? "serial" : "ranks");
    fs::create_directories(dir);
    std::ofstream(dir / "alumina.yaml") << scene;
    const Ran r = run_tool(kSinter, dir, 2 * k, "alumina.yaml --output-dir out --snapshots-at 0.75 --no-plot --json out/summary.json");
    ASSERT_EQ(r.code, 0) << r.err;
    summary[k] = json::parse(slurp(dir / "out/summary.json"));
    snap[k] = read_packing((dir / "out/snapshot-0.75.h5").string());
  }
  const json& a = summary[0]["snapshots"][0];
  const json& b = summary[1]["snapshots"][0];
  EXPECT_EQ(a["step"], b["step"]);
  EXPECT_EQ(a["bonds"], b["bonds"]);
  EXPECT_GT(a["bonds"].get<int>(), 500);  // necks grew between most neighbours
  EXPECT_NEAR(b["relative_density"].get<double>() / a["relative_density"].get<double>(), 1.0, 1e-9);
  ASSERT_EQ(snap[0].particles.size(), 256u);
  ASSERT_EQ(snap[1].particles.size(), snap[0].particles.size());
  for (std::size_t i = 0; i < snap[0].particles.size(); ++i) {
    const tomodem::Vec3 d = snap[1].particles.position[i] - snap[0].particles.position[i];
    EXPECT_LT(std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z), 1e-9 * snap[0].particles.radius[i]) << "particle " << i;
    EXPECT_NEAR(snap[1].particles.radius[i] / snap[0].particles.radius[i], 1.0, 1e-9) << "particle " << i;
  }
  ASSERT_EQ(snap[1].bonds.size(), snap[0].bonds.size());
  for (std::size_t n = 0; n < snap[0].bonds.size(); ++n) {
    EXPECT_EQ(snap[1].bonds.i[n], snap[0].bonds.i[n]);
    EXPECT_EQ(snap[1].bonds.j[n], snap[0].bonds.j[n]);
    EXPECT_NEAR(snap[1].bonds.radius[n] / snap[0].bonds.radius[n], 1.0, 1e-9) << "neck " << n;
  }
  fs::remove_all(root);
}

TEST(DemToolOnRanks, VersionSaysMpi) {
  const fs::path root = fs::temp_directory_path();
  const Ran r = run(root, 0, "--version");
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("\nfeatures: openmp mpi petsc\n"), std::string::npos) << r.out;
}

}  // namespace
