// End-to-end: the tomodem-segment and tomodem-phantom executables, their summaries and exit codes.
#include <gtest/gtest.h>
#include <unistd.h>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sys/wait.h>

#include "../common/scratch.hpp"
#include "png_read.hpp"

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {
const std::string bin = TOMODEM_BIN_DIR;
using tomodem::test::run_err;
int run(const std::string& cmd) {
  const int r = std::system((cmd + " >/dev/null 2>&1").c_str());
  return WIFEXITED(r) ? WEXITSTATUS(r) : -1;
}
fs::path tmpdir(const std::string& name) { return tomodem::test::fresh_dir("tomodem_seg_e2e_", name); }
bool only(const fs::path& d, std::size_t n) {  // no partial outputs: the folder holds exactly n entries
  return std::size_t(std::distance(fs::directory_iterator(d), fs::directory_iterator())) == n;
}
}  // namespace

TEST(SegmentCli, HelpAndVersion) {
  EXPECT_EQ(run(bin + "/tomodem-segment --help"), 0);
  EXPECT_EQ(run(bin + "/tomodem-segment --version"), 0);
  EXPECT_EQ(run(bin + "/tomodem-phantom --help"), 0);
  EXPECT_EQ(run(bin + "/tomodem-phantom --version"), 0);
  EXPECT_EQ(run(bin + "/tomodem-segment --no-such-flag x"), 2);
}

TEST(SegmentCli, PhantomToLabelsWithEveryOutput) {
  const auto d = tmpdir("full");
  const std::string p = d.string();
  ASSERT_EQ(run(bin + "/tomodem-phantom --kind pores --size 64 --macropores 3 --snr 5 --seed 3 -o " + p +
                "/grey.nrrd --truth " + p + "/truth.h5 --json " + p + "/phantom.json"), 0);
  ASSERT_EQ(run(bin + "/tomodem-segment " + p + "/grey.nrrd --threads 2 -q --method intermeans --macropore-radius 5vox --min-island 10 " +
                "--macropore-min-voxels 30 -o " + p + "/labels.h5 --mha " + p + "/labels.mha --vdb " + p +
                "/pores.vdb --overlay " + p + "/ov --grains --packing " + p + "/grains.h5 --json " + p + "/s.json"), 0);
  json s;
  std::ifstream(d / "s.json") >> s;
  json ph;
  std::ifstream(d / "phantom.json") >> ph;
  for (const char* k : {"porosity", "macroporosity", "n_macropores", "thresholds", "n_grains", "wall_time_s",
                        "pore_size_distribution", "specific_surface_per_m"})
    EXPECT_TRUE(s.contains(k)) << k;
  EXPECT_EQ(s["n_macropores"], ph["n_macropores"]);
  EXPECT_NEAR(s["porosity"].get<double>(), ph["true_porosity"].get<double>(), 0.01);
  // Stage times: every stage that ran, each within the wall time, together not more than it.
  double stages = 0;
  for (const char* k : {"read", "filter", "threshold", "clean", "macropores", "measure", "grains", "outputs"}) {
    ASSERT_TRUE(s["stage_times_s"].contains(k)) << k;
    stages += s["stage_times_s"][k].get<double>();
  }
  EXPECT_LE(stages, s["wall_time_s"].get<double>());
  // Peak memory: at least the 64^3 float grey volume the tool held (1 MiB), below 4 GiB.
  EXPECT_GT(s["peak_rss_bytes"].get<double>(), 64.0 * 64 * 64 * 4);
  EXPECT_LT(s["peak_rss_bytes"].get<double>(), 4.0 * (1 << 30));
  for (const char* f : {"labels.h5", "labels.mha", "pores.vdb", "ov_xy.png", "ov_xz.png", "ov_yz.png", "grains.h5",
                        "grains.xdmf"})
    EXPECT_TRUE(fs::exists(d / f)) << f;
  // The overlay decodes with a reader of its own (png_read.hpp: CRCs, inflate, row filters). Its
  // last row is the white footer, and the legend holds the 10 x 10 macropore swatch, 0.55 grey 128
  // + 0.45 red 255 = RGB (185, 70, 70) (outputs.cpp, write_overlays).
  const auto ov = tomodem::test::read_png_rgb((d / "ov_xy.png").string());
  ASSERT_GT(ov.width * ov.height, 0);
  int white = 0, swatch = 0;
  for (int x = 0; x < ov.width; ++x) white += ov.at(x, ov.height - 1)[0] == 255 && ov.at(x, ov.height - 1)[1] == 255 && ov.at(x, ov.height - 1)[2] == 255;
  EXPECT_EQ(white, ov.width);
  for (int y = 0; y < ov.height; ++y)
    for (int x = 0; x < ov.width; ++x) swatch += ov.at(x, y)[0] == 185 && ov.at(x, y)[1] == 70 && ov.at(x, y)[2] == 70;
  EXPECT_GE(swatch, 100);
  for (const auto& e : fs::directory_iterator(d)) EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos);
}

