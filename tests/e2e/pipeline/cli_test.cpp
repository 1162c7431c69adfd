// End-to-end tests of tomodem-run with shell-command steps. Each step appends its name to
// runs.txt (which no step declares), so a test can count exactly what ran.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <iostream>
#include <set>
#include <fstream>
#include <sstream>
#include <thread>

#include "../../unit/pipeline/scratch.hpp"
#include "sharded_pipeline.hpp"

using tomodem::test::Scratch;

namespace {
const std::string kRun = std::string(TOMODEM_BIN_DIR) + "/tomodem-run";

struct Result {
  int code = -1;
  std::string out, err;
};

// Runs tomodem-run with `args` inside the scratch folder.
Result run(const Scratch& s, const std::string& args) {
  const std::string cmd = "cd '" + s.dir + "' && '" + kRun + "' " + args + " > .stdout 2> .stderr";
  const int st = std::system(cmd.c_str());
  return {WIFEXITED(st) ? WEXITSTATUS(st) : -1, s.read(".stdout"), s.read(".stderr")};
}

// Lines of runs.txt: one per step execution.
std::multiset<std::string> runs(const Scratch& s) {
  std::istringstream in(s.read("runs.txt"));
  std::multiset<std::string> r;
  for (std::string line; std::getline(in, line);) r.insert(line);
  return r;
}

// in.txt -> a -> b(param k) -> c, and a -> d: editing k must re-run b and c only.
const char* kChain = R"(vars: {k: 1}
steps:
  a:
    cmd: cp in.txt ${outs.0} && echo a >> runs.txt
    deps: [in.txt]
    outs: [out/a.txt]
  b:
    params: {k: "${vars.k}"}
    cmd: (cat ${deps.0}; echo ${params.k}) > ${outs.0} && echo b >> runs.txt
    deps: ['${steps.a.outs.0}']
    outs: [out/b.txt]
  c:
    cmd: cat ${steps.b.outs.0} > ${outs.0} && echo c >> runs.txt
    outs: [out/c.txt]
  d:
    cmd: cat ${steps.a.outs.0} > ${outs.0} && echo d >> runs.txt
    outs: [out/d.txt]
)";

Scratch chain() {
  Scratch s;
  s.write("in.txt", "input\n");
  s.write("p.yaml", kChain);
  return s;
}
}  // namespace

TEST(RunCli, FirstRunRunsAllAndSecondRunRunsNothing) {
  auto s = chain();
  const auto r1 = run(s, "p.yaml -j 2");
  ASSERT_EQ(r1.code, 0) << r1.err;
  EXPECT_EQ(runs(s), (std::multiset<std::string>{"a", "b", "c", "d"}));
  EXPECT_EQ(s.read("out/c.txt"), "input\n1\n");
  const auto r2 = run(s, "p.yaml -j 2 --json summary.json");
  ASSERT_EQ(r2.code, 0) << r2.err;
  EXPECT_EQ(runs(s).size(), 4u);
  EXPECT_NE(s.read("summary.json").find("\"up_to_date\": 4"), std::string::npos) << s.read("summary.json");
  EXPECT_NE(s.read("summary.json").find("\"ran\": 0"), std::string::npos);
}

TEST(RunCli, EditingOneParamRerunsExactlyTheStepsDownstream) {
  auto s = chain();
  ASSERT_EQ(run(s, "p.yaml").code, 0);
  std::string text = kChain;
  text.replace(text.find("k: 1"), 4, "k: 2");
  s.write("p.yaml", text);
  const auto st = run(s, "status p.yaml");
  EXPECT_NE(st.out.find("would run   b: param k changed: 1 -> 2"), std::string::npos) << st.out;
  const auto r = run(s, "p.yaml");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(runs(s), (std::multiset<std::string>{"a", "b", "c", "d", "b", "c"}));
  EXPECT_EQ(s.read("out/c.txt"), "input\n2\n");
  // The same change from the command line (dvc exp run -S style) is a change back: b, c again.
  ASSERT_EQ(run(s, "p.yaml --set k=1").code, 0);
  EXPECT_EQ(runs(s).count("b"), 3u);
  EXPECT_EQ(runs(s).count("a"), 1u);
}

TEST(RunCli, DeletingAnOutputRerunsOnlyItsStep) {
  auto s = chain();
  ASSERT_EQ(run(s, "p.yaml").code, 0);
  std::filesystem::remove(s.path("out/b.txt"));
  const auto r = run(s, "p.yaml");
  ASSERT_EQ(r.code, 0) << r.err;
  // b makes the same bytes again, so c (which reads it) stays up to date: content, not time.
  EXPECT_EQ(runs(s), (std::multiset<std::string>{"a", "b", "c", "d", "b"}));
  EXPECT_NE(r.err.find("output out/b.txt is missing"), std::string::npos) << r.err;
}

