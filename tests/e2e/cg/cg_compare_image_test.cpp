// tomodem-cg --compare-image: the worked example of docs/cg.md#image-and-model-side-by-side run
// as written on the bundled soil scan, and its refusals.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

namespace fs = std::filesystem;

namespace {
class CgCompareImage : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("tomodem-cg-compare-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  int sh(const std::string& cmd) const {
    const int st = std::system(("cd '" + dir_.string() + "' && " + cmd + " >> stdout.txt 2>> stderr.txt").c_str());
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  }
  std::string bin(const std::string& tool) const { return std::string(TOMODEM_BIN_DIR) + "/" + tool; }
  std::string src(const std::string& rel) const { return std::string(TOMODEM_SOURCE_DIR) + "/" + rel; }
  fs::path dir_;
};
}  // namespace

// The four commands of the docs. Checks against independent facts: the carved packing stands for
// the scan's material at the green packing's density (0.55), so where both are compared the two
// solid-fraction fields are nearly proportional (correlation > 0.9) and the packing's mean is
// 0.55 ± 0.1 of the scan's; the scan's solid spans every axis with 1 ≤ τ (a path is never shorter
// than straight); the fields file and its sidecar exist.
TEST_F(CgCompareImage, WorkedExampleOfTheDocsRunsAsWritten) {
  ASSERT_EQ(sh(bin("tomodem-segment") + " " + src("data/soil-sand-xct/corner100.mhd") + " -o labels.h5"), 0);
  ASSERT_EQ(sh(bin("tomodem-pack") + " " + src("docs/examples/carve/green.yaml") + " -o green.h5"), 0);
  ASSERT_EQ(sh(bin("tomodem-carve") + " green.h5 --labels labels.h5 --label-values 2 -o carved.h5"), 0);
  ASSERT_EQ(sh(bin("tomodem-cg") + " carved.h5 --compare-image labels.h5 --phase 0,1 --width 2 -o compare.h5 --json compare.json"), 0);
  std::ifstream in((dir_ / "compare.json").string());
  const nlohmann::json s = nlohmann::json::parse(in);
  const auto& c = s["compare"];
  EXPECT_GT(c["nodes_compared"].get<long>(), 1000);
  EXPECT_GT(c["correlation"].get<double>(), 0.9);
  const double ratio = c["mean_packing_solid_fraction"].get<double>() / c["mean_image_solid_fraction"].get<double>();
  EXPECT_NEAR(ratio, 0.55, 0.1);
  for (const char* ax : {"x", "y", "z"}) EXPECT_GE(s["tortuosity"]["image"][ax].get<double>(), 1.0) << ax;
  EXPECT_TRUE(fs::exists(dir_ / "compare.h5"));
  EXPECT_TRUE(fs::exists(dir_ / "compare.xdmf"));
  // A label the scan does not hold: exit 2, nothing written.
  EXPECT_EQ(sh(bin("tomodem-cg") + " carved.h5 --compare-image labels.h5 --phase 7 -o bad.h5 --json bad.json"), 2);
  EXPECT_FALSE(fs::exists(dir_ / "bad.h5"));
  EXPECT_FALSE(fs::exists(dir_ / "bad.json"));
}
