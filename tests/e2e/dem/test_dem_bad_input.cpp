// tomodem-dem refuses bad input honestly (issue 16): exit 2, a message naming the file, the
// field (with its line) or option and the value, no output left behind, inputs unchanged.
// Corrupt checkpoints and --restart with changed physics are refused the same way; a restart
// continues the time series.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "../common/tool_test.hpp"
#include "bad_input_table.hpp"
#include "tomodem/core/h5.hpp"

namespace fs = std::filesystem;
using bad_input::Case;
using bad_input::with;

namespace {

const std::string kScene = R"(materials:
  - {name: glass, youngs_modulus: 1.0e8, poisson_ratio: 0.25, density: 2500}
particles:
  generate: {arrangement: fcc, cells: 2, radius: 0.5e-3, solid_fraction: 0.7, jitter: 0.01, seed: 3, phase: glass}
physics: {normal: hertz, tangential: mindlin, restitution: 0.5, friction: 0.5}
settings: {check_interval: 100, track_energy: false}
protocol: {timestep: auto, steps: 40, output_interval: 10}
output: {packing: out.h5, series: series.csv, checkpoint: ck.h5}
)";

const std::string kCell = "cell: {lower: [0, 0, 0], upper: [2.0e-3, 2.0e-3, 2.0e-3], periodic: true}\nsettings:";

/// A row whose scene is kScene with one mutation, run as `tomodem-dem scene.yaml --output-dir out`.
Case scene_row(const std::string& name, const std::string& from, const std::string& to,
               std::vector<std::string> needles) {
  needles.push_back("scene.yaml");
  return {name, {{"scene.yaml", with(kScene, from, to)}}, "scene.yaml --output-dir out", 2, needles};
}

}  // namespace