TEST(RunCli, EditedInputAndForceAndDryRun) {
  auto s = chain();
  ASSERT_EQ(run(s, "p.yaml").code, 0);
  s.write("in.txt", "changed\n");
  const auto dry = run(s, "p.yaml --dry-run");
  ASSERT_EQ(dry.code, 0);
  EXPECT_NE(dry.err.find("would run a: input in.txt changed"), std::string::npos) << dry.err;
  EXPECT_EQ(runs(s).size(), 4u);  // nothing ran
  ASSERT_EQ(run(s, "p.yaml").code, 0);
  EXPECT_EQ(runs(s).size(), 8u);
  ASSERT_EQ(run(s, "p.yaml --force d").code, 0);
  EXPECT_EQ(runs(s).count("d"), 3u);
  EXPECT_EQ(runs(s).size(), 9u);
  const auto ex = run(s, "explain p.yaml b");
  EXPECT_NE(ex.out.find("b: up to date"), std::string::npos) << ex.out;
  EXPECT_NE(ex.out.find("param k = 1"), std::string::npos) << ex.out;
}

namespace {
// A chain whose middle step is long: a (fast) -> slow (2 s) -> after; plus independent e.
const char* kSlow = R"(steps:
  a:
    cmd: echo a > ${outs.0} && echo a >> runs.txt
    outs: [a.txt]
  slow:
    cmd: echo slow >> runs.txt && sleep 2 && cat ${steps.a.outs.0} > ${outs.0}
    outs: [slow.txt]
  after:
    cmd: cat ${steps.slow.outs.0} > ${outs.0} && echo after >> runs.txt
    outs: [after.txt]
)";

// Starts tomodem-run, waits until the slow step has started, and kills the runner.
void kill_during_slow_step(const Scratch& s, int sig) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (::chdir(s.dir.c_str()) != 0) ::_exit(99);
    ::freopen(".stderr", "w", stderr);
    ::execl(kRun.c_str(), kRun.c_str(), "p.yaml", "-j", "1", static_cast<char*>(nullptr));
    ::_exit(98);
  }
  const auto t0 = std::chrono::steady_clock::now();
  while (runs(s).count("slow") == 0 && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(10))
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ASSERT_EQ(runs(s).count("slow"), 1u);
  ::kill(pid, sig);
  int st = 0;
  ::waitpid(pid, &st, 0);
  EXPECT_TRUE(WIFSIGNALED(st) || WEXITSTATUS(st) != 0);
}
}  // namespace

TEST(RunCli, KilledRunResumesWithoutRedoingFinishedSteps) {
  for (const int sig : {SIGTERM, SIGKILL}) {
    Scratch s;
    s.write("p.yaml", kSlow);
    kill_during_slow_step(s, sig);
    // Give an orphaned `sleep` time to not matter: the step's shell is gone either way.
    EXPECT_FALSE(std::filesystem::exists(s.path("slow.txt"))) << "signal " << sig;
    const auto r = run(s, "p.yaml -j 1");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(runs(s), (std::multiset<std::string>{"a", "slow", "slow", "after"})) << "signal " << sig;
    EXPECT_EQ(s.read("after.txt"), "a\n");
  }
}

