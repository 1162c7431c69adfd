// One command-line convention for every tool (docs/cli.md): each tool run on a small input with
// `--json out.json -q` prints nothing on stdout and writes a summary with the common keys; every
// tool with --threads accepts 0 (all cores) and refuses -1 naming the option; every length
// option refuses an unknown unit (exit 2, naming the option) and reads "10um" as 1e-5 m.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

const std::string kBin = TOMODEM_BIN_DIR;

struct Result {
  int code;
  std::string out, err;
};

std::string text_of(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Runs `tomodem-<tool> args` in `dir`, stdout and stderr kept apart.
Result run(const std::string& exe, const std::string& args, const fs::path& dir) {
  const std::string cmd = "cd '" + dir.string() + "' && OMP_WAIT_POLICY=PASSIVE '" + kBin + "/" + exe + "' " + args +
                          " > stdout.txt 2> stderr.txt";
  const int rc = std::system(cmd.c_str());
  return {WEXITSTATUS(rc), text_of(dir / "stdout.txt"), text_of(dir / "stderr.txt")};
}

// Whether this configuration builds `exe` (tests/e2e/cli/CMakeLists.txt); a configured tool that
// is not in bin/ is a broken build, not a reason to skip.
bool built(const std::string& exe) {
  const bool configured = std::string(TOMODEM_CONFIGURED_TOOLS).find(" " + exe + " ") != std::string::npos;
  if (configured) EXPECT_TRUE(fs::exists(kBin + "/" + exe)) << exe << " is configured but missing from " << kBin;
  return configured;
}

// Small inputs, made in the test's own folder on demand (each ctest test is its own process).
class Inputs {
 public:
  explicit Inputs(fs::path dir) : dir_(std::move(dir)) {}
  // A 300-sphere packing (monodisperse, φ = 0.35) whose material conducts.
  std::string packing() {
    if (!fs::exists(dir_ / "green.h5")) {
      std::ofstream(dir_ / "green.yaml")
          << "particles: 300\nphases:\n  - {name: a, material: {density: 1000, youngs_modulus: 1.0e8, "
             "conductivity: 1.0e4}, size_distribution: {kind: monodisperse, diameter: 1.0e-3}}\n"
             "target: {solid_fraction: 0.35}\n";
      must("tomodem-pack", "green.yaml -o green.h5 --no-tessellation -q");
    }
    return "green.h5";
  }
  // The packing densified to 0.6 and bonded.
  std::string bonded() {
    if (!fs::exists(dir_ / "bonded.h5")) {
      packing();
      must("tomodem-bond", "green.h5 -o bonded.h5 --rule density --target-density 0.6 -q");
    }
    return "bonded.h5";
  }
  // A 24^3 phantom of grains, with its truth packing (grains as spheres).
  std::string volume() {
    if (!fs::exists(dir_ / "grey.mha")) must("tomodem-phantom", "-o grey.mha --size 24 --kind packing --truth truth.h5 -q");
    return "grey.mha";
  }
  std::string config() {
    packing();
    return "green.yaml";
  }
  std::string grains() {
    volume();
    return "truth.h5.packing.h5";
  }
  // An FCC box of 2^3 cells: 32 spheres.
  std::string dem_scene() {
    std::ofstream(dir_ / "scene.yaml")
        << "materials:\n  - {name: glass, youngs_modulus: 1.0e8, poisson_ratio: 0.25, density: 2500}\n"
           "particles:\n  generate: {arrangement: fcc, cells: 2, radius: 0.5e-3, solid_fraction: 0.76, velocity: 0.05, "
           "seed: 3, phase: glass}\nphysics: {normal: hertz, tangential: mindlin, restitution: 0.5, friction: 0.5}\n"
           "protocol: {timestep: auto, steps: 20, output_interval: 10}\noutput: {packing: out.h5, series: series.csv}\n";
    return "scene.yaml";
  }
  // 32 alumina spheres sintered to 78 % density.
  std::string sinter_scene() {
    std::ofstream(dir_ / "sinter.yaml")
        << "materials:\n  - {name: alumina, youngs_modulus: 380.0e9, poisson_ratio: 0.22, density: 3950, "
           "surface_energy: 1.0}\nparticles:\n  generate: {arrangement: fcc, cells: 2, radius: 1.0e-6, spacing: "
           "2.82277e-6, jitter: 0.01, seed: 3, phase: alumina}\nphysics: {normal: sintering}\n"
           "settings: {check_interval: 100}\nsintering:\n  temperature:\n    start: 300\n"
           "    segments: [{rate: 50, to: 1600}, {hold: 5000}]\n  phases:\n    - {material: alumina, atomic_volume: "
           "8.47e-30, boundary_diffusion: 8.6e-10, activation_energy: 418.0e3, dihedral_angle: 150}\n"
           "  stop: {relative_density: 0.78}\n  accuracy: {update_interval: 10}\n  conserve_volume: true\n"
           "  output: {curve: curve.csv, packing: sintered.h5, necks: necks.csv, rows: 200, plots: false}\n";
    return "sinter.yaml";
  }
  // A pipeline of one shell step.
  std::string pipeline() {
    std::ofstream(dir_ / "pipe.yaml") << "steps:\n  hello:\n    cmd: echo hello > ${outs.text}\n    outs: {text: hello.txt}\n";
    return "pipe.yaml";
  }

 private:
  void must(const std::string& exe, const std::string& args) {
    const Result r = run(exe, args, dir_);
    ASSERT_EQ(r.code, 0) << exe << " " << args << "\n" << r.err;
  }
  fs::path dir_;
};

fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::path(::testing::TempDir()) / ("cli_e2e_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// ---- --json FILE -q: stdout empty, the file holds the common keys --------------------------

struct Row {
  std::string name;  // the gtest name; the tool is tomodem-<tool>
  std::string exe;   // executable
  std::string tool;  // the summary's "tool"
  std::string args;  // {C} pack config, {P} packing, {B} bonded, {V} volume, {G} grains, {S} dem scene, {T} sinter scene, {R} pipeline
  std::string input; // the summary's input.path ("" : null)
  long n_particles;  // -1: not a particle tool; 0: present, count not known beforehand
};

void PrintTo(const Row& r, std::ostream* os) { *os << r.exe << " " << r.args; }

std::string expand(std::string s, Inputs& in, std::string* input) {
  const std::vector<std::pair<std::string, std::string (Inputs::*)()>> keys = {
      {"{C}", &Inputs::config}, {"{P}", &Inputs::packing}, {"{B}", &Inputs::bonded},      {"{V}", &Inputs::volume},   {"{G}", &Inputs::grains},
      {"{S}", &Inputs::dem_scene}, {"{T}", &Inputs::sinter_scene}, {"{R}", &Inputs::pipeline}};
  for (const auto& [key, make] : keys) {
    const auto k = input->find(key);
    if (k != std::string::npos) input->replace(k, key.size(), (in.*make)());
    for (auto p = s.find(key); p != std::string::npos; p = s.find(key)) s.replace(p, key.size(), (in.*make)());
  }
  return s;
}

const std::vector<Row> kRows = {
    {"phantom", "tomodem-phantom", "tomodem-phantom", "-o g.mha --size 24 --kind pores", "", -1},
    {"segment", "tomodem-segment", "tomodem-segment", "{V} -o labels.h5", "{V}", -1},
    {"pack", "tomodem-pack", "tomodem-pack", "{C} -o p2.h5 --particles 200 --no-tessellation", "{C}", 200},
    {"carve", "tomodem-carve", "tomodem-carve", "{P} --spheres {G} --fit -o carved.h5", "{P}", 0},
    {"bond", "tomodem-bond", "tomodem-bond", "{P} -o b2.h5 --rule density --target-density 0.6", "{P}", 300},
    {"young", "tomodem-young", "tomodem-young", "{B} --method implicit --no-tensor", "{B}", 300},
    {"fracture", "tomodem-fracture", "tomodem-fracture", "{B} --method sla --no-elastic --fracture-energy 2", "{B}", 300},
    {"conduct", "tomodem-conduct", "tomodem-conduct", "{B} --axis x", "{B}", 300},
    {"dem", "tomodem-dem", "tomodem-dem", "{S} --output-dir d", "{S}", 32},
    {"sinter", "tomodem-sinter", "tomodem-sinter", "{T} --output-dir s", "{T}", 32},
    {"run", "tomodem-run", "tomodem-run", "{R}", "{R}", -1},
    {"cg", "tomodem-cg", "tomodem-cg", "{P} -o f.h5 --nodes 8", "{P}", 0},
    {"dispatcher", "tomodem", "tomodem-phantom", "phantom -o g.mha --size 24", "", -1},
};

class JsonQuiet : public ::testing::TestWithParam<Row> {};

TEST_P(JsonQuiet, StdoutIsEmptyAndTheFileHoldsTheCommonKeys) {
  const Row& row = GetParam();
  if (!built(row.exe) || (row.exe == "tomodem" && !built(row.tool)))
    GTEST_SKIP() << row.exe << " is not part of this build";
  const fs::path dir = fresh_dir(row.name);
  Inputs in(dir);
  std::string input = row.input;
  const std::string args = expand(row.args, in, &input);
  const Result r = run(row.exe, args + " --json out.json -q", dir);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.out, "") << "stdout must stay empty with --json FILE -q";
  ASSERT_TRUE(fs::exists(dir / "out.json"));
  const json j = json::parse(text_of(dir / "out.json"));
  EXPECT_EQ(j.value("tool", ""), row.tool);
  ASSERT_TRUE(j.contains("input") && j["input"].is_object());
  if (input.empty()) EXPECT_TRUE(j["input"]["path"].is_null());
  else EXPECT_EQ(j["input"]["path"], input);
  ASSERT_TRUE(j.contains("outputs") && j["outputs"].is_object());
  ASSERT_TRUE(j.contains("units") && j["units"].is_object());
  EXPECT_EQ(j["units"].value("wall_time_s", ""), "s");
  for (const char* k : {"wall_time_s", "cpu_time_s", "peak_rss_bytes"}) {
    ASSERT_TRUE(j.contains(k) && j[k].is_number()) << k;
    EXPECT_GE(j[k].get<double>(), 0) << k;
  }
  // A process that ran a tool holds at least its own code in memory: well over a megabyte.
  EXPECT_GT(j["peak_rss_bytes"].get<double>(), 1e6);
  ASSERT_TRUE(j.contains("provenance") && j["provenance"].is_object());
  for (const char* k : {"version", "git_hash", "command_line", "host", "utc_time"})
    EXPECT_TRUE(j["provenance"].contains(k)) << k;
  EXPECT_NE(j["provenance"].value("command_line", "").find("--json out.json"), std::string::npos);
  EXPECT_EQ(j["provenance"].value("utc_time", "").size(), 20u);  // 2026-01-02T03:04:05Z
  if (row.n_particles >= 0) {
    ASSERT_TRUE(j.contains("n_particles")) << "a tool with particles says how many";
    if (row.n_particles > 0) EXPECT_EQ(j["n_particles"].get<long>(), row.n_particles);
  }
  for (const char* old : {"particles", "output", "version", "scene", "config"})
    EXPECT_FALSE(j.contains(old)) << "old key '" << old << "' (docs/cli.md names the common keys)";
  for (const auto& [role, path] : j["outputs"].items())
    if (path.is_string()) EXPECT_TRUE(fs::exists(dir / path.get<std::string>())) << role << ": " << path;
}

// --json - is stdout: the same summary on stdout, no file named "-".
TEST(JsonDash, IsStdoutAndCreatesNoFile) {
  if (!built("tomodem-phantom")) GTEST_SKIP();
  const fs::path dir = fresh_dir("dash");
  const Result r = run("tomodem-phantom", "-o g.mha --size 16 --json - -q", dir);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_FALSE(fs::exists(dir / "-"));
  EXPECT_EQ(json::parse(r.out).value("tool", ""), "tomodem-phantom");
}

INSTANTIATE_TEST_SUITE_P(AllTools, JsonQuiet, ::testing::ValuesIn(kRows),
                         [](const auto& info) { return info.param.name; });

// ---- --threads 0 accepted, -1 refused -------------------------------------------------------

struct ThreadsRow {
  std::string exe, args;  // args that fail on a missing input file, after the options are parsed
};

const std::vector<ThreadsRow> kThreads = {
    {"tomodem-pack", "missing.yaml -o p.h5"},   {"tomodem-dem", "missing.yaml"},
    {"tomodem-sinter", "missing.yaml"},         {"tomodem-bond", "missing.h5 -o b.h5"},
    {"tomodem-young", "missing.h5"},            {"tomodem-fracture", "missing.h5"},
    {"tomodem-conduct", "missing.h5"},          {"tomodem-carve", "missing.h5 --spheres missing2.h5 -o c.h5"},
    {"tomodem-segment", "missing.mha -o l.h5"}, {"tomodem-phantom", "-o g.mha --size 16"},
    {"tomodem-cg", "missing.h5 -o f.h5"},
};

TEST(Threads, ZeroIsAllCoresInEveryToolAndMinusOneIsRefused) {
  for (const auto& t : kThreads) {
    if (!built(t.exe)) continue;
    SCOPED_TRACE(t.exe);
    const fs::path dir = fresh_dir("threads");
    // 0 passes the parser: the run then stops on the missing input (exit 2, naming it), or,
    // for phantom, which reads nothing, succeeds.
    const Result zero = run(t.exe, t.args + " --threads 0", dir);
    EXPECT_EQ(zero.err.find("--threads"), std::string::npos) << zero.err;
    if (t.exe == "tomodem-phantom") EXPECT_EQ(zero.code, 0) << zero.err;
    else {
      EXPECT_EQ(zero.code, 2) << zero.err;
      EXPECT_NE(zero.err.find("missing"), std::string::npos) << zero.err;
    }
    const Result minus = run(t.exe, t.args + " --threads -1", dir);
    EXPECT_EQ(minus.code, 2);
    EXPECT_NE(minus.err.find("--threads"), std::string::npos) << minus.err;
  }
}

// The default is every core (OMP_NUM_THREADS when set, docs/cli.md) in dem and pack too; a
// count the scene or config writes is used when --threads is not given, and --threads wins.
TEST(Threads, DefaultIsAllCoresAndACountTheInputWritesIsKept) {
  const char* env = std::getenv("OMP_NUM_THREADS");
  const long cores = env && std::atoi(env) > 0 ? std::atoi(env) : long(std::max(1u, std::thread::hardware_concurrency()));
  const auto threads_of = [](const fs::path& json) { return nlohmann::json::parse(text_of(json)).value("threads", -1L); };
  if (built("tomodem-dem")) {
    const fs::path dir = fresh_dir("threads_dem");
    Inputs in(dir);
    const std::string scene = in.dem_scene();
    ASSERT_EQ(run("tomodem-dem", scene + " --output-dir a --json a.json -q", dir).code, 0);
    EXPECT_EQ(threads_of(dir / "a.json"), cores);
    std::ofstream(dir / scene, std::ios::app) << "settings: {threads: 1}\n";
    ASSERT_EQ(run("tomodem-dem", scene + " --output-dir b --json b.json -q", dir).code, 0);
    EXPECT_EQ(threads_of(dir / "b.json"), 1);
    ASSERT_EQ(run("tomodem-dem", scene + " --output-dir c --json c.json -q --threads 2", dir).code, 0);
    EXPECT_EQ(threads_of(dir / "c.json"), 2);
  }
  if (built("tomodem-pack")) {
    const fs::path dir = fresh_dir("threads_pack");
    const std::string config =
        "particles: 50\nphases:\n  - {name: a, material: {density: 1000, youngs_modulus: 1.0e8}, "
        "size_distribution: {kind: monodisperse, diameter: 1.0e-3}}\ntarget: {solid_fraction: 0.3}\n";
    std::ofstream(dir / "a.yaml") << config;
    std::ofstream(dir / "b.yaml") << config << "threads: 1\n";
    ASSERT_EQ(run("tomodem-pack", "a.yaml -o a.h5 --no-tessellation --json a.json -q", dir).code, 0);
    EXPECT_EQ(threads_of(dir / "a.json"), cores);
    ASSERT_EQ(run("tomodem-pack", "b.yaml -o b.h5 --no-tessellation --json b.json -q", dir).code, 0);
    EXPECT_EQ(threads_of(dir / "b.json"), 1);
    ASSERT_EQ(run("tomodem-pack", "b.yaml -o c.h5 --no-tessellation --json c.json -q --threads 2", dir).code, 0);
    EXPECT_EQ(threads_of(dir / "c.json"), 2);
  }
}

// ---- lengths: one parser, units everywhere --------------------------------------------------

TEST(Lengths, AnUnknownUnitExitsTwoNamingTheOption) {
  struct Case {
    std::string exe, option, args;
  };
  const std::vector<Case> cases = {
      {"tomodem-phantom", "--voxel", "-o g.mha --voxel 3furlong"},
      {"tomodem-segment", "--spacing", "missing.mha --spacing 3furlong"},
      {"tomodem-segment", "--header-unit", "missing.mha --header-unit 3furlong"},
      {"tomodem-segment", "--macropore-radius", "missing.mha --macropore-radius 3furlong"},
      {"tomodem-fracture", "--grip", "missing.h5 --grip 3furlong"},
      {"tomodem-carve", "--image-unit", "missing.h5 --mesh m.stl -o c.h5 --image-unit 3furlong"},
      {"tomodem-carve", "--spacing", "missing.h5 --labels l.h5 -o c.h5 --spacing 3furlong"},
      {"tomodem-carve", "--margin", "missing.h5 --mesh m.stl -o c.h5 --margin 3furlong"},
      {"tomodem-carve", "--offset", "missing.h5 --mesh m.stl -o c.h5 --offset 1mm,3furlong,0"},
      {"tomodem-carve", "--image-box", "missing.h5 --mesh m.stl -o c.h5 --image-box 0,0,0,1,1,3furlong"},
  };
  for (const auto& c : cases) {
    if (!built(c.exe)) continue;
    SCOPED_TRACE(c.exe + " " + c.args);
    const fs::path dir = fresh_dir("lengths");
    const Result r = run(c.exe, c.args, dir);
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find(c.option), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("furlong"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "g.mha")) << "nothing written";
  }
}