TEST(SegmentCli, BadInputExitsTwoNamingTheFileWithNoOutput) {
  const auto d = tmpdir("bad");
  const std::string p = d.string(), out = " -o " + p + "/out/l.h5 --json " + p + "/out/s.json";
  fs::create_directories(d / "out");
  { std::ofstream o(d / "short.raw", std::ios::binary); std::vector<char> b(4000, 3); o.write(b.data(), 4000); }
  std::string err;
  // truncated raw
  EXPECT_EQ(run_err(bin + "/tomodem-segment " + p + "/short.raw --raw-dims 16,16,16 --spacing 1um" + out, &err), 2);
  EXPECT_NE(err.find("short.raw"), std::string::npos);
  EXPECT_NE(err.find("truncated"), std::string::npos);
  // dims that do not match the file size (too large a file for them)
  EXPECT_EQ(run_err(bin + "/tomodem-segment " + p + "/short.raw --raw-dims 10,10,10 --spacing 1um" + out, &err), 2);
  EXPECT_NE(err.find("does not match"), std::string::npos);
  // unknown format
  { std::ofstream(d / "scan.xyz") << "?"; }
  EXPECT_EQ(run_err(bin + "/tomodem-segment " + p + "/scan.xyz" + out, &err), 2);
  EXPECT_NE(err.find("unknown format"), std::string::npos);
  // constant volume
  { std::ofstream o(d / "flat.raw", std::ios::binary); std::vector<char> b(4096, 7); o.write(b.data(), 4096); }
  EXPECT_EQ(run_err(bin + "/tomodem-segment " + p + "/flat.raw --raw-dims 16,16,16 --spacing 1um" + out, &err), 2);
  EXPECT_NE(err.find("constant"), std::string::npos);
  // TIFF stack with mixed slice sizes
  ASSERT_EQ(run(bin + "/tomodem-phantom --kind sphere --size 20 --sphere-radius 5 -o " + p + "/stack/"), 0);
  ASSERT_EQ(run(bin + "/tomodem-phantom --kind sphere --size 24 --sphere-radius 5 -o " + p + "/other/"), 0);
  fs::copy_file(d / "other" / "slice00003.tif", d / "stack" / "slice00003b.tif");
  EXPECT_EQ(run_err(bin + "/tomodem-segment " + p + "/stack --spacing 1um" + out, &err), 2);
  EXPECT_NE(err.find("slice00003b.tif"), std::string::npos);
  EXPECT_NE(err.find("mixed slice sizes"), std::string::npos);
  // TIFF without a voxel size
  fs::remove(d / "stack" / "slice00003b.tif");
  EXPECT_EQ(run_err(bin + "/tomodem-segment " + p + "/stack" + out, &err), 2);
  EXPECT_NE(err.find("--spacing"), std::string::npos);
  EXPECT_TRUE(only(d / "out", 0));
  // and the good stack goes through
  EXPECT_EQ(run(bin + "/tomodem-segment " + p + "/stack --spacing 1um --macropore-radius 2vox" + out), 0);
  EXPECT_TRUE(only(d / "out", 3));  // the labels, their XDMF sidecar and the summary
}