TEST(RunCli, FailedStepStopsDependantsAndKeepGoingRunsTheRest) {
  Scratch s;
  s.write("p.yaml", R"(steps:
  bad:
    cmd: echo partial > ${outs.0}; echo "mesh exploded" >&2; exit 3
    outs: [bad.txt]
  child:
    cmd: cat ${steps.bad.outs.0} > ${outs.0}
    outs: [child.txt]
  other:
    cmd: echo ok > ${outs.0}
    outs: [other.txt]
)");
  const auto r = run(s, "p.yaml -j 1 --keep-going --json -");
  EXPECT_EQ(r.code, 1);
  EXPECT_FALSE(std::filesystem::exists(s.path("bad.txt")));  // no half-made output left behind
  EXPECT_TRUE(std::filesystem::exists(s.path("other.txt")));
  EXPECT_NE(r.err.find("failed  bad: exit code 3: mesh exploded"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("skipped child: upstream bad failed"), std::string::npos) << r.err;
  EXPECT_NE(s.read("p.logs/bad.log").find("mesh exploded"), std::string::npos);
  EXPECT_NE(r.out.find("\"failed\": 1"), std::string::npos) << r.out;
  // Without --keep-going the run stops: `other` is not started after `bad` fails.
  std::filesystem::remove(s.path("other.txt"));
  std::filesystem::remove(s.path("p.lock.json"));
  EXPECT_EQ(run(s, "p.yaml -j 1").code, 1);
  EXPECT_FALSE(std::filesystem::exists(s.path("other.txt")));
}

TEST(RunCli, BadInputExitsTwoNamingFileLineAndNameBeforeRunningAnything) {
  struct Case {
    const char* what;
    const char* yaml;
    const char* expect;
  };
  const Case cases[] = {
      {"cycle", "steps:\n  a:\n    cmd: echo a >> runs.txt; cp ${steps.b.outs.0} ${outs.0}\n    outs: [a]\n"
                "  b:\n    cmd: cp ${steps.a.outs.0} ${outs.0}\n    outs: [b]\n",
       "cycle between steps"},
      {"unknown step", "steps:\n  a:\n    cmd: echo a >> runs.txt\n  b:\n    cmd: cat ${steps.zz.outs}\n", "'zz'"},
      {"unknown output", "steps:\n  a:\n    cmd: echo a >> runs.txt\n    outs: {x: x.txt}\n  b:\n"
                         "    cmd: cat ${steps.a.outs.y}\n", "no output 'y'"},
      {"same output", "steps:\n  a:\n    cmd: echo a >> runs.txt\n    outs: [o.txt]\n  b:\n    cmd: true\n"
                      "    outs: [o.txt]\n", "also written by 'a'"},
      {"missing input", "steps:\n  a:\n    cmd: echo a >> runs.txt\n  b:\n    cmd: true\n    deps: [nope.tif]\n",
       "nope.tif"},
      {"unknown tool", "steps:\n  a:\n    cmd: echo a >> runs.txt\n  b:\n    tool: nosuchverb\n", "nosuchverb"},
      {"unknown key", "steps:\n  a:\n    cmd: echo a >> runs.txt\n  b:\n    cmd: true\n    thread: 2\n", "steps.b.thread"},
  };
  const char* lines[] = {"p.yaml:2", "p.yaml:5", "p.yaml:6", "p.yaml:7", "p.yaml:6", "p.yaml:5", "p.yaml:6"};
  int k = 0;
  for (const auto& c : cases) {
    Scratch s;
    s.write("p.yaml", c.yaml);
    const auto r = run(s, "p.yaml");
    EXPECT_EQ(r.code, 2) << c.what << ": " << r.err;
    EXPECT_NE(r.err.find(c.expect), std::string::npos) << c.what << ": " << r.err;
    EXPECT_NE(r.err.find(lines[k++]), std::string::npos) << c.what << ": " << r.err;
    EXPECT_FALSE(std::filesystem::exists(s.path("runs.txt"))) << c.what << ": something ran";
  }
  Scratch s;
  EXPECT_EQ(run(s, "nothere.yaml").code, 2);
  EXPECT_EQ(run(s, "--no-such-flag x.yaml").code, 2);
}

TEST(RunCli, SweepOnTwoJobsTakesAboutHalfTheTimeOfOne) {
  // 3x3 cells of `sleep 0.3`: 2.7 s serial. Two slots should give about 1.35 s; the loose
  // bound (< 0.75) leaves room for process start-up on a loaded two-core machine.
  Scratch s;
  s.write("p.yaml", R"(steps:
  cell:
    matrix: {a: [1, 2, 3], b: [x, y, z]}
    cmd: sleep 0.3 && echo ${cell} > ${outs.0}
    outs: ['out/${cell}.txt']
)");
  const auto timed = [&](const std::string& args) {
    std::filesystem::remove_all(s.path("out"));
    std::filesystem::remove(s.path("p.lock.json"));
    const auto t0 = std::chrono::steady_clock::now();
    const auto r = run(s, args);
    EXPECT_EQ(r.code, 0) << r.err;
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };
  const double one = timed("p.yaml -j 1 --quiet"), two = timed("p.yaml -j 2 --quiet");
  std::cout << "jobs 1: " << one << " s, jobs 2: " << two << " s, ratio " << two / one << "\n";
  EXPECT_GT(one, 2.7);
  EXPECT_LT(two / one, 0.75);
}

TEST(RunCli, ThreadsTakeSlots) {
  // Two steps of threads: 2 on two slots cannot overlap; two of threads: 1 can.
  Scratch s;
  s.write("p.yaml", R"(steps:
  w:
    matrix: {i: [1, 2]}
    threads: 2
    cmd: echo start $(date +%s%N) $OMP_NUM_THREADS >> log.txt; sleep 0.3; echo end $(date +%s%N) >> log.txt; touch ${outs.0}
    outs: ['w${cell}']
)");
  ASSERT_EQ(run(s, "p.yaml -j 2").code, 0);
  std::istringstream in(s.read("log.txt"));
  std::vector<std::string> kinds;
  for (std::string w, t, n; in >> w >> t;) {
    kinds.push_back(w);
    if (w == "start") {
      in >> n;
      EXPECT_EQ(n, "2");
    }
  }
  EXPECT_EQ(kinds, (std::vector<std::string>{"start", "end", "start", "end"}));
}

TEST(RunCli, ShardsThenGatherRunEachCellOnce) {
  Scratch s;
  s.write("p.yaml", tomodem::pipeline::test::kShardedPipeline);
  // A shard before the shared part is refused (its input is not made yet).
  const auto early = run(s, "p.yaml --shard 1/2");
  EXPECT_EQ(early.code, 1);
  EXPECT_NE(early.err.find("--shard 0/2 first"), std::string::npos) << early.err;
  for (const char* k : {"0/2", "1/2", "2/2"}) ASSERT_EQ(run(s, std::string("p.yaml --shard ") + k).code, 0) << k;
  EXPECT_TRUE(std::filesystem::exists(s.path("p.lock.shard-1.json")));
  EXPECT_EQ(runs(s), (std::multiset<std::string>{"prep", "d-1", "d-2", "d-3", "d-4"}));
  const auto g = run(s, "p.yaml");
  ASSERT_EQ(g.code, 0) << g.err;
  EXPECT_EQ(runs(s).size(), 6u);  // only the gather ran
  EXPECT_EQ(runs(s).count("gather"), 1u);
  EXPECT_FALSE(std::filesystem::exists(s.path("p.lock.shard-1.json")));  // merged into p.lock.json
}

TEST(RunCli, ExportSlurmDotAndDispatchThroughTomodem) {
  Scratch s;
  s.write("p.yaml", "steps:\n  c:\n    matrix: {d: [1, 2, 3]}\n    threads: 4\n    cmd: touch ${outs.0}\n"
                    "    outs: ['c${cell}']\n");
  ASSERT_EQ(run(s, "export slurm p.yaml --limit 2").code, 0);
  const std::string a = s.read("p.array.sbatch");
  EXPECT_NE(a.find("#SBATCH --array=1-3%2"), std::string::npos) << a;
  EXPECT_NE(a.find("#SBATCH --cpus-per-task=4"), std::string::npos) << a;
  EXPECT_EQ(std::system(("bash -n " + s.path("p.submit.sh")).c_str()), 0);
  const auto d = run(s, "dot p.yaml");
  EXPECT_NE(d.out.find("digraph"), std::string::npos);
  EXPECT_NE(d.out.find("\"c[d-2]\""), std::string::npos) << d.out;
  const std::string cmd = std::string(TOMODEM_BIN_DIR) + "/tomodem run --version > " + s.path("v.txt");
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  EXPECT_EQ(s.read("v.txt").rfind("tomodem ", 0), 0u);
}

TEST(RunCli, ToolStepRecordsItsVersion) {
  // `tool: run` resolves to tomodem-run beside this build; its --version goes into the lock.
  Scratch s;
  s.write("sub.yaml", "steps:\n  x:\n    cmd: true\n");
  s.write("p.yaml", "steps:\n  t:\n    tool: run\n    args: [status, sub.yaml, --json, '${outs.0}']\n"
                    "    outs: [status.json]\n");
  const auto r = run(s, "p.yaml");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(s.read("status.json").find("\"would_run\": 1"), std::string::npos);
  EXPECT_NE(s.read("p.lock.json").find("\"version\": \"tomodem "), std::string::npos) << s.read("p.lock.json");
}

TEST(RunCli, ExampleSweepGivesTheTableItsReadmePromises) {
  // pipelines/examples/01-sweep, run in a copy so the source tree stays clean.
  Scratch s;
  std::filesystem::copy(std::string(TOMODEM_SOURCE_DIR) + "/pipelines/examples/01-sweep", s.dir,
                        std::filesystem::copy_options::recursive);
  const auto r = run(s, "sweep.yaml -j 2 --json summary.json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(s.read("summary.json").find("\"ran\": 14"), std::string::npos) << s.read("summary.json");
  std::istringstream table(s.read("out/table.csv"));
  std::string line;
  std::getline(table, line);
  EXPECT_EQ(line, "density,seed,E_rel");
  int rows = 0;
  while (std::getline(table, line)) {
    double d = 0, e = 0;
    int seed = 0;
    ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%d,%lf", &d, &seed, &e), 3) << line;
    EXPECT_NEAR(e / (d * d), 1.0, 0.02 + 1e-4) << line;  // the script's +-2 % scatter, 5 digits printed
    EXPECT_GE(seed, 1000);
    EXPECT_LE(seed, 1002);
    ++rows;
  }
  EXPECT_EQ(rows, 9);
  // A new particle count re-runs the 3 packings, whose files change, so the 9 young cells run;
  // their results do not depend on the count, so the table is up to date (early cut-off).
  const auto again = run(s, "sweep.yaml -j 2 --set particles=800 --json summary.json");
  ASSERT_EQ(again.code, 0) << again.err;
  EXPECT_NE(s.read("summary.json").find("\"ran\": 12"), std::string::npos) << s.read("summary.json");
  EXPECT_NE(s.read("summary.json").find("\"up_to_date\": 2"), std::string::npos);
}