TEST(Lengths, MicrometresAreConvertedToMetres) {
  if (!built("tomodem-phantom")) GTEST_SKIP();
  for (const auto& [text, metres] : std::vector<std::pair<std::string, double>>{
           {"10um", 10e-6}, {"0.01mm", 10e-6}, {"1e-5", 1e-5}, {"10000nm", 10e-6}, {"2.5\xc2\xb5m", 2.5e-6}}) {
    SCOPED_TRACE(text);
    const fs::path dir = fresh_dir("micro");
    const Result r = run("tomodem-phantom", "-o g.mha --size 16 --voxel " + text + " --json out.json -q", dir);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NEAR(json::parse(text_of(dir / "out.json"))["voxel_m"].get<double>(), metres, 1e-12 * metres);
  }
}

// ---- -o names a file; dem and sinter take --output-dir -------------------------------------

TEST(OutputOption, DemAndSinterRefuseOAsAFolderAndSayWhatToUse) {
  for (const char* exe : {"tomodem-dem", "tomodem-sinter"}) {
    if (!built(exe)) continue;
    SCOPED_TRACE(exe);
    const fs::path dir = fresh_dir("o_folder");
    Inputs in(dir);
    const std::string scene = std::string(exe) == "tomodem-dem" ? in.dem_scene() : in.sinter_scene();
    const Result r = run(exe, scene + " -o out", dir);
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("--output-dir"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "out"));
  }
}

