// The runner never destroys what it did not make, never runs data as code, and keeps its
// records intact on a full disk (issue 16). Each test reproduces an attack or an accident a
// user could meet and checks that nothing of theirs changed.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/mount.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <thread>
#include <vector>

#include "../../unit/pipeline/scratch.hpp"

using tomodem::test::Scratch;
namespace fs = std::filesystem;

namespace {
const std::string kRun = std::string(TOMODEM_BIN_DIR) + "/tomodem-run";

// The runner started in the background in s's folder (stderr dropped when `quiet`): the
// tests that kill it, or run a second one beside it.
pid_t start_run(const Scratch& s, const std::vector<std::string>& args, bool quiet = true) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::chdir(s.dir.c_str());
    if (quiet) ::freopen("/dev/null", "w", stderr);
    std::vector<char*> argv{const_cast<char*>(kRun.c_str())};
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(kRun.c_str(), argv.data());
    ::_exit(127);
  }
  return pid;
}

struct Result {
  int code = -1;
  std::string out, err;
};

std::string q(const std::string& s) {
  std::string r = "'";
  for (char c : s) r += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return r + "'";
}

// Runs tomodem-run with `args` inside `cwd`; `pre` is shell put before the command (ulimit).
Result run_in(const std::string& cwd, const std::string& args, const std::string& pre = "") {
  // Captured outside `cwd`: it may be a full disk.
  const std::string capture = (fs::temp_directory_path() / ("tomodem-safety-" + std::to_string(::getpid()))).string();
  const std::string cmd = "cd " + q(cwd) + " && " + pre + q(kRun) + " " + args + " > " + q(capture + ".out") +
                          " 2> " + q(capture + ".err");
  const int st = std::system(cmd.c_str());
  std::ifstream o(capture + ".out"), e(capture + ".err");
  Result r{WIFEXITED(st) ? WEXITSTATUS(st) : -1, {std::istreambuf_iterator<char>(o), {}},
           {std::istreambuf_iterator<char>(e), {}}};
  fs::remove(capture + ".out");
  fs::remove(capture + ".err");
  return r;
}

// Every file under `dir` with its content: to prove that nothing changed.
std::map<std::string, std::string> snapshot(const std::string& dir) {
  std::map<std::string, std::string> m;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    const std::string rel = fs::relative(e.path(), dir).string();
    if (e.is_regular_file()) {
      std::ifstream in(e.path(), std::ios::binary);
      m[rel] = std::string(std::istreambuf_iterator<char>(in), {});
    } else {
      m[rel] = "<dir>";
    }
  }
  return m;
}

bool has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }
}  // namespace

