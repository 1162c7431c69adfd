// Results: rows from JSON summaries, the table, the plots' data (replica means) and the report.
// Expected numbers are written out by hand from the inputs, not taken from an earlier run.
#include <cmath>
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "scratch.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/plot.hpp"
#include "tomodem/pipeline/results.hpp"

using tomodem::test::Scratch;
namespace tp = tomodem::pipeline;
namespace fs = std::filesystem;

namespace {
std::string text(const tp::Row& r) {
  std::string s;
  for (const auto& [k, v] : r) s += k + "=" + v.text + (v.number ? "#" : "") + " ";
  return s;
}

// One row file per (family, density, replica) with E = density^2 * scale(family) * (1 + 0.1 replica).
std::vector<std::string> rows(const Scratch& s) {
  std::vector<std::string> files;
  for (const char* fam : {"a", "b"})
    for (const double d : {0.5, 0.8})
      for (int rep = 0; rep < 2; ++rep) {
        const double scale = fam[0] == 'a' ? 1e9 : 2e9;
        std::ostringstream young;
        young.precision(17);
        young << "{\"E\": " << d * d * scale * (1 + 0.1 * rep) << ", \"curve\": [1, 2], \"implicit\": {\"dofs\": 60}}";
        const std::string name = std::string(fam) + std::to_string(d) + "r" + std::to_string(rep);
        const auto y = s.write(name + "/young.json", young.str());
        const auto row = s.write(name + "/row.json",
                                 tp::make_row({"family=" + std::string(fam), "density=" + std::to_string(d).substr(0, 3),
                                               "replica=" + std::to_string(rep), "E_s=1e9"},
                                              {"young=" + y}));
        files.push_back(row);
      }
  return files;
}
}  // namespace

TEST(Results, FlattenKeepsScalarsWithDottedNamesAndDropsArrays) {
  const auto r = tp::flatten_json(R"({"E": 2.5e7, "ok": true, "axis": "x", "s": {"x": 1, "y": [1, 2]}, "n": null})",
                                  "young", "y.json");
  EXPECT_EQ(text(r), "young.E=25000000.0# young.ok=1# young.axis=x young.s.x=1# ");
  EXPECT_THROW(tp::flatten_json("[1, 2]", "p", "f.json"), tomodem::InputError);
  EXPECT_THROW(tp::flatten_json("{oops", "p", "f.json"), tomodem::InputError);
}

TEST(Results, RowNamesBadItems) {
  Scratch s;
  EXPECT_THROW(tp::make_row({"novalue"}, {}), tomodem::InputError);
  EXPECT_THROW(tp::make_row({}, {"young=" + s.path("missing.json")}), tomodem::InputError);
  try {
    tp::make_row({}, {"young=" + s.write("bad.json", "{")});
    FAIL();
  } catch (const tomodem::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.json"), std::string::npos) << e.what();
  }
}

TEST(Results, PlotSpecParsingAndErrors) {
  const auto p = tp::parse_plot(
      "name=E;x=density;y=E_rel,G_rel;legend=Young's modulus,shear modulus;by=family;logy;title=It's E;"
      "xlabel=relative density (-);ylabel=modulus / solid's [1]");
  EXPECT_EQ(p.x, "density");
  EXPECT_EQ(p.y, (std::vector<std::string>{"E_rel", "G_rel"}));
  EXPECT_EQ(p.by, "family");
  EXPECT_TRUE(p.logy);
  EXPECT_FALSE(p.logx);
  EXPECT_EQ(p.title, "It's E");
  EXPECT_EQ(p.xlabel, "relative density (-)");
  EXPECT_EQ(p.legend, (std::vector<std::string>{"Young's modulus", "shear modulus"}));
  // Axis labels need their unit (core/plot.hpp): missing, or a column name alone, is refused.
  EXPECT_THROW(tp::parse_plot("name=p;x=a;y=b;ylabel=b (s)"), tomodem::InputError);
  EXPECT_THROW(tp::parse_plot("name=p;x=a;y=b;xlabel=a (s);ylabel=b"), tomodem::InputError);
  EXPECT_THROW(tp::parse_plot("name=p;x=a;y=b;xlabel=a (s);ylabel=b (per run)"), tomodem::InputError);
  EXPECT_THROW(tp::parse_plot("name=p;x=a;y=b,c;legend=one;xlabel=a (s);ylabel=b (s)"), tomodem::InputError);  // 2 y, 1 name
  EXPECT_THROW(tp::parse_plot("x=a;y=b"), tomodem::InputError);              // no name
  EXPECT_THROW(tp::parse_plot("name=p;x=a"), tomodem::InputError);           // no y
  EXPECT_THROW(tp::parse_plot("name=p;x=a;y=b;logz"), tomodem::InputError);  // unknown flag
  EXPECT_THROW(tp::parse_plot("name=a/b;x=a;y=b"), tomodem::InputError);     // not a file name
}

