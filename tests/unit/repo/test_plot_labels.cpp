// Every plot the repository defines states its axes with units (issue 21: figures a scientist
// would publish). The test finds plot definitions in the tracked files and checks each x and y
// label with core's axis_label_unit (the rule write_plot enforces when a tool draws):
//   - gnuplot scripts (*.gp) that plot: `set xlabel` and `set ylabel` present, each with a unit;
//   - scripts and docs that hold gnuplot commands (`set xlabel '...'` in .py/.sh/.md): each literal
//     label has a unit (templated ones, `{ylabel}`, are checked in the scripts they write);
//   - report plot specs (`--plot 'name=...;x=...;y=...'` in .yaml, .md, .sh, .py): xlabel= and
//     ylabel= present, each with a unit;
//   - C++ plot specs: `PlotSpec v{"title", "xlabel", "ylabel"...}` and `.xlabel = "..."` literals.
// A line holding `plot-label-check: bad on purpose` (tests of the refusal) is left out.
#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <sstream>

#include "repo_files.hpp"
#include "tomodem/core/plot.hpp"

namespace {

namespace fs = std::filesystem;

bool ends_with(const std::string& s, const std::string& e) {
  return s.size() >= e.size() && s.compare(s.size() - e.size(), e.size(), e) == 0;
}

// Problems with the plot definitions in one file's text ("" path suffix decides the kind).
std::vector<std::string> plot_label_problems(const std::string& path, const std::string& text) {
  std::vector<std::string> out;
  const auto check = [&](int line, const std::string& what, const std::string& label) {
    if (tomodem::axis_label_unit(label).empty())
      out.push_back(path + ":" + std::to_string(line) + ": " + what + " '" + label + "' has no unit in brackets at its end");
  };
  const bool gp = ends_with(path, ".gp"), cpp = ends_with(path, ".cpp") || ends_with(path, ".hpp");
  const bool script = ends_with(path, ".py") || ends_with(path, ".sh") || ends_with(path, ".md") || ends_with(path, ".yaml") ||
                      ends_with(path, ".yml");
  static const std::regex gp_label(R"re(set\s+([xy])label\s+(['"])((?:(?!\2).)*)\2)re");
  static const std::regex plot_spec(R"re(name=[A-Za-z0-9_-]+;(?:[^'"`]|'')*)re");  // '': a quote in YAML; ` ends one in Markdown
  static const std::regex spec_key(R"re((?:^|;)([xy])label=([^;]*))re");
  static const std::regex cpp_brace(R"re(PlotSpec\s+\w+\s*\{\s*"([^"]*)"\s*,\s*"([^"]*)"\s*,\s*"([^"]*)")re");
  static const std::regex cpp_assign(R"re(\.([xy])label\s*=\s*"([^"]*)")re");
  bool gp_plots = false, has[2] = {false, false};
  std::istringstream in(text);
  int n = 0;
  for (std::string line; std::getline(in, line);) {
    ++n;
    if (line.find("plot-label-check: bad on purpose") != std::string::npos) continue;
    if (gp || script)
      for (std::sregex_iterator m(line.begin(), line.end(), gp_label), e; m != e; ++m) {
        const std::string axis = (*m)[1], label = (*m)[3];
        has[axis == "y"] = true;
        if (label.find('{') == std::string::npos || tomodem::axis_label_unit(label) != "")
          check(n, axis + "label", label);
      }
    if (gp && std::regex_search(line, std::regex(R"re(^\s*plot\s)re"))) gp_plots = true;
    if (script)
      for (std::sregex_iterator m(line.begin(), line.end(), plot_spec), e; m != e; ++m) {
        const std::string spec = m->str();
        if (spec.find(";x=") == std::string::npos || spec.find(";y=") == std::string::npos) continue;
        bool found[2] = {false, false};
        for (std::sregex_iterator k(spec.begin(), spec.end(), spec_key), ke; k != ke; ++k) {
          found[(*k)[1] == "y"] = true;
          check(n, std::string((*k)[1]) + "label=", (*k)[2]);
        }
        for (int a = 0; a < 2; ++a)
          if (!found[a]) out.push_back(path + ":" + std::to_string(n) + ": --plot spec without " + (a ? "y" : "x") + "label=: " + spec);
      }
    if (cpp) {
      std::smatch m;
      if (std::regex_search(line, m, cpp_brace)) check(n, "PlotSpec xlabel", m[2]), check(n, "PlotSpec ylabel", m[3]);
      for (std::sregex_iterator k(line.begin(), line.end(), cpp_assign), ke; k != ke; ++k)
        check(n, std::string((*k)[1]) + "label", (*k)[2]);
    }
  }
  if (gp && gp_plots)
    for (int a = 0; a < 2; ++a)
      if (!has[a]) out.push_back(path + ": a gnuplot script that plots without set " + (a ? "y" : "x") + "label");
  return out;
}

TEST(PlotLabels, EveryPlotInTheRepositoryStatesUnits) {
  const fs::path root = TOMODEM_SOURCE_DIR;
  const auto files = tomodem::test::repository_files(root);
  ASSERT_FALSE(files.empty());
  std::size_t gp_files = 0, specs = 0;
  std::ostringstream problems;
  int count = 0;
  for (const auto& rel : files) {
    if (rel.find("tests/unit/repo/") == 0) continue;  // this test's own examples
    static const char* kinds[] = {".gp", ".py", ".sh", ".md", ".yaml", ".yml", ".cpp", ".hpp"};
    if (std::none_of(std::begin(kinds), std::end(kinds), [&](const char* k) { return ends_with(rel, k); })) continue;
    std::ifstream f(root / rel, std::ios::binary);
    std::ostringstream s;
    s << f.rdbuf();
    const std::string text = s.str();
    gp_files += ends_with(rel, ".gp");
    specs += text.find("xlabel") != std::string::npos;
    for (const auto& p : plot_label_problems(rel, text)) problems << p << "\n", ++count;
  }
  // The repository has plots (pipelines, tools, benchmarks): a scan that finds none is broken.
  EXPECT_GT(specs, 5u) << "too few files with plot labels found";
  EXPECT_EQ(count, 0) << "plots whose axes state no unit ('time (s)', 'strain (-)'):\n" << problems.str();
}

// The checker itself, on synthetic specifications: it must catch each kind of missing unit.
TEST(PlotLabels, CheckerFailsOnPlotsWithoutUnits) {
  EXPECT_TRUE(plot_label_problems("a.gp", "set xlabel 'time (s)'\nset ylabel \"load (N)\"\nplot 'a.dat'\n").empty());
  EXPECT_EQ(plot_label_problems("a.gp", "set xlabel 'time (s)'\nset ylabel 'load'\nplot 'a.dat'\n").size(), 1u);
  EXPECT_EQ(plot_label_problems("a.gp", "set xlabel 'time (s)'\nplot 'a.dat'\n").size(), 1u);  // no y label at all
  EXPECT_TRUE(plot_label_problems("p.yaml", "--plot, 'name=e;x=d;y=E;xlabel=density (-);ylabel=E (Pa)'").empty());
  EXPECT_EQ(plot_label_problems("p.yaml", "--plot, 'name=e;x=d;y=E;xlabel=density;ylabel=E (Pa)'").size(), 1u);
  EXPECT_EQ(plot_label_problems("p.md", "--plot 'name=e;x=d;y=E;logy'").size(), 2u);  // neither label
  EXPECT_TRUE(plot_label_problems("t.cpp", "PlotSpec d{\"T\", \"time (s)\", \"density (-)\", false};").empty());
  EXPECT_EQ(plot_label_problems("t.cpp", "PlotSpec d{\"T\", \"time (s)\", \"density\", false};").size(), 1u);
  EXPECT_EQ(plot_label_problems("t.cpp", "spec.xlabel = \"opening\";").size(), 1u);
  EXPECT_TRUE(plot_label_problems("t.cpp", "spec.xlabel = \"opening\";  // plot-label-check: bad on purpose").empty());
  EXPECT_EQ(plot_label_problems("s.py", "f.write(\"set ylabel 'efficiency'\\n\")").size(), 1u);
}

}  // namespace
