// End-to-end: tomodem-carve on a packing file with a level set, a label volume and a mesh; the
// summary keys; bad input (no overlap, open mesh, no interior, everything removed) exits 2 with
// a message naming the file and no output.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sys/wait.h>

#include <filesystem>
#include <fstream>

#include "../../validation/carve/carve_util.hpp"
#include "../segment/png_read.hpp"
#include "tomodem/core/packing_io.hpp"
#include "tomodem/image/volume.hpp"

namespace fs = std::filesystem;
using json = nlohmann::json;
using namespace tomodem;
using namespace tomodem::carve::testing;

namespace {
const std::string bin = std::string(TOMODEM_BIN_DIR) + "/tomodem-carve";
int run_err(const std::string& cmd, std::string* err, const std::string& dir) {
  const std::string ef = dir + "/stderr.txt";
  const int r = std::system(("OMP_WAIT_POLICY=PASSIVE " + cmd + " >/dev/null 2>" + ef).c_str());
  std::ifstream in(ef);
  err->assign(std::istreambuf_iterator<char>(in), {});
  fs::remove(ef);
  return WIFEXITED(r) ? WEXITSTATUS(r) : -1;
}
std::size_t entries(const std::string& d) {
  return std::size_t(std::distance(fs::directory_iterator(d), fs::directory_iterator()));
}

/// Inputs: a 64-voxel sphere phantom (1e-5 m voxels) as level set and labels, its packing, meshes.
struct Inputs {
  std::string dir;
  explicit Inputs(const std::string& name) : dir(temp_dir("e2e_" + name)) {
    const auto ph = sphere_phantom(48, 12.0);
    image::write_level_set(dir + "/pore.vdb", macropore_mask(ph));
    write_truth_volume(dir + "/labels.h5", ph);
    write_packing(dir + "/green.h5", random_packing(48e-5, 1.2e-5, 0.3, 3, {-0.5e-5, -0.5e-5, -0.5e-5}));
    write_icosphere_off(dir + "/pore.off", ph.macropore_centres[0], 12e-5, 3);
    write_icosphere_off(dir + "/open.off", ph.macropore_centres[0], 12e-5, 2, true);
    write_icosphere_off(dir + "/huge.off", ph.macropore_centres[0], 1.0, 2);
    image::Mask empty(image::Dims{16, 16, 16}, 0);
    empty.spacing = {1e-5, 1e-5, 1e-5};
    image::write_level_set(dir + "/empty.vdb", empty);
    fs::create_directories(dir + "/out");
  }
};
}  // namespace

TEST(CarveCli, HelpVersionBadFlag) {
  std::string err;
  const Inputs in("help");
  EXPECT_EQ(run_err(bin + " --help", &err, in.dir), 0);
  EXPECT_EQ(run_err(bin + " --version", &err, in.dir), 0);
  EXPECT_EQ(run_err(bin + " --no-such-flag", &err, in.dir), 2);
}

TEST(CarveCli, LevelSetWithEveryOutput) {
  const Inputs in("full");
  const std::string d = in.dir + "/full";
  fs::create_directories(d);
  std::string err;
  ASSERT_EQ(run_err(bin + " " + in.dir + "/green.h5 --level-set " + in.dir + "/pore.vdb --threads 2 -o " + d +
                        "/carved.h5 --json " + d + "/s.json --picture " + d + "/mid.png --relax 50",
                    &err, in.dir),
            0)
      << err;
  json s;
  std::ifstream(d + "/s.json") >> s;
  for (const char* k : {"n_removed", "macroporosity_achieved", "macroporosity_target", "solid_fraction_outside",
                        "wall_time_s", "n_floating_particles", "n_floating_clusters", "connectivity"})
    EXPECT_TRUE(s.contains(k)) << k;
  EXPECT_NEAR(s["macroporosity_achieved"].get<double>(), s["macroporosity_target"].get<double>(), 0.02);
  const Packing out = read_packing(d + "/carved.h5");
  EXPECT_EQ(out.particles.size(), s["n_particles_in"].get<std::size_t>() - s["n_removed"].get<std::size_t>());
  EXPECT_EQ(out.provenance.tool, "tomodem-carve");
  for (const char* f : {"carved.h5", "carved.xdmf", "mid.png", "s.json"}) EXPECT_TRUE(fs::exists(d + "/" + f)) << f;
  EXPECT_EQ(entries(d), 4u);  // nothing else (no temporary files)
  // The picture decodes (an independent reader: CRCs, inflate, row filters) and shows both
  // backgrounds of picture.cpp: the macropore tint RGB (255, 200, 200), as the mid-plane cuts the
  // sphere, and the solid region's RGB (245, 245, 245).
  const auto mid = tomodem::test::read_png_rgb(d + "/mid.png");
  int pore = 0, solid = 0;
  for (int y = 0; y < mid.height; ++y)
    for (int x = 0; x < mid.width; ++x) {
      const uint8_t* c = mid.at(x, y);
      pore += c[0] == 255 && c[1] == 200 && c[2] == 200;
      solid += c[0] == 245 && c[1] == 245 && c[2] == 245;
    }
  EXPECT_GT(pore, 0);
  EXPECT_GT(solid, 0);
}