// Item 1: an output that is the folder itself, above it, absolute, a link out of it, the
// pipeline file, its lock or logs, or a folder holding a user's input: refused at load time
// with file:line, before anything runs, and nothing is touched.
TEST(RunSafety, OutputsOutsideThePipelineFolderAreRefusedAndNothingIsTouched) {
  Scratch s;
  s.write("victim/precious.txt", "mine\n");
  s.write("d/pipe/keep.txt", "keep\n");
  s.write("d/pipe/data/scan.txt", "scan\n");
  fs::create_directory_symlink(s.path("victim"), s.path("d/pipe/link"));
  struct Case {
    const char* outs;
    const char* why;
  } cases[] = {
      {"{o: .}", "inside the pipeline's folder"},
      {"{o: ..}", "inside the pipeline's folder"},
      {"{o: ./}", "inside the pipeline's folder"},
      {"{o: ../victim}", "inside the pipeline's folder"},
      {"{o: sub/../..}", "inside the pipeline's folder"},
      {"{o: link}", "inside the pipeline's folder"},
      {"{o: link/precious.txt}", "inside the pipeline's folder"},
      {"{o: p.yaml}", "pipeline file"},
      {"{o: p.lock.json}", "lock"},
      {"{o: p.lock.shard-1.json}", "lock"},
      {"{o: p.logs}", "logs"},
      {"{o: p.logs/a.log}", "logs"},
      {"{o: data}", "holds the input data/scan.txt"},
  };
  for (const auto& c : cases) {
    const std::string abs_case = std::string(c.outs);
    s.write("d/pipe/p.yaml", "steps:\n  a:\n    cmd: \"true\"\n    outs: " + abs_case +
                                 "\n  b:\n    cmd: cat data/scan.txt > ${outs.0}\n    deps: [data/scan.txt]\n"
                                 "    outs: [b.txt]\n");
    const auto before = snapshot(s.dir);
    const auto r = run_in(s.path("d/pipe"), "p.yaml");
    EXPECT_EQ(r.code, 2) << c.outs << "\n" << r.err;
    EXPECT_TRUE(has(r.err, "p.yaml:4")) << c.outs << "\n" << r.err;  // file:line of the output
    EXPECT_TRUE(has(r.err, "steps.a.outs.o")) << r.err;
    EXPECT_TRUE(has(r.err, c.why)) << c.outs << "\n" << r.err;
    EXPECT_EQ(snapshot(s.dir), before) << c.outs;  // nothing ran, nothing moved
  }
  // A log folder outside: its files are rewritten on every run.
  for (const std::string logs : {"..", "../victim", "/tmp"}) {
    s.write("d/pipe/p.yaml", "logs: " + logs + "\nsteps:\n  a:\n    cmd: echo > ${outs.0}\n    outs: [a.txt]\n");
    const auto before = snapshot(s.dir);
    const auto r = run_in(s.path("d/pipe"), "p.yaml");
    EXPECT_EQ(r.code, 2) << logs << "\n" << r.err;
    EXPECT_TRUE(has(r.err, "p.yaml:1")) << r.err;
    EXPECT_EQ(snapshot(s.dir), before);
  }
  // An absolute path too (written by the test, so the path is this scratch folder's).
  s.write("d/pipe/p.yaml", "steps:\n  a:\n    cmd: \"true\"\n    outs: {o: " + s.path("victim") + "}\n");
  const auto before = snapshot(s.dir);
  const auto r = run_in(s.path("d/pipe"), "p.yaml");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(snapshot(s.dir), before);
}

TEST(RunSafety, DeclaredOutRootAllowsOutputsThere) {
  Scratch s;
  s.write("pipe/p.yaml", "out: ../results\nsteps:\n  a:\n    cmd: echo hi > ${outs.o}\n    outs: {o: ../results/a.txt}\n");
  const auto r = run_in(s.path("pipe"), "p.yaml");
  ASSERT_EQ(r.code, 0) << r.err;
  std::ifstream in(s.path("results/a.txt"));
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "hi\n");
  // The declared root may itself be an output (a report folder); beside it, nothing.
  s.write("pipe/p.yaml", "out: ../results\nsteps:\n  a:\n    cmd: mkdir -p ${outs.o}\n    outs: {o: ../results}\n");
  EXPECT_EQ(run_in(s.path("pipe"), "p.yaml").code, 0);
  s.write("pipe/p.yaml", "out: ../results\nsteps:\n  a:\n    cmd: \"true\"\n    outs: {o: ../other}\n");
  EXPECT_EQ(run_in(s.path("pipe"), "p.yaml").code, 2);
  s.write("pipe/p.yaml", "out: /\nsteps:\n  a:\n    cmd: \"true\"\n    outs: {o: x}\n");
  const auto root = run_in(s.path("pipe"), "p.yaml");
  EXPECT_EQ(root.code, 2);
  EXPECT_TRUE(has(root.err, "p.yaml:1")) << root.err;
}