TEST(Results, TableRatiosPlotMeansAndReport) {
  Scratch s;
  const auto files = rows(s);
  tp::ReportOptions o;
  o.title = "t";
  o.columns = {"family", "density", "replica", "young.E", "E_rel"};
  o.ratios = {"E_rel=young.E/E_s"};
  o.plots = {"name=stiffness;x=density;y=E_rel;by=family;logy;xlabel=relative density (-);ylabel=E/E_s (-)"};
  // tools/scripts/install-deps.sh installs gnuplot: its absence is a broken install, not a skip.
  ASSERT_TRUE(tomodem::plotting_available()) << "gnuplot is not installed: apt-get install gnuplot-nox (tools/scripts/install-deps.sh)";
  const auto f = tp::write_report(s.path("report"), files, o);
  EXPECT_EQ(f.rows, 8u);
  // The table: selected columns in order; E_rel = E / 1e9 = density^2 * scale * (1 + 0.1 replica).
  std::istringstream csv(s.read("report/table.csv"));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "family,density,replica,young.E,E_rel");
  int n = 0;
  while (std::getline(csv, line)) {
    char fam = 0;
    double d = 0, rep = 0, e = 0, rel = 0;
    ASSERT_EQ(std::sscanf(line.c_str(), "%c,%lf,%lf,%lf,%lf", &fam, &d, &rep, &e, &rel), 5) << line;
    const double expect = d * d * (fam == 'a' ? 1 : 2) * (1 + 0.1 * rep);
    EXPECT_NEAR(rel, expect, 1e-9 * expect) << line;  // 10 significant digits printed
    ++n;
  }
  EXPECT_EQ(n, 8);
  // The plot data: per family, the mean of the two replicas (factor 1.05) at each density.
  std::istringstream dat(s.read("report/stiffness.dat"));
  std::vector<double> y;
  for (std::string l; std::getline(dat, l);) {
    double a = 0, b = 0;
    if (std::sscanf(l.c_str(), "%lf %lf", &a, &b) == 2) y.push_back(b);
  }
  const std::vector<double> expect = {0.25 * 1.05, 0.64 * 1.05, 0.5 * 1.05, 1.28 * 1.05};
  ASSERT_EQ(y.size(), expect.size());
  for (std::size_t k = 0; k < y.size(); ++k) EXPECT_NEAR(y[k], expect[k], 1e-9 * expect[k]);
  for (const char* file : {"stiffness.png", "stiffness.svg", "stiffness.gp", "index.html"})
    EXPECT_TRUE(fs::exists(s.path(std::string("report/") + file))) << file;
  const std::string html = s.read("report/index.html");
  EXPECT_NE(html.find("href=\"table.csv\""), std::string::npos);
  EXPECT_NE(html.find("<img src=\"stiffness.svg\""), std::string::npos);
  EXPECT_FALSE(fs::exists(s.path("report.tmp")));
}

TEST(Results, BadReportRequestsWriteNothing) {
  Scratch s;
  const auto files = rows(s);
  const auto bad = [&](tp::ReportOptions o) {
    EXPECT_THROW(tp::write_report(s.path("report"), files, o), tomodem::InputError);
    EXPECT_FALSE(fs::exists(s.path("report")));
  };
  tp::ReportOptions o;
  o.columns = {"family", "nope"};
  bad(o);
  o = {};
  o.ratios = {"r=young.E/missing"};
  bad(o);
  o = {};
  o.plots = {"name=p;x=density;y=nope;xlabel=relative density (-);ylabel=nope (-)"};
  bad(o);
  EXPECT_THROW(tp::write_report(s.path("report"), {s.write("x.json", "{\"E\": {\"a\": 1}}")}, {}), tomodem::InputError);
}