// Tools set a short OpenMP spin (GOMP_SPINCOUNT=1000, docs/benchmarks.md "Waiting threads") when
// the user set no waiting policy, and keep the user's when there is one; the runner's steps
// inherit what the runner runs with.
TEST(RunCli, ToolsSpinBrieflyUnlessTheUserSaidOtherwise) {
  Scratch s;
  s.write("p.yaml", "steps:\n  a:\n    cmd: printf '%s|%s' \"$GOMP_SPINCOUNT\" \"$OMP_WAIT_POLICY\" > ${outs.0}\n"
                    "    outs: [env.txt]\n");
  const auto with = [&](const std::string& env) {
    std::filesystem::remove(s.path("env.txt"));
    std::filesystem::remove(s.path("p.lock.json"));
    const std::string cmd = "cd '" + s.dir + "' && env -u OMP_WAIT_POLICY -u GOMP_SPINCOUNT " + env + " '" + kRun +
                            "' p.yaml -q";
    EXPECT_EQ(std::system(cmd.c_str()), 0) << env;
    return s.read("env.txt");
  };
  EXPECT_EQ(with(""), "1000|");
  EXPECT_EQ(with("OMP_WAIT_POLICY=ACTIVE"), "|ACTIVE");
  EXPECT_EQ(with("GOMP_SPINCOUNT=5"), "5|");
}