// Item 1: the old output is moved aside while the step runs and comes back when it fails.
TEST(RunSafety, FailedStepGetsTheOldOutputBack) {
  Scratch s;
  s.write("p.yaml", "vars: {fail: 0}\nsteps:\n  a:\n    cmd: echo new > ${outs.0}; exit ${vars.fail}\n"
                    "    outs: [a.txt]\n");
  ASSERT_EQ(run_in(s.dir, "p.yaml").code, 0);
  EXPECT_EQ(s.read("a.txt"), "new\n");
  s.write("a.txt", "good old result\n");  // the user's own copy of the output
  const auto r = run_in(s.dir, "p.yaml --set fail=3");
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_EQ(s.read("a.txt"), "good old result\n");  // restored, not deleted
  EXPECT_FALSE(fs::exists(s.path(".a.txt.tomodem-old")));
  // A folder output too.
  s.write("q.yaml", "vars: {fail: 0}\nsteps:\n  b:\n    cmd: mkdir -p ${outs.0} && echo x > ${outs.0}/f; exit ${vars.fail}\n"
                    "    outs: [out]\n");
  ASSERT_EQ(run_in(s.dir, "q.yaml").code, 0);
  s.write("out/mine.txt", "mine\n");
  EXPECT_EQ(run_in(s.dir, "q.yaml --set fail=1").code, 1);
  EXPECT_EQ(s.read("out/mine.txt"), "mine\n");
  // A success replaces it and leaves nothing aside.
  EXPECT_EQ(run_in(s.dir, "q.yaml").code, 0);
  EXPECT_FALSE(fs::exists(s.path("out/mine.txt")));
  EXPECT_FALSE(fs::exists(s.path(".out.tomodem-old")));
}

// Item 1: kill -9 of the runner in the middle of a step: the next run starts from the last
// good output, and if that step fails again the good output is what stays.
TEST(RunSafety, KillNineMidStepKeepsTheLastGoodOutput) {
  Scratch s;
  s.write("p.yaml", "vars: {fail: 0, nap: 0}\nsteps:\n  a:\n"
                    "    cmd: echo partial > ${outs.0}; sleep ${vars.nap}; echo done >> ${outs.0}; exit ${vars.fail}\n"
                    "    outs: [a.txt]\n");
  ASSERT_EQ(run_in(s.dir, "p.yaml").code, 0);
  ASSERT_EQ(s.read("a.txt"), "partial\ndone\n");
  const pid_t pid = start_run(s, {"p.yaml", "-q", "--set", "nap=30", "-B"}, false);
  for (int k = 0; k < 100 && s.read("a.txt") != "partial\n"; ++k) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  ::kill(pid, SIGKILL);
  ::waitpid(pid, nullptr, 0);
  EXPECT_EQ(s.read(".a.txt.tomodem-old"), "partial\ndone\n");  // the good one, aside
  const auto r = run_in(s.dir, "p.yaml --set fail=1");
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_EQ(s.read("a.txt"), "partial\ndone\n");
  EXPECT_FALSE(fs::exists(s.path(".a.txt.tomodem-old")));
}

// Item 2: values are data. Each attack would create the file P if it ran as code.
TEST(RunSafety, VariablesMatrixSetValuesAndPathsNeverRunAsCode) {
  const std::vector<std::string> attacks = {"x; touch P", "$(touch P)", "`touch P`", "a\ntouch P",
                                            "'; touch P; '", "\"; touch P; \"", "x && touch P #", "|touch P"};
  for (const auto& a : attacks) {
    Scratch s;
    // Plain, inside single quotes and inside double quotes: the value must arrive verbatim.
    s.write("p.yaml", R"(vars: {label: x}
steps:
  plain:
    cmd: printf '%s' ${vars.label} > ${outs.0}
    outs: [plain.txt]
  single:
    cmd: printf '%s' '${vars.label}' > ${outs.0}
    outs: [single.txt]
  double:
    cmd: printf '%s' "${vars.label}" > ${outs.0}
    outs: [double.txt]
  swept:
    matrix: {v: ['${vars.label}']}
    cell: one
    cmd: printf '%s' ${matrix.v} > ${outs.0}
    outs: ['swept-${cell}.txt']
)");
    const auto r = run_in(s.dir, "p.yaml --set label=" + q(a));
    EXPECT_EQ(r.code, 0) << a << "\n" << r.err;
    EXPECT_FALSE(fs::exists(s.path("P"))) << "ran as code: " << a;
    for (const char* f : {"plain.txt", "single.txt", "double.txt", "swept-one.txt"})
      EXPECT_EQ(s.read(f), a) << f << " for " << a;
  }
}

