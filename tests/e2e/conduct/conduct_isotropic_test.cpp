// tomodem-conduct's isotropic estimate sigma_iso (docs/conduct.md): present only when all three
// axes are solved, equal to the mean of three single-axis runs and to the trace / 3 of the
// periodic tensor, checked against the HS bound as the mean of the axes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "../common/tool_test.hpp"
#include "tomodem/core/h5.hpp"

namespace {
class ConductIsotropic : public tomodem::test::ToolTest {
 protected:
  ConductIsotropic() : ToolTest("tomodem-conduct-iso-e2e") {}
  // The worked example's cathode: 50 % LSM, a few per cent apart between axes.
  static std::string cathode() { return std::string(TOMODEM_TEST_DATA) + "/examples/cathode.h5"; }
  nlohmann::json conduct(const std::string& args, const std::string& name) const {
    const int code = sh(bin("tomodem-conduct") + " " + cathode() + " --phases LSM -q " + args + " --json " + path(name));
    EXPECT_EQ(code, 0) << text("stderr.txt");
    return json(name);
  }
};
}  // namespace

TEST_F(ConductIsotropic, AllAxesGiveTheMeanOfThreeSingleAxisRuns) {
  const auto all = conduct("--axis zxy", "all.json");  // any order of the three letters
  double mean = 0, mean_error = 0, lo = 1e300, hi = 0;
  for (const char* axis : {"x", "y", "z"}) {
    const auto one = conduct(std::string("--axis ") + axis, std::string(axis) + ".json");
    EXPECT_FALSE(one.contains("sigma_iso")) << axis;  // one axis: no isotropic estimate
    const double s = one["sigma_eff"][axis].get<double>();
    mean += s / 3;
    mean_error += one["sigma_eff_error"][axis].get<double>() / 3;
    lo = std::min(lo, s);
    hi = std::max(hi, s);
  }
  EXPECT_GT(hi - lo, 1e-3 * mean);  // the axes differ: a mix-up would show
  // 1e-8 relative: the solves stop at the relative residual 1e-10 (sigma_eff_error is ~1e-10 of sigma).
  EXPECT_NEAR(all["sigma_iso"].get<double>() / mean, 1.0, 1e-8);
  EXPECT_NEAR(all["sigma_iso_error"].get<double>(), mean_error, 1e-8 * mean);
  EXPECT_LT(all["sigma_iso_error"].get<double>(), 1e-6 * mean);
  EXPECT_EQ(all["units"]["sigma_iso"], "S/m");
  const auto& b = all["bounds"];
  EXPECT_NEAR(b["sigma_iso_over_sigma_s"].get<double>(), mean / b["sigma_s"].get<double>(), 1e-8);
  EXPECT_FALSE(conduct("--axis xz", "xz.json").contains("sigma_iso"));  // two axes: none
}

TEST_F(ConductIsotropic, PeriodicTensorGivesTheMeanOfItsDiagonal) {
  const auto p = conduct("--bc periodic", "periodic.json");
  const auto& t = p["sigma_tensor"];
  const double trace = t[0][0].get<double>() + t[1][1].get<double>() + t[2][2].get<double>();
  // 1e-8 relative: the diagonal and sigma_eff come from the same three solves (tolerance 1e-10).
  EXPECT_NEAR(p["sigma_iso"].get<double>() / (trace / 3), 1.0, 1e-8);
}

// --image: a layered label volume (layers normal to z of labels 1 and 3, conductivities 0.5 and 1)
// is anisotropic by construction; sigma_iso (relative to sigma0) is the mean of the single-axis
// runs and its relative error the error-weighted mean of theirs.
TEST_F(ConductIsotropic, ImageAllAxesGiveTheMeanOfThreeSingleAxisRuns) {
  const std::size_t nx = 6, ny = 5, nz = 8;
  std::vector<uint8_t> v(nx * ny * nz, 1);
  for (std::size_t z = 0; z < nz; z += 2)
    for (std::size_t k = 0; k < nx * ny; ++k) v[z * nx * ny + k] = 3;
  {
    tomodem::h5::File f(path("layers.h5"), tomodem::h5::File::Mode::create);
    f.write("/labels", v, {nz, ny, nx});
    f.set_attr("/labels", "spacing", std::vector<double>{1e-6, 1e-6, 1e-6});
    f.close();
  }
  const auto image = [&](const std::string& axis, const std::string& name) {
    const int code = sh(bin("tomodem-conduct") + " --image layers.h5 --phase-conductivity 1:0.5,3:1 -q --axis " + axis +
                        " --json " + path(name));
    EXPECT_EQ(code, 0) << text("stderr.txt");
    return json(name);
  };
  const auto all = image("all", "all.json");
  double mean = 0, abs_error = 0;
  for (const char* axis : {"x", "y", "z"}) {
    const auto one = image(axis, std::string(axis) + ".json");
    const double s = one["sigma_eff"][axis].get<double>();
    mean += s / 3;
    abs_error += one["sigma_eff_error"][axis].get<double>() * s / 3;
  }
  // Along the layers the arithmetic mean 0.75 (parallel, exact); across them less (series).
  EXPECT_NEAR(all["sigma_eff"]["x"].get<double>(), 0.75, 1e-6);
  EXPECT_LT(all["sigma_eff"]["z"].get<double>(), 0.7);
  // 1e-8: the solves stop at the relative residual 1e-10.
  EXPECT_NEAR(all["sigma_iso"].get<double>() / mean, 1.0, 1e-8);
  EXPECT_NEAR(all["sigma_iso_error"].get<double>(), abs_error / mean, 1e-8);
  EXPECT_EQ(all["units"]["sigma_iso_error"], "relative");
}
