// End-to-end tests of adaptive replicas and the report's statistics (issue 18). A shell step
// prints a value drawn from its seed with the LCG of C's rand() example; the test draws the
// same numbers itself and applies the stop rule with t quantiles copied from a printed table,
// so every expectation here is computed independently of the runner's code.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "../../unit/pipeline/scratch.hpp"

using tomodem::test::Scratch;

namespace {
const std::string kRun = std::string(TOMODEM_BIN_DIR) + "/tomodem-run";

struct Result {
  int code = -1;
  std::string err;
};

Result run(const Scratch& s, const std::string& args) {
  const std::string cmd = "cd '" + s.dir + "' && '" + kRun + "' " + args + " > .stdout 2> .stderr";
  const int st = std::system(cmd.c_str());
  return {WIFEXITED(st) ? WEXITSTATUS(st) : -1, s.read(".stderr")};
}

int count_lines(const std::string& text, const std::string& prefix) {
  std::istringstream in(text);
  int n = 0;
  for (std::string line; std::getline(in, line);) n += line.rfind(prefix, 0) == 0;
  return n;
}

const char* kDraw = R"sh(# draw.sh SEED LEVEL REPLICA: a summary whose value is drawn from the seed
v=$(( ($1 * 1103515245 + 12345) % 2147483648 / 65536 % 32768 ))
if [ "$2" = a ]; then x=$(( 1000 + v % 200 )); else x=$(( 1000 + v % 2000 )); fi
printf '{"level": "%s", "replica": %s, "x": %s, "x_error": 0, "cpu_time_s": %s}\n' "$2" "$3" "$x" "$(( 1 + v % 9 ))"
)sh";

// gen has 12 plain replicas per level, but only those an adaptive draw replica reads may run.
const char* kPipeline = R"(vars: {levels: [a, b], target: 0.05}
steps:
  gen:
    matrix: {level: '${vars.levels}'}
    replicas: 12
    seed: 100
    cell: ${matrix.level}-r${replica}
    cmd: echo ${seed} > ${outs.0} && echo gen ${cell} >> runs.txt
    outs: ['out/${cell}/seed.txt']
  draw:
    matrix: {level: '${vars.levels}'}
    replicas: {until: {x: '${vars.target}'}, min: 3, max: 12}
    cell: ${matrix.level}-r${replica}
    cmd: sh draw.sh $(cat ${steps.gen.outs.0}) ${matrix.level} ${replica} > ${outs.summary} && echo draw ${cell} >> runs.txt
    outs: {summary: 'out/${cell}/draw.json'}
  report:
    tool: run
    args: [report, -o, '${outs.report}', --group, level, --replicas, '${run.replicas}', '${steps.draw.outs.summary}']
    outs: {report: report}
)";

std::int64_t draw_v(std::int64_t seed) { return (seed * 1103515245 + 12345) % 2147483648 / 65536 % 32768; }
double draw_x(char level, int replica) {
  const std::int64_t v = draw_v(100 + replica);
  return 1000.0 + static_cast<double>(level == 'a' ? v % 200 : v % 2000);
}

// t_{0.975, dof} for dof 1..11, from a printed table.
const double kT975[] = {0, 12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201};

struct ByHand {
  int n = 0;
  std::string because;
  double mean = 0, half = 0, cpu = 0;
};

// The stop rule applied by hand: from 3 replicas, stop when t sd / sqrt(n) / mean <= target,
// or at 12.
ByHand by_hand(char level, double target) {
  ByHand h;
  for (int n = 1; n <= 12; ++n) {
    double sum = 0, ss = 0, cpu = 0;
    for (int r = 0; r < n; ++r) sum += draw_x(level, r), cpu += static_cast<double>(1 + draw_v(100 + r) % 9);
    const double mean = sum / n;
    for (int r = 0; r < n; ++r) ss += (draw_x(level, r) - mean) * (draw_x(level, r) - mean);
    const double half = n > 1 ? kT975[n - 1] * std::sqrt(ss / (n - 1)) / std::sqrt(static_cast<double>(n)) : 0;
    h = {n, "", mean, half, cpu};
    if (n >= 3 && half / mean <= target) h.because = "target met";
    else if (n == 12) h.because = "max reached";
    if (!h.because.empty()) return h;
  }
  return h;
}

Scratch adaptive_pipeline() {
  Scratch s;
  s.write("draw.sh", kDraw);
  s.write("p.yaml", kPipeline);
  return s;
}
}  // namespace

