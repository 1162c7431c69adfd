// core/plot.hpp: PNG and SVG through gnuplot, with the data and script kept beside them.
#include "tomodem/core/plot.hpp"

#include <gtest/gtest.h>

#include <cmath>
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
  PlotSpec spec{"E against density", "relative density (-)", "E/E_s (-)", false, true,
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
  const std::string gp = slurp(stem.string() + ".gp");
  EXPECT_NE(gp.find("set logscale y"), std::string::npos);
  // y spans 0.01..0.5, more than a decade: powers of ten with minor ticks; x is linear.
  EXPECT_NE(gp.find("set format y '10^{%L}'"), std::string::npos) << gp;
  EXPECT_NE(gp.find("set mytics 10"), std::string::npos);
  EXPECT_EQ(gp.find("set format x"), std::string::npos);
  // The one house style is in every script, and the script sets no terminal of its own.
  EXPECT_NE(gp.find(plot_style()), std::string::npos);
  EXPECT_NE(plot_style().find("plot_terminal_png"), std::string::npos);
  for (const auto& e : std::filesystem::directory_iterator(dir))  // nothing left under a temporary name
    EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos) << e.path();
}

TEST_F(Plot, MismatchedSeriesIsInputError) {
  PlotSpec spec{"t", "x (m)", "y (m)", false, false, {{"bad", {1, 2}, {1}}}};
  EXPECT_THROW(write_plot(file("bad"), spec), InputError);
  EXPECT_FALSE(std::filesystem::exists(file("bad.dat")));
}

TEST(PlotLabels, UnitInClosingBrackets) {
  // Units as a reader of a paper expects them, and labels that state none.
  for (const auto& [label, unit] : std::vector<std::pair<std::string, std::string>>{
           {"time (s)", "s"}, {"load [N]", "N"}, {"strain (-)", "-"}, {"E/E_s [1]", "1"}, {"porosity (%)", "%"},
           {"K_IC (Pa m^0.5)", "Pa m^0.5"}, {"K (Pa m^{1/2})", "Pa m^{1/2}"}, {"grip opening (\u00b5m)", "\u00b5m"},
           {"opening (um) ", "um"}, {"conductivity (S/m)", "S/m"}, {"CPU time spent (s, sum over replicas)", "s"},
           {"rate (1/s)", "1/s"}, {"stiffness (GPa)", "GPa"}, {"area (m^2)", "m^2"}, {"energy (J m^-2)", "J m^-2"},
           {"a (f(x) in m)", ""}, {"time", ""}, {"neck ratio a/R (bin centre)", ""}, {"(s) time", ""}, {"count (per run)", ""},
           {"length (furlong)", ""}, {"x ()", ""}, {"", ""}, {"x (s", ""}})
    EXPECT_EQ(axis_label_unit(label), unit) << label;
}

TEST_F(Plot, LabelWithoutUnitIsRefusedBeforeAnythingIsWritten) {
  PlotSpec spec{"t", "time (s)", "relative density", false, false, {{"a", {1, 2}, {1, 2}}}};  // plot-label-check: bad on purpose
  try {
    write_plot(file("nounit"), spec);
    FAIL() << "a y label without a unit was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "ylabel");
    EXPECT_EQ(e.value(), "relative density");
  }
  spec.ylabel = "relative density (-)";
  spec.xlabel = "time";  // plot-label-check: bad on purpose
  EXPECT_THROW(write_plot(file("nounit"), spec), InputError);
  EXPECT_FALSE(std::filesystem::exists(file("nounit.dat")));
  EXPECT_FALSE(std::filesystem::exists(file("nounit.gp")));
}

TEST_F(Plot, StepsLinesBarsAndNarrowLogAxis) {
  ASSERT_TRUE(plotting_available()) << "gnuplot is not installed: apt-get install gnuplot-nox (tools/scripts/install-deps.sh)";
  PlotSeries hist{"necks", {0.05, 0.15, 0.25}, {0.2, 0.5, 0.3}, false, {0.01, 0.02, 0.01}, PlotDraw::steps};
  PlotSeries saw{"SLA events", {1, 2, 2, 1.5}, {2, 4, 3, 2.25}, false, {}, PlotDraw::lines};
  PlotSpec spec{"t", "x (m)", "y (N)", true, false, {hist, saw}};
  const std::filesystem::path stem = file("styles");
  write_plot(stem, spec);
  const std::string gp = slurp(stem.string() + ".gp");
  EXPECT_NE(gp.find("with histeps linetype 1"), std::string::npos) << gp;
  EXPECT_NE(gp.find("with yerrorbars linetype 1 pointsize 0 notitle"), std::string::npos) << gp;  // bars over the steps
  EXPECT_NE(gp.find("with lines linetype 2"), std::string::npos) << gp;
  // x spans 0.05..2 (more than a decade): 10^n; y is linear.
  EXPECT_NE(gp.find("set format x '10^{%L}'"), std::string::npos) << gp;
  // The saw-tooth keeps its points in order: the drop at x = 2 stays a vertical segment.
  EXPECT_NE(slurp(stem.string() + ".dat").find("2 4\n2 3\n1.5 2.25\n"), std::string::npos);
  // Bars are written as their ends (x y low high): y -/+ yerr, or ylow/yhigh where given (an
  // interval cut at a bound).
  EXPECT_NE(slurp(stem.string() + ".dat").find("0.05 0.2 0.19 0.21\n"), std::string::npos);
  EXPECT_NE(gp.find("using 1:2:3:4 with histeps"), std::string::npos) << gp;
  PlotSeries cut{"cut", {1, 2}, {0.1, 0.3}, true, {0.2, 0.1}};
  cut.ylow = {0, NAN};
  write_plot(stem, {"t", "x (m)", "y (N)", false, false, {cut}});
  EXPECT_NE(slurp(stem.string() + ".dat").find("1 0.1 0 0.3\n2 0.3 0.2 0.4\n"), std::string::npos) << slurp(stem.string() + ".dat");
  spec.series = {{"narrow", {2, 3, 5}, {1, 2, 3}}};  // x within one decade: plain numbers
  write_plot(stem, spec);
  EXPECT_NE(slurp(stem.string() + ".gp").find("set format x '%g'"), std::string::npos);
  EXPECT_EQ(slurp(stem.string() + ".png").substr(0, 4), std::string("\x89PNG", 4));
}

}  // namespace
}  // namespace tomodem