TEST(DemBadInput, EveryRowExits2NamingFileFieldAndValueAndWritesNothing) {
  const std::vector<Case> cases = {
      // YAML type errors: file:line and the field, never "bad conversion" (exit 1).
      scene_row("radius_text", "radius: 0.5e-3", "radius: abc", {"particles.generate.radius", "line 4", "abc", "number"}),
      scene_row("cells_list", "cells: 2", "cells: [1, 2]", {"particles.generate.cells", "line 4", "[1, 2]"}),
      scene_row("cells_fraction", "cells: 2", "cells: 2.5", {"particles.generate.cells", "2.5", "whole"}),
      scene_row("periodic_maybe", "settings:", kCell + "", {}),  // placeholder replaced below
      scene_row("periodic_list_maybe", "settings:", with(kCell, "periodic: true", "periodic: [true, maybe, true]"),
                {"cell.periodic[1]", "maybe", "true or false"}),
      scene_row("materials_map", "  - {name: glass,", "  {name: glass,", {"materials", "must be a list"}),
      scene_row("physics_list", "physics: {normal: hertz, tangential: mindlin, restitution: 0.5, friction: 0.5}",
                "physics: [hertz, mindlin]", {"physics", "line 5", "mapping"}),
      scene_row("name_list", "name: glass", "name: [glass]", {"materials[0].name", "text"}),
      scene_row("track_energy_maybe", "track_energy: false", "track_energy: maybe", {"settings.track_energy", "maybe"}),
      scene_row("pairs_phases_map", "friction: 0.5}", "friction: 0.5, pairs: [{phases: {a: b}}]}",
                {"physics.pairs[0].phases", "list"}),
      scene_row("gravity_two", "friction: 0.5}", "friction: 0.5, gravity: [0, 0]}", {"physics.gravity", "three numbers"}),
      // Protocol, settings and physics values: NaN, Inf, negative, zero where invalid.
      scene_row("check_interval_zero", "check_interval: 100", "check_interval: 0", {"settings.check_interval", "line 6", "0"}),
      scene_row("check_interval_negative", "check_interval: 100", "check_interval: -5", {"settings.check_interval", "-5"}),
      scene_row("threads_zero", "check_interval: 100", "check_interval: 100, threads: 0", {"settings.threads", "0"}),
      scene_row("restitution_nan", "restitution: 0.5", "restitution: .nan", {"physics.restitution", ".nan", "finite"}),
      scene_row("restitution_above_one", "restitution: 0.5", "restitution: 1.5", {"physics.restitution", "1.5", "[0.001, 1]"}),
      scene_row("restitution_tiny", "restitution: 0.5", "restitution: 1.0e-5", {"physics.restitution", "1.0e-5", "[0.001, 1]"}),
      scene_row("friction_negative", "friction: 0.5", "friction: -1", {"physics.friction", "-1"}),
      scene_row("friction_inf", "friction: 0.5", "friction: .inf", {"physics.friction", ".inf", "finite"}),
      scene_row("damping_ratio_one", "friction: 0.5}", "friction: 0.5, damping_ratio: 1}", {"physics.damping_ratio", "1"}),
      scene_row("local_damping_one", "friction: 0.5}", "friction: 0.5, local_damping: 1}", {"physics.local_damping", "[0, 1)"}),
      scene_row("poisson_half", "poisson_ratio: 0.25", "poisson_ratio: 0.5", {"materials[0].poisson_ratio", "0.5", "(-1, 0.5)"}),
      scene_row("poisson_minus_one", "poisson_ratio: 0.25", "poisson_ratio: -1", {"materials[0].poisson_ratio", "-1"}),
      scene_row("density_zero", "density: 2500", "density: 0", {"materials[0].density", "0"}),
      scene_row("youngs_negative", "youngs_modulus: 1.0e8", "youngs_modulus: -1.0e8", {"materials[0].youngs_modulus", "-1.0e8"}),
      scene_row("surface_energy_nan", "density: 2500", "density: 2500, surface_energy: .nan", {"materials[0].surface_energy", ".nan"}),
      scene_row("steps_negative", "steps: 40", "steps: -5", {"protocol.steps", "-5"}),
      scene_row("steps_fraction", "steps: 40", "steps: 1.5", {"protocol.steps", "1.5", "whole"}),
      scene_row("timestep_fraction_zero", "timestep: auto", "timestep: auto, timestep_fraction: 0",
                {"protocol.timestep_fraction", "(0, 1]"}),
      scene_row("timestep_fraction_two", "timestep: auto", "timestep: auto, timestep_fraction: 2", {"protocol.timestep_fraction", "2"}),
      scene_row("timestep_negative", "timestep: auto", "timestep: -1.0e-6", {"protocol.timestep", "-1.0e-6"}),
      scene_row("output_interval_negative", "output_interval: 10", "output_interval: -1", {"protocol.output_interval", "-1"}),
      scene_row("stop_negative", "output_interval: 10}", "output_interval: 10, stop: {unbalanced_force_ratio: -1}}",
                {"protocol.stop.unbalanced_force_ratio", "-1"}),
      scene_row("solid_fraction_above_one", "solid_fraction: 0.7", "solid_fraction: 1.5", {"solid_fraction", "1.5", "(0, 1)"}),
      scene_row("jitter_negative", "jitter: 0.01", "jitter: -0.1", {"generate.jitter", "-0.1"}),
      scene_row("seed_negative", "seed: 3", "seed: -1", {"generate.seed", "-1"}),
      // Resource requests: refused before allocation, with the need and what the machine has.
      scene_row("count_1e12", "arrangement: fcc, cells: 2", "arrangement: random, count: 1e12",
                {"particles.generate.count", "1e12", "memory", "this machine has"}),
      scene_row("fcc_1e5_cells", "cells: 2", "cells: 100000", {"particles.generate.cells", "100000", "memory"}),
      scene_row("steps_absurd_rows", "steps: 40, output_interval: 10", "steps: 1e15, output_interval: 1",
                {"protocol.output_interval", "memory", "time-series rows"}),
      scene_row("duration_absurd", "steps: 40", "duration: 1.0e30", {"protocol.duration", "1.0e30"}),
      // Outputs named in the scene stay inside the --output-dir folder, and do not collide.
      scene_row("packing_outside", "packing: out.h5", "packing: ../../x.h5", {"output.packing", "line 8", "../../x.h5"}),
      scene_row("series_absolute", "series: series.csv", "series: /tmp/tomodem_x.csv", {"output.series", "/tmp/tomodem_x.csv"}),
      scene_row("series_is_packing", "series: series.csv", "series: out.h5", {"output", "same name"}),
      // Outputs over inputs.
      {"json_is_scene", {{"scene.yaml", kScene}}, "scene.yaml --output-dir out --json scene.yaml", 2, {"--json", "scene.yaml"}},
      {"series_over_scene", {{"scene.yaml", with(kScene, "series: series.csv", "series: scene.yaml")}}, "scene.yaml --output-dir .", 2,
       {"output.series", "scene.yaml", "input"}},
      {"packing_over_input_packing", {{"scene.yaml", with(kScene, "packing: out.h5", "packing: scene.yaml")}}, "scene.yaml --output-dir .",
       2, {"output.packing", "scene.yaml"}},
      // Command-line options.
      {"threads_negative_cli", {{"scene.yaml", kScene}}, "scene.yaml --output-dir out --threads -1", 2, {"--threads", "-1"}},
      {"threads_text_cli", {{"scene.yaml", kScene}}, "scene.yaml --output-dir out --threads abc", 2, {"--threads", "abc"}},
      {"steps_negative_cli", {{"scene.yaml", kScene}}, "scene.yaml --output-dir out --steps -3", 2, {"--steps", "-3"}},
      {"steps_absurd_cli", {{"scene.yaml", kScene}}, "scene.yaml --output-dir out --steps 1000000000000000000", 2, {"--steps", "memory"}},
      {"changed_physics_without_restart", {{"scene.yaml", kScene}}, "scene.yaml --output-dir out --restart-changed-physics", 2,
       {"--restart-changed-physics", "--restart"}},
      {"restart_missing", {{"scene.yaml", kScene}}, "scene.yaml --output-dir out --restart nowhere.h5", 2, {"nowhere.h5"}},
      {"restart_random_bytes", {{"scene.yaml", kScene}, {"ck.h5", std::string("\x89HDF\r\n\x1a\n garbage bytes \x01\x02\x03", 32)}},
       "scene.yaml --output-dir out --restart ck.h5", 2, {"ck.h5"}},
      {"restart_is_a_scene", {{"scene.yaml", kScene}}, "scene.yaml --output-dir out --restart scene.yaml", 2, {"scene.yaml"}},
      {"output_folder_is_a_file", {{"scene.yaml", kScene}, {"f", "x"}}, "scene.yaml --output-dir f", 2, {"--output-dir", "f", "not a folder"}},
  };
  // The placeholder row above is the periodic: maybe case, built here (kCell holds periodic: true).
  std::vector<Case> rows = cases;
  rows[3] = scene_row("periodic_maybe", "settings:", with(kCell, "periodic: true", "periodic: maybe"),
                      {"cell.periodic", "maybe", "true, false"});
  EXPECT_GE(bad_input::run_all("tomodem-dem", rows), 50);
}