TEST(CarveCli, LabelsAndMeshAgreeWithTheLevelSet) {
  const Inputs in("routes");
  std::string err;
  json a, b, c;
  for (auto [src, out] : {std::pair<std::string, std::string>{"--level-set " + in.dir + "/pore.vdb", "a"},
                          {"--labels " + in.dir + "/labels.h5 --dataset /volume --label-values 2", "b"},
                          {"--mesh " + in.dir + "/pore.off --offset 0,0,0", "c"}}) {
    ASSERT_EQ(run_err(bin + " " + in.dir + "/green.h5 " + src + " -q -o " + in.dir + "/out/" + out + ".h5 --json " +
                          in.dir + "/out/" + out + ".json",
                      &err, in.dir),
              0)
        << err;
  }
  std::ifstream(in.dir + "/out/a.json") >> a;
  std::ifstream(in.dir + "/out/b.json") >> b;
  std::ifstream(in.dir + "/out/c.json") >> c;
  // Same sphere, three descriptions: the targets agree to the voxel staircase / level-set smoothing.
  EXPECT_NEAR(a["macroporosity_target"].get<double>(), b["macroporosity_target"].get<double>(), 0.01);
  EXPECT_NEAR(a["macroporosity_target"].get<double>(), c["macroporosity_target"].get<double>(), 0.01);
  EXPECT_NEAR(c["macroporosity_achieved"].get<double>(), c["macroporosity_target"].get<double>(), 0.02);
}

TEST(CarveCli, BadInputExitsTwoWithNoOutput) {
  const Inputs in("bad");
  const std::string o = in.dir + "/out";
  const std::string outs = " -o " + o + "/c.h5 --json " + o + "/s.json --picture " + o + "/p.png";
  std::string err;
  // the image beside the packing
  EXPECT_EQ(run_err(bin + " " + in.dir + "/green.h5 --level-set " + in.dir + "/pore.vdb --offset 1,0,0" + outs, &err, in.dir), 2);
  EXPECT_NE(err.find("does not overlap"), std::string::npos) << err;
  EXPECT_NE(err.find("pore.vdb"), std::string::npos) << err;
  // an open mesh
  EXPECT_EQ(run_err(bin + " " + in.dir + "/green.h5 --mesh " + in.dir + "/open.off" + outs, &err, in.dir), 2);
  EXPECT_NE(err.find("open.off"), std::string::npos) << err;
  EXPECT_NE(err.find("watertight"), std::string::npos) << err;
  // a level set with no interior
  EXPECT_EQ(run_err(bin + " " + in.dir + "/green.h5 --level-set " + in.dir + "/empty.vdb" + outs, &err, in.dir), 2);
  EXPECT_NE(err.find("no interior"), std::string::npos) << err;
  // every particle inside the pore
  EXPECT_EQ(run_err(bin + " " + in.dir + "/green.h5 --mesh " + in.dir + "/huge.off" + outs, &err, in.dir), 2);
  EXPECT_NE(err.find("every particle"), std::string::npos) << err;
  // no macropore source, two sources, bad rule
  EXPECT_EQ(run_err(bin + " " + in.dir + "/green.h5" + outs, &err, in.dir), 2);
  EXPECT_EQ(run_err(bin + " " + in.dir + "/green.h5 --mesh a.off --level-set b.vdb" + outs, &err, in.dir), 2);
  EXPECT_EQ(run_err(bin + " " + in.dir + "/green.h5 --level-set " + in.dir + "/pore.vdb --rule nope" + outs, &err, in.dir), 2);
  EXPECT_EQ(entries(o), 0u);
}