// The same family b with its E_error marked random: the interval is the replicas' alone,
// u = sem = 1.4142, dof = n - 1 = 4, half-width = t_{0.975,4} sem = 2.77645 * 1.41421 = 3.9265.
TEST(Results, RandomToolErrorLeavesTheReplicaInterval) {
  Scratch s;
  std::vector<std::string> files;
  for (int r = 0; r < 5; ++r)
    files.push_back(s.write("b" + std::to_string(r) + ".json",
                            "{\"family\": \"b\", \"replica\": " + std::to_string(r) + ", \"E\": " + std::to_string(3 + 2 * r) +
                                ", \"E_error\": 0.1, \"E_error_kind\": \"random\"}"));
  tp::ReportOptions o;
  o.group = {"family"};
  o.plots = {};
  tp::write_report(s.path("report"), files, o);
  const std::string j = s.read("report/summary.json");
  const auto number_after = [&](const std::string& key) {
    const auto at = j.find("\"" + key + "\":");
    return std::stod(j.substr(at + key.size() + 3));
  };
  EXPECT_NEAR(number_after("tool_error"), 0, 1e-12);
  EXPECT_NEAR(number_after("u"), 1.41421, 1e-5);
  EXPECT_NEAR(number_after("dof"), 4, 1e-9);
  EXPECT_NEAR(number_after("half_width95"), 2.77645 * 1.41421, 5e-5);  // t_{0.975,4} = 2.77645
}

// The worked example of docs/pipelines.md ("Statistics"): two families of five replicas.
// a: E = 1..5 (mean 3, sd 1.5811, sem 0.70711), b: E = 3, 5, .., 11 (mean 7, sd 3.1623,
// sem 1.4142). 95 % CI of a: 3 -/+ t_{0.975,4} sem = 3 -/+ 2.776 * 0.70711 = [1.037, 4.963].
// Welch: t = 4 / sqrt(0.5 + 2) = 2.5298, dof = 5.8824, p = 0.045 -> "a < b in E: Welch p = 0.045".
// b carries a tool error E_error = 0.1 (relative): tool = 0.1 * mean over replicas = 0.7, so
// u = sqrt(2 + 0.49) = 1.5780 and dof = u^4 / (sem^4 / 4) = 6.2001.
TEST(Results, WorkedExampleOfTheDocs) {
  // The README's install script installs gnuplot: a missing one is a broken install, not a skip.
  ASSERT_TRUE(tomodem::plotting_available()) << "gnuplot is not installed (Debian package gnuplot-nox)";
  Scratch s;
  std::vector<std::string> files;
  for (int r = 0; r < 5; ++r) {
    files.push_back(s.write("a" + std::to_string(r) + ".json",
                            "{\"family\": \"a\", \"replica\": " + std::to_string(r) + ", \"E\": " + std::to_string(1 + r) +
                                ", \"cpu_time_s\": 2}"));
    files.push_back(s.write("b" + std::to_string(r) + ".json",
                            "{\"family\": \"b\", \"replica\": " + std::to_string(r) + ", \"E\": " + std::to_string(3 + 2 * r) +
                                ", \"E_error\": 0.1, \"cpu_time_s\": 3}"));
  }
  tp::ReportOptions o;
  o.group = {"family"};
  const auto f = tp::write_report(s.path("report"), files, o);
  EXPECT_EQ(f.cells, 2u);
  EXPECT_EQ(f.rankings, 1u);
  const std::string j = s.read("report/summary.json");
  // Pull numbers out of the JSON text without a JSON library in this test.
  const auto number_after = [&](std::size_t from, const std::string& key) {
    const auto at = j.find("\"" + key + "\":", from);
    return std::stod(j.substr(at + key.size() + 3));
  };
  const auto a = j.find("\"family\": \"a\""), b = j.find("\"family\": \"b\"");
  ASSERT_NE(a, std::string::npos);
  ASSERT_NE(b, std::string::npos);
  EXPECT_NEAR(number_after(a, "mean"), 3, 1e-12);
  EXPECT_NEAR(number_after(a, "sem"), 0.70711, 1e-5);
  EXPECT_NEAR(number_after(a, "half_width95"), 2.776 * 0.70711, 5e-4);
  EXPECT_NEAR(number_after(a, "cpu_s"), 10, 1e-12);
  EXPECT_NEAR(number_after(b, "tool_error"), 0.7, 1e-12);
  EXPECT_NEAR(number_after(b, "u"), 1.5780, 1e-4);
  EXPECT_NEAR(number_after(b, "dof"), 6.2001, 1e-4);
  EXPECT_NE(j.find("\"stopped_because\": \"fixed replicas\""), std::string::npos);
  EXPECT_NE(j.find("a < b in E: Welch p = 0.045"), std::string::npos) << j;
  EXPECT_NEAR(number_after(j.find("\"rankings\""), "dof"), 5.8824, 1e-4);
}