TEST(RunSafety, PathsWithShellCharactersAreData) {
  Scratch s;
  s.write("in; touch P.txt", "data\n");
  s.write("p.yaml", "steps:\n  a:\n    deps: ['in; touch P.txt']\n    cmd: cat ${deps.0} > ${outs.0}\n"
                    "    outs: ['out $(touch P).txt']\n");
  const auto r = run_in(s.dir, "p.yaml");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_FALSE(fs::exists(s.path("P")));
  EXPECT_EQ(s.read("out $(touch P).txt"), "data\n");
}

// Item 2: the Slurm export quotes or refuses every value; the scripts run nothing else.
TEST(RunSafety, SlurmExportQuotesEveryValue) {
  Scratch s;
  const std::string name = "x;touch P;.yaml";
  s.write(name, "steps:\n  a:\n    matrix: {k: [1, 2]}\n    cmd: echo ${matrix.k} > ${outs.0}\n    outs: ['a${cell}.txt']\n");
  const auto r = run_in(s.dir, "export slurm " + q(name) + " --partition 'gpu,cpu' --time 01:00:00");
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string array = s.read("x;touch P;.array.sbatch"), submit = s.read("x;touch P;.submit.sh");
  EXPECT_TRUE(has(array, "#SBATCH --job-name=\"x;touch P;\"")) << array;
  // Both scripts parse, and the submit script run against a fake sbatch creates no P.
  s.write("bin/sbatch", "#!/bin/sh\nprintf '%s\\n' \"$@\" >> sbatch-args.txt\necho 42\n");
  fs::permissions(s.path("bin/sbatch"), fs::perms::owner_all);
  const std::string env = "cd " + q(s.dir) + " && PATH=" + q(s.path("bin")) + ":$PATH ";
  EXPECT_EQ(std::system((env + "bash -n " + q("x;touch P;.array.sbatch")).c_str()), 0);
  EXPECT_EQ(std::system((env + "bash " + q("x;touch P;.submit.sh") + " > /dev/null").c_str()), 0) << submit;
  EXPECT_FALSE(fs::exists(s.path("P")));
  EXPECT_TRUE(has(s.read("sbatch-args.txt"), "--job-name=x;touch P;-shared")) << s.read("sbatch-args.txt");
  // Values that cannot be written safely are refused, naming the option.
  for (const std::string bad : {"--partition 'a;touch P'", "--partition \"$(printf 'a\\ntouch P')\"",
                                "--time '1:00;touch P'", "--time \"$(printf '1:00\\n#SBATCH --wrap=touch P')\""}) {
    const auto b = run_in(s.dir, "export slurm " + q(name) + " " + bad);
    EXPECT_EQ(b.code, 2) << bad << "\n" << b.err;
    EXPECT_TRUE(has(b.err, bad.substr(0, bad.find(' ')))) << b.err;
  }
  // A logs folder with a newline in its name: refused, nothing written.
  Scratch t;
  t.write("p.yaml", "logs: \"l\\nx\"\nsteps:\n  a:\n    matrix: {k: [1, 2]}\n    cmd: echo ${matrix.k} > ${outs.0}\n"
                    "    outs: ['a${cell}.txt']\n");
  const auto nl = run_in(t.dir, "export slurm p.yaml");
  EXPECT_EQ(nl.code, 2) << nl.err;
  EXPECT_FALSE(fs::exists(t.path("p.array.sbatch")));
}

