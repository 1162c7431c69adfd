// The study's CI variant (pipelines/study.yaml --set scale=small, issue 18 item 9): the sintering route and
// the homothetic one for 150-particle packings, adaptive replicas, the report. The test copies the
// pipeline to a temporary folder, runs it with -j 2, and recomputes from the replica table it
// wrote (table.csv: every replica) what the report and the runner say: the 95 % intervals
// (Student t, tool errors added), the adaptive stop of every group, and every Welch ranking.
// The t distribution is computed here by integrating its density (Simpson), independently of
// libs/pipeline's incomplete-beta continued fraction, and checked against the printed table.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// ---- Student's t by quadrature: P(T <= t) = 1/2 + integral_0^t f(x) dx, f the t density.
double t_cdf(double t, double nu) {
  const double c = std::exp(std::lgamma((nu + 1) / 2) - std::lgamma(nu / 2)) / std::sqrt(nu * M_PI);
  const auto f = [&](double x) { return c * std::pow(1 + x * x / nu, -(nu + 1) / 2); };
  const double a = std::abs(t);
  const int n = 20000;  // Simpson on [0, |t|]: |t| < 50 here, error far below 1e-8
  const double h = a / n;
  double s = f(0) + f(a);
  for (int k = 1; k < n; ++k) s += (k % 2 ? 4 : 2) * f(k * h);
  const double half = s * h / 3;
  return t >= 0 ? 0.5 + half : 0.5 - half;
}
double t975(double nu) {
  double lo = 0, hi = 100;
  for (int k = 0; k < 80; ++k) {
    const double mid = 0.5 * (lo + hi);
    (t_cdf(mid, nu) < 0.975 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

struct Cell {
  double mean = 0, sd = 0, sem = 0, e = 0, u = 0, dof = 0, half = 0;
};
/// mean, sd, sem; the tool error e = mean of rel_i |x_i|; u = sqrt(sem^2 + e^2); Welch-Satterthwaite
/// dof u^4 / (sem^4 / (n - 1)); half-width t975(dof) u (docs/pipelines.md, Statistics).
Cell stats(const std::vector<double>& x, const std::vector<double>& rel) {
  Cell c;
  const double n = double(x.size());
  for (double v : x) c.mean += v / n;
  for (double v : x) c.sd += (v - c.mean) * (v - c.mean);
  c.sd = std::sqrt(c.sd / (n - 1));
  c.sem = c.sd / std::sqrt(n);
  for (std::size_t i = 0; i < x.size(); ++i) c.e += (rel.empty() ? 0 : rel[i]) * std::abs(x[i]) / n;
  c.u = std::sqrt(c.sem * c.sem + c.e * c.e);
  c.dof = std::pow(c.u, 4) / (std::pow(c.sem, 4) / (n - 1));
  c.half = t975(c.dof) * c.u;
  return c;
}

/// table.csv as column -> values (every cell a number, or text for the family and route).
struct Table {
  std::vector<std::string> head;
  std::vector<std::vector<std::string>> rows;
  int col(const std::string& name) const {
    const auto it = std::find(head.begin(), head.end(), name);
    EXPECT_NE(it, head.end()) << name;
    return int(it - head.begin());
  }
  double num(std::size_t r, const std::string& name) const { return std::stod(rows[r][std::size_t(col(name))]); }
  std::string text(std::size_t r, const std::string& name) const { return rows[r][std::size_t(col(name))]; }
};
Table read_csv(const fs::path& p) {
  Table t;
  std::istringstream in(slurp(p));
  std::string line;
  auto split = [](const std::string& s) {
    std::vector<std::string> out;
    std::string cell;
    std::istringstream l(s);
    while (std::getline(l, cell, ',')) out.push_back(cell);
    if (!s.empty() && s.back() == ',') out.push_back("");
    return out;
  };
  std::getline(in, line);
  t.head = split(line);
  while (std::getline(in, line))
    if (!line.empty()) t.rows.push_back(split(line));
  return t;
}

std::string density_key(double d) {
  std::ostringstream s;
  s << d;
  return s.str();
}

}  // namespace

TEST(StudySmall, ReportIntervalsAdaptiveStopAndRankingsMatchTheReplicaTable) {
  const fs::path dir = fs::temp_directory_path() / ("tomodem_study_small_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir / "pipelines");
  const fs::path src = fs::path(TOMODEM_SOURCE_DIR) / "pipelines";
  fs::copy_file(src / "study.yaml", dir / "pipelines" / "study.yaml");
  fs::copy(src / "study", dir / "pipelines" / "study", fs::copy_options::recursive);
  const std::string cmd = std::string(TOMODEM_BIN_DIR) + "/tomodem run " + (dir / "pipelines" / "study.yaml").string() +
                          " --set scale=small -j 2 -q > " + (dir / "run.out").string() + " 2>&1";
  const int st = std::system(cmd.c_str());
  ASSERT_EQ(WEXITSTATUS(st), 0) << slurp(dir / "run.out");

  // The quadrature t against the printed table (Student 1908; any statistics text), 5e-4.
  const double table[][2] = {{1, 12.706}, {2, 4.303}, {3, 3.182}, {4, 2.776}, {10, 2.228}, {30, 2.042}};
  for (const auto& r : table) EXPECT_NEAR(t975(r[0]), r[1], 5e-4) << "nu = " << r[0];

  const fs::path rep = dir / "pipelines" / "out" / "study-small" / "report";
  const Table t = read_csv(rep / "table.csv");
  const json summary = json::parse(slurp(rep / "summary.json"));
  const json record = json::parse(slurp(dir / "pipelines" / "study.replicas.json"));
  ASSERT_FALSE(t.rows.empty());

  // Rows by (family, density), in replica order.
  std::map<std::pair<std::string, std::string>, std::vector<std::size_t>> groups;
  for (std::size_t r = 0; r < t.rows.size(); ++r) groups[{t.text(r, "family"), density_key(t.num(r, "density"))}].push_back(r);
  for (auto& [k, rows] : groups)
    std::sort(rows.begin(), rows.end(), [&](std::size_t a, std::size_t b) { return t.num(a, "replica") < t.num(b, "replica"); });
  // 2 sintered families + the homothetic one, 3 densities each.
  EXPECT_EQ(groups.size(), 9u);

  auto column = [&](const std::vector<std::size_t>& rows, const std::string& name, std::size_t k) {
    std::vector<double> v;
    for (std::size_t i = 0; i < k; ++i) v.push_back(t.num(rows[i], name));
    return v;
  };

  // 1. Intervals: every cell of the report for properties without a tool error (the density, the
  // bonds per particle, and K_IC, whose K_IC_error fracture marks random: it is in the replicas'
  // scatter, docs/pipelines.md; dof n - 1).
  int checked = 0;
  for (const auto& c : summary["cells"]) {
    const std::string prop = c["property"];
    if (prop != "young.relative_density" && prop != "bonds_per_particle" && prop != "sigma_rel" && prop != "fracture.K_IC")
      continue;
    const auto key = std::make_pair(c["family"].get<std::string>(), density_key(c["density"].get<double>()));
    ASSERT_TRUE(groups.count(key)) << key.first << " " << key.second;
    const auto& rows = groups[key];
    const std::vector<double> x = column(rows, prop, rows.size());
    const Cell h = stats(x, {});
    EXPECT_EQ(c["n"].get<std::size_t>(), rows.size());
    // (table.csv: 10 significant digits, so 1e-9 relative on the mean, 1e-6 on the spread.)
    EXPECT_NEAR(c["mean"].get<double>(), h.mean, 1e-9 * std::abs(h.mean));
    EXPECT_NEAR(c["sem"].get<double>(), h.sem, 1e-6 * h.sem + 1e-300);
    EXPECT_NEAR(c["dof"].get<double>(), h.dof, 1e-6 * h.dof) << prop;
    // The quadrature and the report's t agree to 1e-6 relative (both converged far below it).
    EXPECT_NEAR(c["half_width95"].get<double>(), h.half, 1e-6 * h.half) << prop << " " << key.first << " " << key.second;
    // The interval is cut at study.yaml's --bound ranges: [0, 1] for the density, >= 0 for the
    // bonds and K_IC, [0, the largest Hashin-Shtrikman bound of the cell's rows] for sigma_rel.
    double lo = 0, hi = INFINITY;
    if (prop == "young.relative_density") hi = 1;
    if (prop == "sigma_rel") {
      const std::vector<double> hs = column(rows, "conduct.bounds.hs_upper_sigma_over_sigma_s", rows.size());
      hi = *std::max_element(hs.begin(), hs.end());
    }
    EXPECT_NEAR(c["ci95"][0].get<double>(), std::max(lo, h.mean - h.half), 1e-6 * h.half) << prop;
    EXPECT_NEAR(c["ci95"][1].get<double>(), std::min(hi, h.mean + h.half), 1e-6 * h.half) << prop;
    EXPECT_EQ(c["ci95_cut_at_bound"].get<bool>(), h.mean - h.half < lo || h.mean + h.half > hi) << prop;
    ++checked;
  }
  EXPECT_EQ(checked, 9 * 4);

  // 2. The adaptive stop of every sintered group: the rule applied to the first k replicas,
  // k = min..max, with the runner's keys and targets; its n and reason, and the report's.
  const int mn = 2, mx = 4;
  const double tE = 0.1, tK = 1.0;  // study.yaml's scales.small.target_E, target_K
  // (E_iso_error is relative; sigma_iso_error is in S/m, the unit conduct gives it: made relative below.)
  struct Key {
    std::string value, error;
    bool absolute_error;
  };
  const std::vector<Key> keys = {{"young.E_iso", "young.E_iso_error", false},
                                 {"conduct.sigma_iso", "conduct.sigma_iso_error", true},
                                 {"fracture.K_IC", "", false}};  // K_IC_error: random
  int met = 0, maxed = 0;
  for (const auto& g : record["groups"]) {
    const auto key = std::make_pair(g["matrix"]["family"].get<std::string>(), g["matrix"]["density"].get<std::string>());
    ASSERT_TRUE(groups.count(key)) << key.first << " " << key.second;
    const auto& rows = groups[key];
    int n_expected = mx;
    std::string why = "max reached";
    for (int k = mn; k <= mx && k <= int(rows.size()); ++k) {
      bool all = true;
      for (const auto& [p, e, absolute_error] : keys) {
        const std::vector<double> x = column(rows, p, std::size_t(k));
        std::vector<double> rel = e.empty() ? std::vector<double>{} : column(rows, e, std::size_t(k));
        if (absolute_error)
          for (std::size_t i = 0; i < rel.size(); ++i) rel[i] /= std::abs(x[i]);
        const Cell h = stats(x, rel);
        const double target = p == "fracture.K_IC" ? tK : tE;
        all = all && h.half / std::abs(h.mean) <= target;
      }
      if (all) {
        n_expected = k;
        why = "target met";
        break;
      }
    }
    EXPECT_EQ(int(rows.size()), n_expected) << key.first << " " << key.second;
    EXPECT_EQ(g["n"].get<int>(), n_expected);
    EXPECT_EQ(g["stopped_because"].get<std::string>(), why) << key.first << " " << key.second;
    (why == "target met" ? met : maxed)++;
    for (const auto& c : summary["cells"])
      if (c["family"] == key.first && density_key(c["density"].get<double>()) == key.second)
        EXPECT_EQ(c["stopped_because"].get<std::string>(), why);
  }
  EXPECT_EQ(met + maxed, 6);

  // 3. Every Welch ranking of E_rel and sigma_rel: t, dof, p by hand; "<" when the
  // Benjamini-Hochberg q over all the report's rankings (by hand from their p, below) is < 0.05,
  // "not resolved" otherwise.
  std::vector<std::pair<double, std::size_t>> sorted_p;
  for (std::size_t i = 0; i < summary["rankings"].size(); ++i) sorted_p.push_back({summary["rankings"][i]["p"].get<double>(), i});
  std::sort(sorted_p.begin(), sorted_p.end());
  std::vector<double> q(sorted_p.size());
  const double m = double(sorted_p.size());
  for (std::size_t k = 0; k < sorted_p.size(); ++k) {  // q_(k) = min over j >= k of m p_(j) / j
    double qk = 1;
    for (std::size_t j = k; j < sorted_p.size(); ++j) qk = std::min(qk, m * sorted_p[j].first / double(j + 1));
    q[sorted_p[k].second] = qk;
  }
  int ranked = 0;
  for (std::size_t i = 0; i < summary["rankings"].size(); ++i) {
    const auto& r = summary["rankings"][i];
    const std::string prop = r["property"];
    if (prop != "E_rel" && prop != "sigma_rel") continue;
    const std::string at = r["at"];  // "density=0.6"
    const std::string d = density_key(std::stod(at.substr(at.find('=') + 1)));
    const auto& ra = groups[{r["lower"].get<std::string>(), d}];
    const auto& rb = groups[{r["higher"].get<std::string>(), d}];
    const Cell a = stats(column(ra, prop, ra.size()), {}), b = stats(column(rb, prop, rb.size()), {});
    EXPECT_LE(a.mean, b.mean);
    const double va = a.sd * a.sd / double(ra.size()), vb = b.sd * b.sd / double(rb.size());
    const double tt = (b.mean - a.mean) / std::sqrt(va + vb);
    const double nu = (va + vb) * (va + vb) / (va * va / double(ra.size() - 1) + vb * vb / double(rb.size() - 1));
    const double p = 2 * (1 - t_cdf(tt, nu));
    // table.csv holds 10 significant digits: the hand t, dof and p differ from the report's (full
    // precision) by about 1e-10 / (sd / mean), 1e-8 at most here; 1e-6 leaves room.
    EXPECT_NEAR(std::abs(r["t"].get<double>()), tt, 1e-6 * tt);
    EXPECT_NEAR(r["dof"].get<double>(), nu, 1e-6 * nu);
    EXPECT_NEAR(r["p"].get<double>(), p, 1e-6 + 1e-5 * p) << r["text"];
    EXPECT_NEAR(r["q"].get<double>(), q[i], 1e-12 * q[i]);
    const bool resolved = q[i] < 0.05;
    const std::string text = r["text"];
    const std::string pair = r["lower"].get<std::string>() + (resolved ? " < " : " vs ") + r["higher"].get<std::string>();
    EXPECT_EQ(text.rfind(pair + " in " + prop + " at " + at, 0), 0u) << text;
    EXPECT_EQ(r["resolved"].get<bool>(), resolved) << text;
    EXPECT_EQ(text.find("not resolved") != std::string::npos, !resolved) << text;
    ++ranked;
  }
  EXPECT_EQ(ranked, 2 * 3 * 3);  // 2 properties x 3 densities x 3 pairs of the 3 series
  fs::remove_all(dir);
}