namespace {

/// Copies a checkpoint dataset by dataset (as doubles: the reader converts), with `dataset`
/// replaced by `values` (left out when empty).
void copy_group(const tomodem::h5::File& in, tomodem::h5::File& out, const std::string& group, const std::string& dataset,
                const std::vector<double>& values) {
  for (const std::string& name : in.children(group)) {
    const std::string path = (group == "/" ? "" : group) + "/" + name;
    bool is_dataset = true;
    try {
      in.shape(path);
    } catch (...) {
      is_dataset = false;
    }
    if (!is_dataset) {
      copy_group(in, out, path, dataset, values);
    } else if (path == dataset) {
      if (!values.empty()) out.write(path, values);
    } else {
      std::vector<std::size_t> dims;
      const auto v = in.read_double(path, &dims);
      out.write(path, v, dims);
    }
  }
}
void rewrite(const std::string& from, const std::string& to, const std::string& dataset, const std::vector<double>& values) {
  fs::remove(to);
  const tomodem::h5::File in(from, tomodem::h5::File::Mode::read);
  tomodem::h5::File out(to, tomodem::h5::File::Mode::create);
  out.set_attr("/", "tomodem_checkpoint_format", in.attr_double("/", "tomodem_checkpoint_format"));
  out.set_attr("/", "scene", in.attr_string("/", "scene"));
  copy_group(in, out, "/", dataset, values);
}

class DemRestart : public tomodem::test::ToolTest {
 protected:
  DemRestart() : ToolTest("tomodem_dem_restart") {}
  std::string write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
    return (dir_ / name).string();
  }
  int run(const std::string& args) {
    const int code = sh(bin("tomodem-dem") + " " + args + " -q");
    err = text("stderr.txt");
    return code;
  }
  /// A checkpoint at step 20 of kScene, in half/ck.h5.
  void half_run() {
    write("scene.yaml", kScene);
    ASSERT_EQ(run("scene.yaml --output-dir half --steps 20"), 0) << err;
  }
  std::vector<std::string> lines(const fs::path& p) {
    std::vector<std::string> out;
    std::istringstream in(bad_input::slurp(p));
    for (std::string l; std::getline(in, l);) out.push_back(l);
    return out;
  }
  std::string err;
};

}  // namespace