// Review D21: `-j 0` said "Value 0 not in range 0.000000 to 1797693...".
TEST(RunCli, BadJobsCountSaysWhatIsExpected) {
  Scratch s = chain();
  for (const char* bad : {"0", "-1", "x", "1.5"}) {
    const auto r = run(s, std::string("p.yaml -j ") + bad);
    EXPECT_EQ(r.code, 2) << bad << ": " << r.err;
    EXPECT_NE(r.err.find("--jobs"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("from 1 to 1000000"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("1797693"), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(s.path("runs.txt")));
  }
}

// `tomodem run report`'s list options take one value per occurrence, so row files may follow
// any of them (docs/pipelines.md's worked example: `--group family a*.json b*.json`); a comma
// still separates the items of --group, --stats and --columns.
TEST(RunCli, ReportRowFilesMayFollowEveryOption) {
  Scratch s;
  for (const char* f : {"a1", "a2", "b1", "b2"})
    s.write(std::string(f) + ".json", std::string("{\"family\": \"") + f[0] + "\", \"x\": 1, \"y\": " + (f[1] == '1' ? "2" : "3") + "}");
  for (const std::string opts :
       {"--group family", "--group=family", "--stats y", "--stats x,y", "--columns family,y", "--columns family --columns y",
        "--ratio r=y/2", "--bound y=0:", "--plot 'name=p;x=x;y=y;xlabel=x (-);ylabel=y (-)'"}) {
    const auto r = run(s, "report -o report " + opts + " a*.json b*.json");
    ASSERT_EQ(r.code, 0) << opts << ": " << r.err;
    std::istringstream table(s.read("report/table.csv"));
    int lines = 0;
    for (std::string l; std::getline(table, l);) ++lines;
    EXPECT_EQ(lines, 5) << opts;  // the header and the 4 rows
  }
  EXPECT_EQ(s.read("report/table.csv").substr(0, 8), "family,x");
  // One row file given twice (another spelling of it) would be two replicas: exit 2, naming both.
  std::filesystem::remove_all(s.path("report"));
  const auto twice = run(s, "report -o report --group family a1.json a2.json ./a1.json");
  EXPECT_EQ(twice.code, 2);
  EXPECT_NE(twice.err.find("./a1.json"), std::string::npos) << twice.err;
  EXPECT_FALSE(std::filesystem::exists(s.path("report")));
}