// Item 3: a full disk while the lock file is rewritten: the old lock stays whole, the run
// exits non-zero; `run row` on a full disk leaves no empty file.
TEST(RunSafety, FullDiskKeepsTheOldLockFileAndLeavesNoEmptyFile) {
  Scratch s;
  const std::string mnt = s.path("disk");
  fs::create_directories(mnt);
  // A real 1 MiB tmpfs where the test may mount one (root); otherwise a file size limit gives
  // the same EFBIG/ENOSPC answer to every write past 1 MiB.
  const bool mounted = ::mount("tmpfs", mnt.c_str(), "tmpfs", 0, "size=1m") == 0;
  struct Unmount {
    std::string dir;
    bool on;
    ~Unmount() {
      if (on) ::umount2(dir.c_str(), MNT_DETACH);
    }
  } unmount{mnt, mounted};
  const std::string limit = mounted ? "" : "trap '' XFSZ; ulimit -f 1024; ";
  // Many cells with long names make a lock file larger than what is left once the outputs are written.
  std::string yaml = "steps:\n  a:\n    matrix: {k: [";
  for (int k = 0; k < 60; ++k) yaml += (k ? "," : "") + std::to_string(k);
  yaml += "]}\n    cell: cell-with-a-long-name-to-make-the-lock-file-big-${matrix.k}\n"
          "    cmd: echo ${matrix.k} > ${outs.0}\n    outs: ['o/${cell}.txt']\n";
  std::ofstream(mnt + "/p.yaml") << yaml;
  ASSERT_EQ(run_in(mnt, "p.yaml -j 2 -q", limit).code, 0);
  std::ifstream l0(mnt + "/p.lock.json");
  const std::string lock_before(std::istreambuf_iterator<char>(l0), {});
  ASSERT_GT(lock_before.size(), 1000u);
  // Fill the disk (or the size limit: one file at the limit), then force every step to run again.
  if (mounted) {
    std::ofstream fill(mnt + "/fill", std::ios::binary);
    const std::string block(4096, 'x');
    while (fill.write(block.data(), block.size())) {
    }
  }
  const auto r = run_in(mnt, "p.yaml -B -j 2 -q", mounted ? "" : "trap '' XFSZ; ulimit -f 1; ");
  EXPECT_NE(r.code, 0) << r.err;
  std::ifstream l1(mnt + "/p.lock.json");
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(l1), {}), lock_before);
  for (const auto& e : fs::directory_iterator(mnt))
    EXPECT_FALSE(has(e.path().filename().string(), ".tmp")) << e.path();
  // `run row` on the full disk: non-zero, and no 0-byte row file.
  const auto row = run_in(mnt, "row -o row.json --value " + q("note=" + std::string(8000, 'n')),
                          mounted ? "" : "trap '' XFSZ; ulimit -f 1; ");
  EXPECT_NE(row.code, 0);
  EXPECT_FALSE(fs::exists(mnt + "/row.json"));
  EXPECT_TRUE(has(row.err, "row.json")) << row.err;
}