// ---- docs/cli.md names every option of every tool ---------------------------------------------

TEST(CliDoc, EveryOptionOfEveryToolIsInTheTable) {
  const std::string doc = text_of(fs::path(TOMODEM_SOURCE_DIR) / "docs" / "cli.md");
  ASSERT_FALSE(doc.empty());
  const fs::path dir = fresh_dir("doc");
  int checked = 0;
  for (const char* tool : {"pack", "dem", "sinter", "bond", "young", "fracture", "conduct", "carve", "segment", "phantom",
                           "run", "cg"}) {
    const std::string exe = std::string("tomodem-") + tool;
    if (!built(exe)) continue;
    const Result r = run(exe, "--help", dir);
    ASSERT_EQ(r.code, 0) << exe;
    std::istringstream lines(r.out);
    for (std::string line; std::getline(lines, line);) {
      const auto k = line.find_first_not_of(' ');
      if (k == std::string::npos || line[k] != '-') continue;  // options only, not the usage line
      std::string names = line.substr(k, line.find(' ', k) - k);
      for (std::size_t b = 0; b < names.size();) {
        const auto e = std::min(names.find(',', b), names.size());
        const std::string name = names.substr(b, e - b);
        EXPECT_NE(doc.find("`" + name + "`"), std::string::npos) << exe << ": " << name << " is not in docs/cli.md";
        ++checked;
        b = e + 1;
      }
    }
  }
  EXPECT_GT(checked, 100);  // the tools have some 160 options between them
}

}  // namespace