TEST(Adaptive, StopsWhenTheTargetIsMetAndNeverRerunsFinishedReplicas) {
  auto s = adaptive_pipeline();
  const ByHand a = by_hand('a', 0.05), b = by_hand('b', 0.05);
  // The drawn numbers make one level stop early and the other run to max.
  ASSERT_EQ(a.because, "target met");
  ASSERT_LT(a.n, 12);
  ASSERT_EQ(b.because, "max reached");
  EXPECT_EQ(a.n, 8) << "docs/pipelines.md quotes 8";

  const auto r1 = run(s, "p.yaml -j 2");
  ASSERT_EQ(r1.code, 0) << r1.err;
  const std::string runs = s.read("runs.txt");
  EXPECT_EQ(count_lines(runs, "draw a-"), a.n);
  EXPECT_EQ(count_lines(runs, "draw b-"), b.n);
  EXPECT_EQ(count_lines(runs, "gen a-"), a.n) << "upstream replicas nobody reads must not run";
  EXPECT_EQ(count_lines(runs, "gen b-"), b.n);
  EXPECT_NE(r1.err.find("replicas draw[level=a]: " + std::to_string(a.n)), std::string::npos) << r1.err;

  const auto rec = nlohmann::json::parse(s.read("p.replicas.json"));
  std::map<std::string, nlohmann::json> groups;
  for (const auto& g : rec.at("groups")) groups[g.at("id").get<std::string>()] = g;
  EXPECT_EQ(groups["draw[level=a]"].at("stopped_because"), "target met");
  EXPECT_EQ(groups["draw[level=a]"].at("n"), a.n);
  EXPECT_EQ(groups["draw[level=b]"].at("stopped_because"), "max reached");
  EXPECT_EQ(groups["draw[level=b]"].at("n"), 12);

  // The report: mean and ci95 from the same numbers, by hand.
  const auto sum = nlohmann::json::parse(s.read("report/summary.json"));
  for (const auto& c : sum.at("cells")) {
    const ByHand& h = c.at("level") == "a" ? a : b;
    EXPECT_EQ(c.at("property"), "x");
    EXPECT_EQ(c.at("n"), h.n);
    EXPECT_EQ(c.at("stopped_because"), h.because);
    EXPECT_NEAR(c.at("mean").get<double>(), h.mean, 1e-9 * h.mean);
    EXPECT_NEAR(c.at("ci95")[0].get<double>(), h.mean - h.half, 2e-3 * h.half);  // table t: 3 decimals
    EXPECT_NEAR(c.at("ci95")[1].get<double>(), h.mean + h.half, 2e-3 * h.half);
    EXPECT_DOUBLE_EQ(c.at("cpu_s").get<double>(), h.cpu);
  }
  ASSERT_EQ(sum.at("rankings").size(), 1u);
  EXPECT_EQ(sum.at("rankings")[0].at("lower"), a.mean < b.mean ? "a" : "b");

  // A second invocation: every replica and the report are up to date, nothing runs.
  const auto r2 = run(s, "p.yaml -j 2 --json run2.json");
  ASSERT_EQ(r2.code, 0) << r2.err;
  EXPECT_EQ(s.read("runs.txt"), runs);
  EXPECT_EQ(nlohmann::json::parse(s.read("run2.json")).at("ran"), 0);

  // A tighter target adds replicas to level a only, and none of the finished ones runs again.
  const ByHand tight = by_hand('a', 0.03);
  ASSERT_GT(tight.n, a.n);
  const auto r3 = run(s, "p.yaml -j 2 --set target=0.03");
  ASSERT_EQ(r3.code, 0) << r3.err;
  const std::string runs3 = s.read("runs.txt");
  EXPECT_EQ(count_lines(runs3, "draw a-"), tight.n);
  EXPECT_EQ(count_lines(runs3, "draw b-"), 12);
  EXPECT_EQ(runs3.substr(0, runs.size()), runs);
}