// Item 4: a plain run and a shard run of one pipeline never run at once; two shard runs with
// overlapping work never run one step twice at the same time.
TEST(RunSafety, PlainAndShardRunsExcludeEachOther) {
  Scratch s;
  s.write("p.yaml", R"(steps:
  prep:
    cmd: sleep 3 && echo prep > ${outs.0} && echo prep >> runs.txt
    outs: [prep.txt]
  cell:
    matrix: {d: [1, 2]}
    cmd: cat ${steps.prep.outs.0} > ${outs.0} && echo ${cell} >> runs.txt
    outs: ['c${cell}.txt']
)");
  const pid_t pid = start_run(s, {"p.yaml", "-q", "-j", "1"});
  std::this_thread::sleep_for(std::chrono::milliseconds(800));
  const auto shard = run_in(s.dir, "p.yaml --shard 0/2 -q");
  EXPECT_NE(shard.code, 0);
  EXPECT_TRUE(has(shard.err, "plain tomodem-run is running this pipeline")) << shard.err;
  int st = 0;
  ::waitpid(pid, &st, 0);
  EXPECT_TRUE(WIFEXITED(st) && WEXITSTATUS(st) == 0);
  EXPECT_EQ(s.read("runs.txt"), "prep\nd-1\nd-2\n");
  // The other way round: a shard running, then a plain run.
  const pid_t pid2 = start_run(s, {"p.yaml", "-q", "-B", "--shard", "0/2"});
  std::this_thread::sleep_for(std::chrono::milliseconds(800));
  const auto plain = run_in(s.dir, "p.yaml -q");
  EXPECT_NE(plain.code, 0);
  EXPECT_TRUE(has(plain.err, "another tomodem-run")) << plain.err;
  ::waitpid(pid2, &st, 0);
  EXPECT_EQ(s.read("runs.txt"), "prep\nd-1\nd-2\nprep\n");
  // Two splits of one sweep that share a cell (2/2 and 3/4 both hold the third of four): the
  // second one skips the cell while the first runs it.
  s.write("r.yaml", "steps:\n  cell:\n    matrix: {d: [1, 2, 3, 4]}\n"
                    "    cmd: sleep 2 && echo ${cell} >> runs2.txt && echo > ${outs.0}\n    outs: ['r${cell}.txt']\n");
  const pid_t pid3 = start_run(s, {"r.yaml", "-q", "-j", "1", "--shard", "2/2"});
  std::this_thread::sleep_for(std::chrono::milliseconds(800));
  const auto other = run_in(s.dir, "r.yaml --shard 3/4");
  EXPECT_NE(other.code, 0);
  EXPECT_TRUE(has(other.err, "skipped cell[d-3]: another tomodem-run is running this step now")) << other.err;
  ::waitpid(pid3, &st, 0);
  EXPECT_EQ(s.read("runs2.txt"), "d-3\nd-4\n");  // each once
}

// Item 8: a sweep size that is a typo is refused before anything is expanded.
TEST(RunSafety, HugeSweepIsRefusedAtOnce) {
  Scratch s;
  for (const std::string rep : {"1e9", "1000000000", "1000001"}) {
    s.write("p.yaml", "steps:\n  a:\n    replicas: " + rep + "\n    cmd: echo > ${outs.0}\n    outs: ['a${cell}.txt']\n");
    const auto t0 = std::chrono::steady_clock::now();
    const auto r = run_in(s.dir, "p.yaml");
    EXPECT_EQ(r.code, 2) << rep << "\n" << r.err;
    EXPECT_TRUE(has(r.err, "p.yaml:3")) << r.err;
    EXPECT_TRUE(has(r.err, "instances")) << r.err;
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 5.0);
  }
  s.write("p.yaml", "steps:\n  a:\n    matrix: {a: [1,2,3,4,5,6,7,8,9,10], b: [1,2,3,4,5,6,7,8,9,10]}\n"
                    "    replicas: 20000\n    cmd: echo > ${outs.0}\n    outs: ['a${cell}.txt']\n");
  EXPECT_EQ(run_in(s.dir, "p.yaml").code, 2);
}

