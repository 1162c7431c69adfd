// tomodem-conduct --image: transport in a segmented label volume from the command line, and the
// worked example of docs/conduct.md#transport-in-a-segmented-image (phantom -> segment -> conduct).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "tomodem/core/h5.hpp"

namespace fs = std::filesystem;
using namespace tomodem;

namespace {
const std::string kBin = std::string(TOMODEM_BIN_DIR);

class ConductImage : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("tomodem-conduct-image-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  // Runs a command in the test folder; returns the exit code, stderr in *err.
  int sh(const std::string& cmd, std::string* err = nullptr) const {
    const std::string e = path("stderr.txt");
    const int st = std::system(("cd '" + dir_.string() + "' && " + cmd + " > stdout.txt 2> '" + e + "'").c_str());
    if (err) {
      std::ifstream in(e);
      std::stringstream s;
      s << in.rdbuf();
      *err = s.str();
    }
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  }
  nlohmann::json summary(const std::string& file) const {
    std::ifstream in(path(file));
    return nlohmann::json::parse(in);
  }
  fs::path dir_;
};

// A hand-written label volume (nx 12, ny 9, nz 7; anisotropic voxels): straight channels of label 3
// along y in an otherwise label-1 block. σ_eff/σ0 along y is the channel fraction exactly (no
// transverse current: the solution is the linear profile), τ = 1; along x and z nothing spans.
TEST_F(ConductImage, StraightChannelsThroughTheCli) {
  const std::size_t nx = 12, ny = 9, nz = 7;
  std::vector<uint8_t> v(nx * ny * nz, 1);
  std::size_t on = 0;
  for (std::size_t z = 1; z < nz; z += 3)
    for (std::size_t x = 2; x < nx; x += 4) {
      for (std::size_t y = 0; y < ny; ++y) v[(z * ny + y) * nx + x] = 3;
      on += ny;
    }
  {
    h5::File f(path("labels.h5"), h5::File::Mode::create);
    f.write("/labels", v, {nz, ny, nx});
    f.set_attr("/labels", "spacing", std::vector<double>{2e-6, 1e-6, 3e-6});
    f.close();
  }
  std::string err;
  ASSERT_EQ(sh(kBin + "/tomodem-conduct --image labels.h5 --phase 3 --axis all --json t.json", &err), 0) << err;
  const auto j = summary("t.json");
  const double eps = double(on) / v.size();
  EXPECT_DOUBLE_EQ(j["porosity"].get<double>(), eps);
  EXPECT_NEAR(j["sigma_eff"]["y"].get<double>(), eps, 1e-6 * eps);
  EXPECT_NEAR(j["tortuosity"]["y"].get<double>(), 1.0, 1e-6);
  EXPECT_EQ(j["sigma_eff"]["x"].get<double>(), 0.0);
  EXPECT_TRUE(j["tortuosity"]["x"].is_null()) << "no spanning path: tortuosity inf (null)";
  EXPECT_FALSE(j["axes"]["z"]["percolates"].get<bool>());
  EXPECT_NE(err.find("no spanning path"), std::string::npos) << err;
  // Label 1 with conductivity 0.5 and label 3 with 1 in parallel along y: the arithmetic mean.
  ASSERT_EQ(sh(kBin + "/tomodem-conduct --image labels.h5 --phase-conductivity 1:0.5,3:1 --axis y --json p.json -q", &err), 0)
      << err;
  const double arith = 0.5 * (1 - eps) + 1.0 * eps;
  EXPECT_NEAR(summary("p.json")["sigma_eff"]["y"].get<double>(), arith, 1e-6 * arith);
}

// The worked example of docs/conduct.md: a lamellae phantom (walls normal to x, wavy along z),
// segmented, then the tortuosity of its pore phase (label 2, the channels) along x, y and z.
TEST_F(ConductImage, WorkedExamplePhantomSegmentConduct) {
#ifndef TOMODEM_IMAGE_TOOLS_CONFIGURED
  GTEST_SKIP() << "this configuration leaves out libs/image (TOMODEM_SKIP, or the MPI build)";
#endif
  ASSERT_TRUE(fs::exists(kBin + "/tomodem-phantom") && fs::exists(kBin + "/tomodem-segment"))
      << "tomodem-phantom / tomodem-segment are configured but missing from " << kBin;
  std::string err;
  ASSERT_EQ(sh(kBin + "/tomodem-phantom --kind lamellae --size 64 -o grey.mha -q", &err), 0) << err;
  ASSERT_EQ(sh(kBin + "/tomodem-segment grey.mha --method intermeans -o labels.h5 -q", &err), 0) << err;
  ASSERT_EQ(sh(kBin + "/tomodem-conduct --image labels.h5 --phase 2 --axis all -o fields.h5 --json t.json", &err), 0)
      << err;
  const auto j = summary("t.json");
  // The porosity is the fraction of label-2 voxels of the segmented volume.
  std::vector<std::size_t> dims;
  const auto lab = h5::File(path("labels.h5"), h5::File::Mode::read).read_uint8("/labels", &dims);
  std::size_t pores = 0;
  for (auto l : lab) pores += l == 2;
  const double eps = double(pores) / lab.size();
  EXPECT_DOUBLE_EQ(j["porosity"].get<double>(), eps);
  EXPECT_GT(eps, 0.3);
  // The walls close every channel along x: no spanning path, σ_eff = 0, τ = inf, exit 0.
  EXPECT_EQ(j["sigma_eff"]["x"].get<double>(), 0.0);
  EXPECT_TRUE(j["tortuosity"]["x"].is_null());
  EXPECT_NE(err.find("no spanning path"), std::string::npos) << err;
  // Along y the channels are straight (τ close to 1, above 1 by the segmented walls' roughness);
  // along z they are wavy: a longer path, τ_z > τ_y.
  for (const char* a : {"y", "z"}) {
    const auto& ax = j["axes"][a];
    EXPECT_TRUE(ax["percolates"].get<bool>()) << a;
    EXPECT_TRUE(ax["solver"]["converged"].get<bool>()) << a;
    EXPECT_LT(ax["sigma_eff_error"].get<double>(), 1e-6) << a;
    const double tau = ax["tortuosity"].get<double>();
    EXPECT_NEAR(tau, eps / ax["sigma_eff"].get<double>(), 1e-12 * tau) << a;
    EXPECT_GE(tau, 1.0) << a;
    EXPECT_LT(tau, 1.5) << a;
  }
  EXPECT_GT(j["tortuosity"]["z"].get<double>(), j["tortuosity"]["y"].get<double>());
  // Fields: potential in [0, 1] on the solved voxels, NaN elsewhere; an XDMF sidecar for ParaView.
  ASSERT_TRUE(fs::exists(path("fields.xdmf")));
  const h5::File f(path("fields.h5"), h5::File::Mode::read);
  std::vector<std::size_t> fd;
  const auto pot = f.read_double("/y/potential", &fd);
  EXPECT_EQ(fd, dims);
  std::size_t solved = 0;
  for (double p : pot)
    if (!std::isnan(p)) {
      ++solved;
      EXPECT_GE(p, -1e-9);
      EXPECT_LE(p, 1 + 1e-9);
    }
  EXPECT_EQ(solved, j["axes"]["y"]["solver"]["unknowns"].get<std::size_t>());
  EXPECT_TRUE(f.exists("/z/current_magnitude"));
  for (const auto& e : fs::directory_iterator(dir_))
    EXPECT_EQ(e.path().filename().string().find("tmp"), std::string::npos) << "temporary left: " << e.path();
}

}  // namespace