TEST(Adaptive, ProjectedBatchesAddHalfOfWhatTheSpreadSaysIsMissing) {
  // The rule of `batch: projected` by hand: after each round, the first n' <= 12 with
  // t sd / sqrt(n') / mean <= target (sd and mean of the replicas so far, table t), and half the
  // way there (at least one) is added.
  auto s = adaptive_pipeline();
  std::string text = kPipeline;
  const std::string spec0 = "min: 3, max: 12}";
  text.replace(text.find(spec0), spec0.size(), "min: 3, max: 12, batch: projected}");
  s.write("p.yaml", text);
  std::map<char, std::vector<int>> rounds;  // replica counts after each round, by hand
  std::map<char, std::string> because;
  for (const char level : {'a', 'b'}) {
    int n = 3;
    for (;;) {
      rounds[level].push_back(n);
      double sum = 0, ss = 0;
      for (int r = 0; r < n; ++r) sum += draw_x(level, r);
      const double mean = sum / n;
      for (int r = 0; r < n; ++r) ss += (draw_x(level, r) - mean) * (draw_x(level, r) - mean);
      const double sd = std::sqrt(ss / (n - 1));
      const auto rel = [&](int m) { return kT975[m - 1] * sd / std::sqrt(double(m)) / mean; };
      if (rel(n) <= 0.05) { because[level] = "target met"; break; }
      if (n == 12) { because[level] = "max reached"; break; }
      int want = 12;
      for (int m = 12; m > n && rel(m) <= 0.05; --m) want = m;
      n = std::min(12, n + std::max(1, (want - n + 1) / 2));
    }
  }
  ASSERT_GT(rounds['a'].size(), 1u);
  ASSERT_LT(rounds['a'].size(), static_cast<std::size_t>(rounds['a'].back() - 2)) << "a batch larger than one must occur";
  const auto r = run(s, "p.yaml -j 2");
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string runs = s.read("runs.txt");
  const auto rec = nlohmann::json::parse(s.read("p.replicas.json"));
  for (const auto& g : rec.at("groups")) {
    const char level = g.at("matrix").at("level").get<std::string>()[0];
    EXPECT_EQ(g.at("n"), rounds[level].back()) << level;
    EXPECT_EQ(g.at("stopped_because"), because[level]) << level;
    EXPECT_EQ(count_lines(runs, std::string("draw ") + level + "-"), rounds[level].back());
    for (std::size_t k = 0; k + 1 < rounds[level].size(); ++k) {
      const int added = rounds[level][k + 1] - rounds[level][k];
      const std::string line = "replicas draw[level=" + std::string(1, level) + "]: " + std::to_string(rounds[level][k]) + ", x";
      const auto at = r.err.find(line);
      ASSERT_NE(at, std::string::npos) << line << "\n" << r.err;
      const std::string tail = r.err.substr(at, r.err.find('\n', at) - at);
      EXPECT_NE(tail.find(added == 1 ? ": one more" : ": " + std::to_string(added) + " more"), std::string::npos) << tail;
    }
  }
}