TEST_F(DemRestart, DamagedCheckpointsExit2NamingFileAndDataset) {
  half_run();
  const std::string ck = bad_input::slurp(dir_ / "half" / "ck.h5");
  ASSERT_GT(ck.size(), 1000u);
  // Truncated.
  std::ofstream(dir_ / "trunc.h5", std::ios::binary) << ck.substr(0, ck.size() / 2);
  EXPECT_EQ(run("scene.yaml --output-dir o1 --restart trunc.h5"), 2) << err;
  EXPECT_NE(err.find("trunc.h5"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(dir_ / "o1" / "out.h5"));
  // Wrong dataset shapes: the neighbour list's start offsets and the engine scalars.
  struct Shape {
    const char* dataset;
    std::vector<double> values;
  };
  for (const Shape& s : {Shape{"/engine/start", {0, 5, 3}}, Shape{"/engine/scalars", {1, 2}},
                         Shape{"/particles/velocity", {1, 2, 3}}, Shape{"/engine/history", {1}},
                         Shape{"/engine/j", {1.0e6}}, Shape{"/cell/h", {1, 0, 0}}}) {
    rewrite((dir_ / "half" / "ck.h5").string(), (dir_ / "shape.h5").string(), s.dataset, s.values);
    EXPECT_EQ(run("scene.yaml --output-dir o2 --restart shape.h5"), 2) << s.dataset << ": " << err;
    EXPECT_NE(err.find("shape.h5"), std::string::npos) << err;
    EXPECT_NE(err.find(s.dataset), std::string::npos) << err;
    EXPECT_FALSE(fs::exists(dir_ / "o2" / "out.h5"));
  }
  // A missing dataset.
  rewrite((dir_ / "half" / "ck.h5").string(), (dir_ / "missing.h5").string(), "/engine/force", {});
  EXPECT_EQ(run("scene.yaml --output-dir o4 --restart missing.h5"), 2) << err;
  EXPECT_NE(err.find("/engine/force"), std::string::npos) << err;
  // A checkpoint of a different particle count (3^3 FCC cells instead of 2^3).
  write("big.yaml", with(kScene, "cells: 2", "cells: 3"));
  ASSERT_EQ(run("big.yaml --output-dir big --steps 10"), 0) << err;
  EXPECT_EQ(run("scene.yaml --output-dir o3 --restart big/ck.h5"), 2) << err;
  EXPECT_NE(err.find("big/ck.h5"), std::string::npos) << err;
  EXPECT_NE(err.find("particles.generate.cells: 3 -> 2"), std::string::npos) << err;
  // Even when told to accept changed physics, the particle count must match.
  EXPECT_EQ(run("scene.yaml --output-dir o3 --restart big/ck.h5 --restart-changed-physics"), 2) << err;
  EXPECT_NE(err.find("big/ck.h5"), std::string::npos) << err;
  EXPECT_NE(err.find("/particles/position"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(dir_ / "o3" / "out.h5"));
}

TEST_F(DemRestart, ChangedPhysicsIsRefusedNamingTheChangeOrAcceptedWithTheFlagAndAWarning) {
  half_run();
  struct Change {
    const char* from;
    const char* to;
    const char* named;
  };
  for (const Change& c : {Change{"density: 2500", "density: 2600", "materials[0].density: 2500 -> 2600"},
                          Change{"tangential: mindlin", "tangential: linear", "physics.tangential: mindlin -> linear"},
                          Change{"timestep: auto", "timestep: 1.0e-7", "protocol.timestep: auto -> 1.0e-7"},
                          Change{"friction: 0.5}", "friction: 0.5, gravity: [0, 0, -9.81]}", "physics.gravity"}}) {
    write("changed.yaml", with(kScene, c.from, c.to));
    EXPECT_EQ(run("changed.yaml --output-dir o --restart half/ck.h5"), 2) << err;
    EXPECT_NE(err.find("half/ck.h5"), std::string::npos) << err;
    EXPECT_NE(err.find(c.named), std::string::npos) << err;
    EXPECT_NE(err.find("--restart-changed-physics"), std::string::npos) << err;
    EXPECT_FALSE(fs::exists(dir_ / "o" / "out.h5"));
  }
  // Not physics: more steps, another output name, other threads.
  write("same.yaml", with(with(kScene, "steps: 40", "steps: 60"), "series: series.csv", "series: s.csv"));
  EXPECT_EQ(run("same.yaml --output-dir same --restart half/ck.h5"), 0) << err;
  // With the flag: runs, and the warning says what changed.
  write("changed.yaml", with(kScene, "density: 2500", "density: 2600"));
  EXPECT_EQ(run("changed.yaml --output-dir o --restart half/ck.h5 --restart-changed-physics"), 0) << err;
  EXPECT_NE(err.find("materials[0].density: 2500 -> 2600"), std::string::npos) << err;
}

TEST_F(DemRestart, TheTimeSeriesContinuesInTheSameFile) {
  write("scene.yaml", kScene);
  ASSERT_EQ(run("scene.yaml --output-dir full"), 0) << err;
  ASSERT_EQ(run("scene.yaml --output-dir run --steps 20"), 0) << err;
  ASSERT_EQ(run("scene.yaml --output-dir run --restart run/ck.h5"), 0) << err;
  // The restarted series holds every row from step 0, once each, as the uninterrupted run's.
  const auto full = lines(dir_ / "full" / "series.csv"), cont = lines(dir_ / "run" / "series.csv");
  ASSERT_EQ(full.size(), 6u);  // header + steps 0, 10, 20, 30, 40
  EXPECT_EQ(cont, full);
  // A restart into another folder carries the series too (it travels in the checkpoint).
  ASSERT_EQ(run("scene.yaml --output-dir half --steps 20"), 0) << err;
  ASSERT_EQ(run("scene.yaml --output-dir elsewhere --restart half/ck.h5"), 0) << err;
  EXPECT_EQ(lines(dir_ / "elsewhere" / "series.csv"), full);
}