// A per-axis value finds its tool error in both layouts, with its unit: `E.x_error` relative by
// default; tomodem-conduct's `sigma_eff_error.x` under `units.sigma_eff_error` ("S/m": absolute,
// "relative": times the value).
TEST(Results, PerAxisToolErrorsInBothLayouts) {
  const auto row = [](const std::string& json) { return tp::flatten_json(json, "c", "summary.json"); };
  EXPECT_NEAR(tp::own_error(row(R"({"E": {"x": 10, "x_error": 0.02}})"), "c.E.x", 10), 0.2, 1e-12);
  EXPECT_NEAR(tp::own_error(row(R"({"sigma_eff": {"x": 10}, "sigma_eff_error": {"x": 0.5},
                                   "units": {"sigma_eff_error": "S/m"}})"), "c.sigma_eff.x", 10), 0.5, 1e-12);
  EXPECT_NEAR(tp::own_error(row(R"({"sigma_eff": {"x": 10}, "sigma_eff_error": {"x": 0.5},
                                   "units": {"sigma_eff_error": "relative"}})"), "c.sigma_eff.x", 10), 5.0, 1e-12);
  EXPECT_TRUE(std::isnan(tp::own_error(row(R"({"sigma_eff": {"x": 10}})"), "c.sigma_eff.x", 10)));
}

// An error marked random (`K_IC_error_kind: "random"`, as tomodem-fracture writes for its
// crack-tip discreteness) is already in the replicas' scatter: it is no tool error to add again,
// in either layout; any other kind (or none) stays systematic.
TEST(Results, RandomToolErrorsAreNotAddedAgain) {
  const auto row = [](const std::string& json) { return tp::flatten_json(json, "f", "summary.json"); };
  EXPECT_TRUE(std::isnan(tp::own_error(row(R"({"K_IC": 2, "K_IC_error": 0.3, "K_IC_error_kind": "random"})"), "f.K_IC", 2)));
  EXPECT_NEAR(tp::own_error(row(R"({"K_IC": 2, "K_IC_error": 0.3, "K_IC_error_kind": "systematic"})"), "f.K_IC", 2), 0.6, 1e-12);
  EXPECT_TRUE(std::isnan(tp::own_error(row(R"({"sigma_eff": {"x": 10}, "sigma_eff_error": {"x": 0.5},
                                             "sigma_eff_error_kind": "random"})"), "f.sigma_eff.x", 10)));
}

// --bound: a 95 % interval that reaches past a physical bound is cut at it (the true mean lies
// within the bound, so the cut interval covers it at least as often), and a replica outside its
// own bound is listed. Family a (three sub-volumes of one scan, E_rel as in the demo):
// 0.0386, 0.0121, 0.0298: mean 0.026833, sd 0.013497, sem 0.0077924, t_{0.975,2} = 4.3027,
// half-width 0.033528: [-0.006695, 0.060361] -> [0, 0.060361] with E_rel=0:voigt (0.4 per row).
// Family c, nu = 0.49, 0.45, 0.40 with nu=-1:0.5: mean 0.44667, sd 0.045092, sem 0.026034,
// half-width 0.11202: [0.33465, 0.55868] -> [0.33465, 0.5]. Family b has one E_rel of 0.5
// above its row's Voigt bound 0.4: listed.
TEST(Results, IntervalsAreCutAtPhysicalBoundsAndValuesOutsideThemListed) {
  ASSERT_TRUE(tomodem::plotting_available()) << "gnuplot is not installed (Debian package gnuplot-nox)";
  Scratch s;
  std::vector<std::string> files;
  const double e_a[] = {0.0386, 0.0121, 0.0298}, e_b[] = {0.02, 0.5, 0.03}, nu_c[] = {0.49, 0.45, 0.40};
  for (int r = 0; r < 3; ++r) {
    std::ostringstream a, b, c;
    a.precision(17);
    b.precision(17);
    c.precision(17);
    a << "{\"family\": \"a\", \"replica\": " << r << ", \"density\": 0.4, \"voigt\": 0.4, \"E_rel\": " << e_a[r] << ", \"nu\": 0.2}";
    b << "{\"family\": \"b\", \"replica\": " << r << ", \"density\": 0.4, \"voigt\": 0.4, \"E_rel\": " << e_b[r] << ", \"nu\": 0.2}";
    c << "{\"family\": \"c\", \"replica\": " << r << ", \"density\": 0.4, \"voigt\": 0.4, \"E_rel\": 0.1, \"nu\": " << nu_c[r] << "}";
    files.push_back(s.write("a" + std::to_string(r) + ".json", a.str()));
    files.push_back(s.write("b" + std::to_string(r) + ".json", b.str()));
    files.push_back(s.write("c" + std::to_string(r) + ".json", c.str()));
  }
  tp::ReportOptions o;
  o.group = {"family"};
  o.stats = {"E_rel", "nu"};
  o.bounds = {"E_rel=0:voigt", "nu=-1:0.5"};
  o.plots = {"name=stiffness;x=density;y=E_rel;by=family;xlabel=relative density (-);ylabel=E/E_s (-)"};
  const auto f = tp::write_report(s.path("report"), files, o);
  ASSERT_EQ(f.outside_bounds.size(), 1u);
  EXPECT_NE(f.outside_bounds[0].find("b1.json: E_rel = 0.5 is above its upper bound 0.4 (voigt)"), std::string::npos)
      << f.outside_bounds[0];
  const std::string j = s.read("report/summary.json");
  // The cell of `family` F and `property` P: the text from its "family" key to the next cell.
  const auto cell = [&](const std::string& fam, const std::string& prop) {
    for (std::size_t at = j.find("\"family\": \"" + fam + "\""); at != std::string::npos; at = j.find("\"family\": \"" + fam + "\"", at + 1)) {
      const std::string c = j.substr(at, j.find('}', at) - at);
      if (c.find("\"property\": \"" + prop + "\"") != std::string::npos) return c;
    }
    return std::string();
  };
  const auto ci = [&](const std::string& c) {
    const auto at = c.find("\"ci95\": [");
    const std::string rest = c.substr(at + 9);
    return std::pair{std::stod(rest), std::stod(rest.substr(rest.find(',') + 1))};
  };
  const std::string a = cell("a", "E_rel"), b = cell("b", "E_rel"), cnu = cell("c", "nu");
  ASSERT_FALSE(a.empty() || b.empty() || cnu.empty()) << j;
  EXPECT_EQ(ci(a).first, 0.0);
  EXPECT_NEAR(ci(a).second, 0.060361, 2e-6);
  EXPECT_NE(a.find("\"ci95_cut_at_bound\": true"), std::string::npos) << a;
  EXPECT_NEAR(ci(cnu).first, 0.33465, 2e-5);
  EXPECT_EQ(ci(cnu).second, 0.5);
  // b: mean 0.18333 (inside [0, 0.4]), sd 0.27429, half-width 0.68137: [-0.49803, 0.86470] is cut
  // at both ends; its replica outside the bound is listed above.
  EXPECT_EQ(ci(b).first, 0.0);
  EXPECT_EQ(ci(b).second, 0.4);
  EXPECT_NE(j.find("\"outside_bounds\": ["), std::string::npos);
  EXPECT_NE(j.find("b1.json"), std::string::npos);
  // The plot's bar ends are the cut interval (x y low high).
  EXPECT_NE(s.read("report/stiffness.dat").find("0.4 0.02683333333 0 0.06036"), std::string::npos) << s.read("report/stiffness.dat");
  const std::string html = s.read("report/index.html");
  EXPECT_NE(html.find("cut at the property's physical bound"), std::string::npos);
  EXPECT_NE(html.find("outside their physical bounds"), std::string::npos);
}

TEST(Results, BadBoundsWriteNothing) {
  Scratch s;
  const auto files = rows(s);
  for (const std::string spec : {"young.E", "young.E=0", "nope=0:1", "young.E=:", "young.E=1:0", "young.E=0:missing", "young.E=0:inf", "family=0:1"}) {
    tp::ReportOptions o;
    o.bounds = {spec};
    EXPECT_THROW(tp::write_report(s.path("report"), files, o), tomodem::InputError) << spec;
    EXPECT_FALSE(fs::exists(s.path("report"))) << spec;
  }
  tp::ReportOptions o;
  o.bounds = {"young.E=0:", "young.E=:1e12"};
  EXPECT_THROW(tp::write_report(s.path("report"), files, o), tomodem::InputError);
}

namespace {
// Row files NAME.json from {"family": F, "y": Y, ...extra}: one replica each.
std::string row_file(const Scratch& s, const std::string& name, const std::string& fields) {
  return s.write(name + ".json", "{" + fields + "}");
}

// The cells of summary.json for `property`, by the value of `family`.
std::map<std::string, nlohmann::json> cells_of(const nlohmann::json& summary, const std::string& property) {
  std::map<std::string, nlohmann::json> out;
  for (const auto& c : summary.at("cells"))
    if (c.at("property") == property) out[c.at("family").get<std::string>()] = c;
  return out;
}

// The message of the InputError that `f` throws ("" when it throws none).
template <class F>
std::string input_error(F f) {
  try {
    f();
  } catch (const tomodem::InputError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

// One file named twice (another spelling of its path) would be two replicas of one result, with
// an interval of zero width: refused, naming both arguments, nothing written.
TEST(Results, OneRowFileGivenTwiceIsRefused) {
  Scratch s;
  const auto a = row_file(s, "a", R"("family": "a", "y": 2)"), b = row_file(s, "b", R"("family": "a", "y": 3)");
  fs::create_directories(s.path("sub"));
  for (const std::string again : {a, s.dir + "/./a.json", s.dir + "/sub/../a.json"}) {
    tp::ReportOptions o;
    o.group = {"family"};
    const std::string what = input_error([&] { tp::write_report(s.path("report"), {a, b, again}, o); });
    EXPECT_NE(what.find("given twice"), std::string::npos) << again << ": " << what;
    EXPECT_NE(what.find("'" + again + "'"), std::string::npos) << what;
    EXPECT_NE(what.find("'" + a + "'"), std::string::npos) << what;
    EXPECT_FALSE(fs::exists(s.path("report")));
  }
}

// A cell of one replica has a mean and no interval: the page says "n = 1: no interval", the plot
// draws its point without a bar (a series of its own, titled so), summary.json has dof null,
// and the cell is listed under not_ranked rather than silently left out of the rankings.
// Family a: y = 1, 2, 3 (n = 3: dof 2); family b: y = 5 (n = 1).
TEST(Results, OneReplicaCellsSayTheyHaveNoInterval) {
  ASSERT_TRUE(tomodem::plotting_available()) << "gnuplot is not installed (Debian package gnuplot-nox)";
  Scratch s;
  std::vector<std::string> files;
  for (int r = 0; r < 3; ++r) files.push_back(row_file(s, "a" + std::to_string(r), R"("family": "a", "x": 1, "y": )" + std::to_string(1 + r)));
  files.push_back(row_file(s, "b0", R"("family": "b", "x": 1, "y": 5)"));
  tp::ReportOptions o;
  o.group = {"family"};
  o.plots = {"name=p;x=x;y=y;by=family;xlabel=x (-);ylabel=y (-)"};
  const auto f = tp::write_report(s.path("report"), files, o);
  const auto summary = nlohmann::json::parse(s.read("report/summary.json"));
  auto cells = cells_of(summary, "y");
  ASSERT_EQ(cells.size(), 2u) << summary.dump(1);
  EXPECT_NEAR(cells["a"].at("dof").get<double>(), 2, 1e-12);
  EXPECT_EQ(cells["b"].at("n"), 1);
  EXPECT_EQ(cells["b"].at("mean"), 5.0);
  EXPECT_TRUE(cells["b"].at("dof").is_null()) << cells["b"];  // was 0.0
  EXPECT_TRUE(cells["b"].at("ci95").is_null());
  EXPECT_TRUE(summary.at("rankings").empty());
  ASSERT_EQ(summary.at("not_ranked").size(), 1u) << summary.dump(1);
  EXPECT_EQ(summary.at("not_ranked")[0].at("family"), "b");
  EXPECT_EQ(summary.at("not_ranked")[0].at("property"), "y");
  ASSERT_EQ(f.not_ranked.size(), 1u);
  EXPECT_EQ(f.not_ranked[0], "family=b: y has 1 replica, not ranked (Welch's test needs 2 or more)");
  const std::string html = s.read("report/index.html");
  EXPECT_NE(html.find("<td>5</td><td>n = 1: no interval</td>"), std::string::npos) << html;
  EXPECT_NE(html.find("Not ranked (fewer than 2 replicas)"), std::string::npos);
  // The plot data: a's point with its bar ends (x y low high), b's point alone in its own series.
  const std::string dat = s.read("report/p.dat");
  EXPECT_NE(dat.find("# b (n = 1: no interval)\n1 5\n"), std::string::npos) << dat;
  EXPECT_NE(dat.find("# a\n1 2 "), std::string::npos) << dat;
}

// A --bound side naming a column must give a number in every row that has the bounded column:
// a row without it, or with text in it, would go unchecked. Refused naming the row file.
TEST(Results, BoundColumnsMustHoldANumberInEveryBoundedRow) {
  Scratch s;
  const auto b1 = row_file(s, "b1", R"("family": "b", "y": 5, "ub": 10)");
  const auto b2 = row_file(s, "b2", R"("family": "b", "y": 6)");
  const auto b3 = row_file(s, "b3", R"("family": "b", "y": 7, "ub": "n/a")");
  const auto c1 = row_file(s, "c1", R"("family": "c", "ub": "n/a")");  // no y: nothing to bound
  tp::ReportOptions o;
  o.group = {"family"};
  o.bounds = {"y=0:ub"};
  for (const auto& [rows, bad] : {std::pair{std::vector<std::string>{b1, b2}, b2}, std::pair{std::vector<std::string>{b1, b3}, b3}}) {
    const std::string what = input_error([&] { tp::write_report(s.path("report"), rows, o); });
    EXPECT_NE(what.find(bad), std::string::npos) << what;
    EXPECT_NE(what.find("'ub'"), std::string::npos) << what;
    EXPECT_FALSE(fs::exists(s.path("report")));
  }
  o.bounds = {"y=family:"};  // a text column as a bound
  EXPECT_THROW(tp::write_report(s.path("report"), {b1}, o), tomodem::InputError);
  o.bounds = {"y=0:ub"};
  EXPECT_NO_THROW(tp::write_report(s.path("report"), {b1, c1}, o));
}

// A cell whose mean lies outside its bound: its interval is still cut at the bound the mean is
// within, and the cell itself is flagged (summary.json, page, warning). y = 0.095, 0.100, 0.108
// with y=0.09:0.10: mean 0.101, sd = sqrt(86e-6 / 2) = 0.0065574, sem 0.0037859,
// t_{0.975,2} = 4.3027: [0.08471, 0.11729] -> [0.09, 0.11729] (the mean is above 0.10).
TEST(Results, AMeanOutsideItsBoundIsFlaggedAndCutAtTheOtherBound) {
  Scratch s;
  std::vector<std::string> files;
  int k = 0;
  for (const char* y : {"0.095", "0.100", "0.108"}) files.push_back(row_file(s, "r" + std::to_string(k++), std::string(R"("family": "a", "y": )") + y));
  tp::ReportOptions o;
  o.group = {"family"};
  o.bounds = {"y=0.09:0.10"};
  const auto f = tp::write_report(s.path("report"), files, o);
  const auto summary = nlohmann::json::parse(s.read("report/summary.json"));
  const auto a = cells_of(summary, "y").at("a");
  EXPECT_NEAR(a.at("mean").get<double>(), 0.101, 1e-12);
  EXPECT_EQ(a.at("ci95")[0].get<double>(), 0.09) << a;
  EXPECT_NEAR(a.at("ci95")[1].get<double>(), 0.101 + 4.30265 * 0.0037859, 2e-6) << a;
  EXPECT_TRUE(a.at("ci95_cut_at_bound").get<bool>());
  EXPECT_TRUE(a.at("mean_outside_bound").get<bool>());
  ASSERT_EQ(f.outside_bounds.size(), 1u);  // the replica 0.108
  ASSERT_EQ(f.warnings.size(), 1u);
  EXPECT_EQ(f.warnings[0], "family=a: the mean of y, 0.101, is outside its bound [0.09, 0.1]");
  EXPECT_NE(s.read("report/index.html").find("mean outside its bound"), std::string::npos);
  // Inside its bound, the flag is false.
  o.bounds = {"y=0.09:0.2"};
  tp::write_report(s.path("report"), files, o);
  EXPECT_FALSE(cells_of(nlohmann::json::parse(s.read("report/summary.json")), "y").at("a").at("mean_outside_bound").get<bool>());
}

// --ratio NAME=A/B: a NAME that is taken (a column, another ratio) or a divisor of the number 0
// is refused; a divisor column that is 0 in some rows leaves the ratio empty there, with a
// warning naming those rows.
TEST(Results, RatiosRefuseTakenNamesAndADivisorOfZero) {
  Scratch s;
  const auto r1 = row_file(s, "r1", R"("family": "a", "y": 2, "z": 0)");
  const auto r2 = row_file(s, "r2", R"("family": "a", "y": 3, "z": 1)");
  const auto r3 = row_file(s, "r3", R"("family": "a", "y": 4, "z": 0)");
  for (const std::vector<std::string> ratios :
       {std::vector<std::string>{"y=y/2"}, {"r=y/2", "r=y/3"}, {"r=y/0"}, {"r=y/0.0"}, {"r=y/2", "q=r/y", "q=y/3"}}) {
    tp::ReportOptions o;
    o.ratios = ratios;
    const std::string what = input_error([&] { tp::write_report(s.path("report"), {r1, r2, r3}, o); });
    EXPECT_NE(what.find("--ratio"), std::string::npos) << ratios.back() << ": " << what;
    EXPECT_FALSE(fs::exists(s.path("report")));
  }
  tp::ReportOptions o;
  o.ratios = {"r=y/z"};
  const auto f = tp::write_report(s.path("report"), {r1, r2, r3}, o);
  ASSERT_EQ(f.warnings.size(), 1u);
  EXPECT_EQ(f.warnings[0], "--ratio r=y/z: 'z' is 0 in " + r1 + ", " + r3 + ", so 'r' is empty there");
}

// Small inconsistencies: a column named twice in --stats, --columns or --group is refused; a row
// without a group column (a cell of its own with an empty value) is refused naming the row; dof
// is a number or null (no replica scatter: infinite, and JSON has no infinity), never "inf".
TEST(Results, RepeatsRowsWithoutTheGroupAndInfiniteDof) {
  Scratch s;
  const auto a1 = row_file(s, "a1", R"("family": "a", "y": 2)");
  const auto a2 = row_file(s, "a2", R"("family": "a", "y": 2)");
  const auto none = row_file(s, "none", R"("y": 3)");
  const auto bad = [&](tp::ReportOptions o, const std::vector<std::string>& rows, const std::string& expect) {
    const std::string what = input_error([&] { tp::write_report(s.path("report"), rows, o); });
    EXPECT_NE(what.find(expect), std::string::npos) << what;
    EXPECT_FALSE(fs::exists(s.path("report")));
  };
  tp::ReportOptions o;
  o.stats = {"y", "y"};
  bad(o, {a1, a2}, "named twice");
  o = {};
  o.columns = {"family", "y", "y"};
  bad(o, {a1, a2}, "named twice");
  o = {};
  o.group = {"family", "family"};
  bad(o, {a1, a2}, "named twice");
  o = {};
  o.group = {"family"};
  bad(o, {a1, a2, none}, none);
  o.stats = {"y"};  // a constant column is no property by default
  tp::write_report(s.path("report"), {a1, a2}, o);
  const auto a = cells_of(nlohmann::json::parse(s.read("report/summary.json")), "y").at("a");
  EXPECT_TRUE(a.at("dof").is_null()) << a;
  EXPECT_EQ(a.at("sd").get<double>(), 0.0);
}