// The report replaces its folder: never the current folder, one holding the rows, or a folder
// of the user's that is not a report.
TEST(RunSafety, ReportNeverReplacesAFolderItDidNotMake) {
  Scratch s;
  s.write("rows/r1.json", "{\"a\": 1}\n");
  s.write("mine/notes.txt", "notes\n");
  const auto before = snapshot(s.dir);
  for (const std::string& out : std::vector<std::string>{".", "..", "rows", "mine", s.dir}) {
    const auto r = run_in(s.dir, "report -o " + q(out) + " rows/r1.json");
    EXPECT_EQ(r.code, 2) << out << "\n" << r.err;
    EXPECT_TRUE(has(r.err, "-o")) << r.err;
    EXPECT_EQ(snapshot(s.dir), before) << out;
  }
  ASSERT_EQ(run_in(s.dir, "report -o rep rows/r1.json").code, 0);
  ASSERT_EQ(run_in(s.dir, "report -o rep rows/r1.json").code, 0);  // its own folder: replaced
  EXPECT_TRUE(fs::exists(s.path("rep/.tomodem-report")));
  // A row named as its own output is refused.
  const auto same = run_in(s.dir, "row -o rows/r1.json --summary a=rows/r1.json");
  EXPECT_EQ(same.code, 2) << same.err;
  EXPECT_EQ(s.read("rows/r1.json"), "{\"a\": 1}\n");
}

// Review D1: `kill -9` of the runner ends the step's shell (PR_SET_PDEATHSIG) but not what the
// shell started, which went on writing the output while a run started at once ran the step
// again and recorded the mixed file. Those processes hold the step's lock (they inherit it), so
// the next run stops their process group before it runs the step.
TEST(RunSafety, KillNineLeavesNoOrphanThatARerunMixesWith) {
  Scratch s;
  s.write("p.yaml", "steps:\n  a:\n    cmd: sh -c 'for i in 1 2 3 4 5 6 7 8; do echo line $i >> a.txt; sleep 0.3; done;"
                    " echo complete >> a.txt'; echo wrapper-done\n    outs: [a.txt]\n");
  const pid_t pid = start_run(s, {"p.yaml", "-q"});
  for (int k = 0; k < 100 && s.read("a.txt").size() < 14; ++k) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  ::kill(pid, SIGKILL);
  ::waitpid(pid, nullptr, 0);
  const auto r = run_in(s.dir, "p.yaml");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(has(r.err, "stop process group ")) << r.err;
  EXPECT_TRUE(has(r.err, "left running by an earlier run of a whose runner was killed")) << r.err;
  std::this_thread::sleep_for(std::chrono::milliseconds(1000));  // an orphan left running would write now
  EXPECT_EQ(s.read("a.txt"), "line 1\nline 2\nline 3\nline 4\nline 5\nline 6\nline 7\nline 8\ncomplete\n");
  EXPECT_TRUE(has(run_in(s.dir, "status p.yaml").out, "up to date  a"));
}

// Review D6: the run lock lived only in <stem>.logs, so a link to the pipeline under another name
// ran beside it, both writing one output. The pipeline file itself is locked as well.
TEST(RunSafety, ALinkToThePipelineIsTheSamePipelineForTheRunLock) {
  Scratch s;
  s.write("p.yaml", "steps:\n  a:\n    cmd: for i in 1 2 3 4 5; do echo pass $i >> ${outs.0}; sleep 0.3; done\n"
                    "    outs: [a.txt]\n");
  fs::create_symlink("p.yaml", s.path("q.yaml"));
  fs::create_hard_link(s.path("p.yaml"), s.path("h.yaml"));
  const pid_t pid = start_run(s, {"p.yaml", "-q"});
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  for (const char* other : {"q.yaml", "h.yaml", "q.yaml --shard 1/1"}) {
    const auto r = run_in(s.dir, std::string(other) + " -q");
    EXPECT_NE(r.code, 0) << other;
    EXPECT_TRUE(has(r.err, "under this or another name")) << other << ": " << r.err;
  }
  int st = 0;
  ::waitpid(pid, &st, 0);
  EXPECT_TRUE(WIFEXITED(st) && WEXITSTATUS(st) == 0);
  EXPECT_EQ(s.read("a.txt"), "pass 1\npass 2\npass 3\npass 4\npass 5\n");
}