TEST(Adaptive, BadUntilInputIsRefusedAtLoadWithFileAndLine) {
  const std::pair<std::string, std::string> cases[] = {
      {"{until: {x: 0}, min: 3, max: 12}", "steps.draw.replicas.until.x"},
      {"{until: {x: -0.1}, min: 3, max: 12}", "steps.draw.replicas.until.x"},
      {"{until: {x: 0.05}, min: 5, max: 4}", "steps.draw.replicas.max"},
      {"{until: {x: 0.05}, min: 1, max: 4}", "steps.draw.replicas.min"},
      {"{until: {}, min: 3, max: 4}", "steps.draw.replicas.until"},
      {"{until: {x: 0.05}, min: 3}", "steps.draw.replicas.max"},
      {"{until: {x: 0.05}, min: 3, max: 12, batch: 0}", "steps.draw.replicas.batch"},
      {"{until: {x: 0.05}, min: 3, max: 12, batch: 13}", "steps.draw.replicas.batch"},
      {"{until: {x: 0.05}, min: 3, max: 12, batch: half}", "steps.draw.replicas.batch"},
  };
  for (const auto& [spec, field] : cases) {
    auto s = adaptive_pipeline();
    std::string text = kPipeline;
    const std::string spec0 = "{until: {x: '${vars.target}'}, min: 3, max: 12}";
    text.replace(text.find(spec0), spec0.size(), spec);
    s.write("p.yaml", text);
    const auto r = run(s, "p.yaml");
    EXPECT_EQ(r.code, 2) << spec << "\n" << r.err;
    EXPECT_NE(r.err.find("p.yaml:12:"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(field), std::string::npos) << r.err;
    EXPECT_EQ(s.read("runs.txt"), "") << "nothing may run";
  }
}

TEST(Adaptive, UntilKeyTheStepDoesNotWriteIsRefusedAtLoad) {
  // A row step writes its --value names and NAME.* for each --summary: young.E is not among them.
  Scratch s;
  s.write("d.json", "{\"x\": 1}");
  s.write("p.yaml", R"(steps:
  row:
    replicas: {until: {young.E: 0.02}, min: 3, max: 5}
    tool: run
    args: [row, -o, '${outs.row}', --value, 'replica=${replica}', --summary, 'draw=d.json']
    outs: {row: 'out/r${replica}.json'}
)");
  const auto r = run(s, "p.yaml");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("p.yaml:3:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("does not write this key"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(s.path("out")));
  // draw.x is written (draw.*): loads, runs and stops at min (every row is identical: zero spread).
  std::string text = s.read("p.yaml");
  text.replace(text.find("young.E"), 7, "draw.x");
  s.write("p.yaml", text);
  const auto ok = run(s, "p.yaml");
  ASSERT_EQ(ok.code, 0) << ok.err;
  EXPECT_NE(s.read("p.replicas.json").find("\"target met\""), std::string::npos);
  // A cmd step without a JSON output has nothing to read the key from.
  s.write("q.yaml", R"(steps:
  draw:
    replicas: {until: {x: 0.02}, min: 3, max: 5}
    cmd: echo 1 > ${outs.0}
    outs: ['out/q${replica}.txt']
)");
  const auto q = run(s, "q.yaml");
  EXPECT_EQ(q.code, 2) << q.err;
  EXPECT_NE(q.err.find("q.yaml:3:"), std::string::npos) << q.err;
  EXPECT_NE(q.err.find("no JSON output"), std::string::npos) << q.err;
}

TEST(Adaptive, ReportMatchesStopsByStepNotOnlyByGroupValues) {
  // Two row steps with the same level values: `adaptive` adds replicas until d.x is narrow
  // enough, `fixed` always has 3. The report keeps them apart (the row's step column, set by the
  // runner) and gives the runner's stop to the adaptive cells only.
  auto s = adaptive_pipeline();
  s.write("p.yaml", R"(vars: {levels: [a, b]}
steps:
  gen:
    matrix: {level: '${vars.levels}'}
    replicas: 12
    seed: 100
    cell: ${matrix.level}-r${replica}
    cmd: sh draw.sh ${seed} ${matrix.level} ${replica} > ${outs.0}
    outs: ['out/${cell}/draw.json']
  adaptive:
    matrix: {level: '${vars.levels}'}
    replicas: {until: {d.x: 0.05}, min: 3, max: 12}
    cell: ${matrix.level}-r${replica}
    tool: run
    args: [row, -o, '${outs.row}', --value, 'level=${matrix.level}', --value, 'replica=${replica}', --summary, 'd=${steps.gen.outs.0}']
    outs: {row: 'out/${cell}/row.json'}
  fixed:
    matrix: {level: '${vars.levels}'}
    replicas: 3
    cell: ${matrix.level}-r${replica}
    tool: run
    args: [row, -o, '${outs.row}', --value, 'level=${matrix.level}', --value, 'replica=${replica}', --summary, 'd=${steps.gen.outs.0}']
    outs: {row: 'out/fixed/${cell}/row.json'}
  report:
    tool: run
    args: [report, -o, '${outs.report}', --group, level, --stats, d.x, --replicas, '${run.replicas}',
           '${steps.adaptive.outs.row}', '${steps.fixed.outs.row}']
    outs: {report: report}
)");
  const ByHand a = by_hand('a', 0.05), b = by_hand('b', 0.05);
  const auto r = run(s, "p.yaml -j 2");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto sum = nlohmann::json::parse(s.read("report/summary.json"));
  int cells = 0;
  for (const auto& c : sum.at("cells")) {
    if (c.at("property") != "d.x") continue;
    ++cells;
    const bool adaptive = c.at("step") == "adaptive";
    ASSERT_TRUE(adaptive || c.at("step") == "fixed") << c;
    const ByHand& h = c.at("level") == "a" ? a : b;
    EXPECT_EQ(c.at("n"), adaptive ? h.n : 3) << c;
    EXPECT_EQ(c.at("stopped_because"), adaptive ? h.because : "fixed replicas") << c;
  }
  EXPECT_EQ(cells, 4);
  // Rankings compare the levels within one step, never a step against the other.
  int ranked = 0;
  for (const auto& k : sum.at("rankings"))
    if (k.at("property") == "d.x") {
      ++ranked;
      const std::string at = k.at("at").get<std::string>();
      EXPECT_TRUE(at == "step=adaptive" || at == "step=fixed") << at;
    }
  EXPECT_EQ(ranked, 2);
}
