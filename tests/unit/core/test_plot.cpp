// core/plot.hpp: PNG and SVG through gnuplot, with the data and script kept beside them.
#include "tomodem/core/plot.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "tmpdir.hpp"
#include "tomodem/core/error.hpp"

namespace tomodem {
namespace {

class Plot : public test::TmpDir {};

std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST_F(Plot, WritesPngSvgDataAndScript) {
  // tools/scripts/install-deps.sh installs gnuplot: its absence is a broken install, not a skip.
  ASSERT_TRUE(plotting_available()) << "gnuplot is not installed: apt-get install gnuplot-nox (tools/scripts/install-deps.sh)";
  PlotSpec spec{"E against density", "relative density", "E/E_s", false, true,
                {{"homogeneous", {0.5, 0.7, 0.9}, {0.01, 0.1, 0.5}}, {"pore formers", {0.6}, {0.05}, true}}};
  const std::filesystem::path stem = file("young");
  write_plot(stem, spec);
  const std::string png = slurp(stem.string() + ".png");
  ASSERT_GE(png.size(), 8u);
  EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  const std::string svg = slurp(stem.string() + ".svg");
  EXPECT_NE(svg.find("<svg"), std::string::npos);
  EXPECT_NE(svg.find("pore formers"), std::string::npos);  // the legend names each series
  const std::string dat = slurp(stem.string() + ".dat");
  EXPECT_NE(dat.find("0.7 0.1\n"), std::string::npos);
  EXPECT_NE(slurp(stem.string() + ".gp").find("set logscale y"), std::string::npos);
  for (const auto& e : std::filesystem::directory_iterator(dir))  // nothing left under a temporary name
    EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos) << e.path();
}

TEST_F(Plot, MismatchedSeriesIsInputError) {
  PlotSpec spec{"t", "x", "y", false, false, {{"bad", {1, 2}, {1}}}};
  EXPECT_THROW(write_plot(file("bad"), spec), InputError);
  EXPECT_FALSE(std::filesystem::exists(file("bad.dat")));
}

}  // namespace
}  // namespace tomodem
