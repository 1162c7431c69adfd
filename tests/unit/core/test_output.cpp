// core/output.hpp: CSV tables, atomic text writes, content hashes, timestamps.
#include "tomodem/core/output.hpp"

#include <gtest/gtest.h>

#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <csignal>
#include <regex>
#include <thread>

#include "tmpdir.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/tool.hpp"

namespace tomodem {
namespace {

using test::TmpDir;

class Output : public TmpDir {};

TEST(CsvTable, HeaderThenRows) {
  const std::string t = csv_table({"time_s", "kinetic_energy_J"}, {{0, 1.5}, {1e-6, 0.1}});
  EXPECT_EQ(t, "time_s,kinetic_energy_J\n0,1.5\n1e-06,0.1\n");
}

TEST(CsvTable, TenSignificantDigits) {
  // Precision 10: enough for plots and fits, stable text for diffs.
  EXPECT_EQ(csv_table({"x"}, {{1.0 / 3.0}}), "x\n0.3333333333\n");
  EXPECT_EQ(csv_table({"a", "b"}, {}), "a,b\n");
}

TEST(TemporaryPath, SameFolderDifferentName) {
  const std::string t = temporary_path("/some/dir/out.h5");
  EXPECT_EQ(t.rfind("/some/dir/out.h5", 0), 0u);  // same folder: rename stays atomic
  EXPECT_NE(t, "/some/dir/out.h5");
}

TEST_F(Output, WriteTextAtomicWritesAndReplaces) {
  write_text_atomic(file("a.txt"), "first\n");
  EXPECT_EQ(test::slurp(file("a.txt")), "first\n");
  write_text_atomic(file("a.txt"), std::string("sec\0ond", 7));  // binary-safe
  EXPECT_EQ(test::slurp(file("a.txt")), std::string("sec\0ond", 7));
  EXPECT_EQ(test::entries(dir), (std::vector<std::string>{"a.txt"}));  // no temporary left
}

// An output that is a special file (here a FIFO, as /dev/null or a pipe given to --json) is written
// through and stays what it was: renaming a temporary onto /dev/null replaced the device with a
// regular file for every later program on the machine.
TEST_F(Output, SpecialFileIsWrittenThroughNotReplaced) {
  const std::string fifo = file("pipe");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::string got;
  std::thread reader([&] { got = test::slurp(fifo); });
  write_text_atomic(fifo, "{\"a\": 1}\n");
  reader.join();
  EXPECT_EQ(got, "{\"a\": 1}\n");
  struct stat st {};
  ASSERT_EQ(::stat(fifo.c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
  EXPECT_EQ(test::entries(dir), (std::vector<std::string>{"pipe"}));  // no temporary beside it
}

TEST_F(Output, WriteTextAtomicFailsCleanly) {
  EXPECT_THROW(write_text_atomic(file("missing/dir/a.txt"), "x"), RuntimeFailure);
  EXPECT_TRUE(test::entries(dir).empty());
}

TEST_F(Output, CommitWithoutTemporaryFails) {
  EXPECT_THROW(commit_output(file("never_written.h5")), RuntimeFailure);
}

TEST_F(Output, FileHashStableAndContentSensitive) {
  write_text_atomic(file("a"), "hello world\n");
  write_text_atomic(file("b"), "hello world\n");
  write_text_atomic(file("c"), "hello world!");
  write_text_atomic(file("empty"), "");
  const std::string ha = file_hash(file("a"));
  EXPECT_TRUE(std::regex_match(ha, std::regex("[0-9a-f]{32}"))) << ha;  // XXH3-128 in hex
  EXPECT_EQ(ha, file_hash(file("a")));
  EXPECT_EQ(ha, file_hash(file("b")));  // content, not name
  EXPECT_NE(ha, file_hash(file("c")));
  // XXH3-128 of no bytes is a published constant: pins the algorithm and the hex order (high first).
  EXPECT_EQ(file_hash(file("empty")), "99aa06d3014798d86001c324468d497f");
  // Larger than the 64 KiB read buffer: a change in the last byte must still show.
  std::string big(200000, 'x');
  write_text_atomic(file("big1"), big);
  big.back() = 'y';
  write_text_atomic(file("big2"), big);
  EXPECT_NE(file_hash(file("big1")), file_hash(file("big2")));
}

TEST_F(Output, FileHashMissingFileIsInputError) {
  try {
    file_hash(file("nope"));
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), file("nope"));
  }
}

// A full disk (here: a file-size limit, which fails writes past it with EFBIG the way a full
// disk fails them with ENOSPC) never turns a good file into a short or empty one.
TEST_F(Output, WriteFailureKeepsTheOldFileAndLeavesNoTemporary) {
  write_text_atomic(file("lock.json"), "good\n");
  const pid_t pid = ::fork();
  if (pid == 0) {
    std::signal(SIGXFSZ, SIG_IGN);
    const rlimit lim{1024, 1024};
    ::setrlimit(RLIMIT_FSIZE, &lim);
    try {
      write_text_atomic(file("lock.json"), std::string(4096, 'x'));
    } catch (const RuntimeFailure& e) {
      ::_exit(std::string(e.what()).find("lock.json") != std::string::npos ? 10 : 11);
    }
    ::_exit(12);
  }
  int st = 0;
  ::waitpid(pid, &st, 0);
  ASSERT_TRUE(WIFEXITED(st));
  EXPECT_EQ(WEXITSTATUS(st), 10);  // a RuntimeFailure naming the file
  EXPECT_EQ(test::slurp(file("lock.json")), "good\n");
  EXPECT_EQ(test::entries(dir), (std::vector<std::string>{"lock.json"}));
}

// A tool's outputs appear together when its run ends: a run that fails after writing some of
// them (here the second of three, as a full disk or a failed solve after the first file would)
// leaves none, and the files they would have replaced stay as they were.
TEST_F(Output, ARunThatFailsLeavesNoneOfItsOutputs) {
  write_text_atomic(file("curve.csv"), "old curve\n");
  const int code = run_tool("tomodem-test", [&]() -> int {
    write_text_atomic(file("curve.csv"), "new curve\n");
    write_text_atomic(file("necks.csv"), "necks\n");
    EXPECT_EQ(test::slurp(file("curve.csv")), "old curve\n") << "renamed before the run ended";
    EXPECT_FALSE(std::filesystem::exists(file("necks.csv")));
    throw RuntimeFailure("the solve failed");
  });
  EXPECT_EQ(code, 1);
  EXPECT_EQ(test::slurp(file("curve.csv")), "old curve\n");
  EXPECT_EQ(test::entries(dir), (std::vector<std::string>{"curve.csv"}));  // no temporaries either
}

TEST_F(Output, ARunThatEndsRenamesEveryOutputWhateverItsCode) {
  for (const int returned : {0, 4}) {  // 4: a run short of its target keeps what it wrote
    const int code = run_tool("tomodem-test", [&]() -> int {
      write_text_atomic(file("a.csv"), "a\n");
      write_text_atomic(file("b.json"), "{}\n");
      write_text_atomic(file("a.csv"), "a again\n");  // written twice: the last text, renamed once
      std::ofstream(temporary_path(file("checkpoint.h5"))) << "state\n";
      commit_output(file("checkpoint.h5"), Commit::now);
      EXPECT_TRUE(std::filesystem::exists(file("checkpoint.h5")));
      return returned;
    });
    EXPECT_EQ(code, returned);
    EXPECT_EQ(test::slurp(file("a.csv")), "a again\n");
    EXPECT_EQ(test::slurp(file("b.json")), "{}\n");
    EXPECT_EQ(test::entries(dir), (std::vector<std::string>{"a.csv", "b.json", "checkpoint.h5"}));
    for (const auto& f : test::entries(dir)) std::filesystem::remove(file(f));
  }
}

// A checkpoint must survive a run that fails after writing it: Commit::now renames at once.
TEST_F(Output, ACheckpointCommittedNowOutlivesTheRun) {
  const int code = run_tool("tomodem-test", [&]() -> int {
    std::ofstream(temporary_path(file("restart.h5"))) << "state";
    commit_output(file("restart.h5"), Commit::now);
    write_text_atomic(file("series.csv"), "t\n");
    throw NumericalError("the time step collapsed");
  });
  EXPECT_EQ(code, 3);
  EXPECT_EQ(test::entries(dir), (std::vector<std::string>{"restart.h5"}));
}

// kill -9 runs no handler: the next run with the same output removes the temporaries whose
// process is gone, and leaves a live process's (that run is writing now) and other names alone.
TEST_F(Output, TemporariesOfAKilledRunGoWithTheNextRun) {
  const pid_t dead = ::fork();
  if (dead == 0) ::_exit(0);
  ::waitpid(dead, nullptr, 0);
  const std::string gone = std::to_string(dead), live = std::to_string(::getppid());
  for (const std::string& f : std::vector<std::string>{"out.h5.tmp" + gone, "out.h5.tmp" + gone + ".nii.gz", "out.h5.tmp" + live,
                               "out.h5.tmpx", "out.h5.tmp" + gone + "x", "other.h5.tmp" + gone})
    std::ofstream(file(f)) << "half written";
  check_outputs({}, {{"-o", file("out.h5")}});
  std::vector<std::string> kept{"other.h5.tmp" + gone, "out.h5.tmp" + gone + "x", "out.h5.tmp" + live, "out.h5.tmpx"};
  std::sort(kept.begin(), kept.end());
  EXPECT_EQ(test::entries(dir), kept);
}

TEST_F(Output, SigtermRemovesRegisteredTemporaries) {
  for (const int sig : {SIGTERM, SIGINT}) {
    const pid_t pid = ::fork();
    if (pid == 0) {
      install_cleanup_handlers();
      const std::string tmp = temporary_path(file("big.h5"));
      std::ofstream(tmp) << "half written";
      ::raise(sig);
      ::_exit(0);
    }
    int st = 0;
    ::waitpid(pid, &st, 0);
    EXPECT_TRUE(WIFSIGNALED(st) && WTERMSIG(st) == sig);  // still ends by the signal
    EXPECT_TRUE(test::entries(dir).empty()) << "signal " << sig;
  }
}

TEST_F(Output, DiscardRemovesTheTemporaryAndCommitFailureToo) {
  std::ofstream(temporary_path(file("a.h5"))) << "x";
  discard_output(file("a.h5"));
  EXPECT_TRUE(test::entries(dir).empty());
}

TEST_F(Output, OutputOverInputIsRefused) {
  write_text_atomic(file("in.h5"), "data");
  const std::string via_dot = dir + "/./in.h5";
  EXPECT_THROW(refuse_output_over_input(file("in.h5"), "--json", {file("in.h5")}), InputError);
  EXPECT_THROW(refuse_output_over_input(via_dot, "-o", {file("in.h5")}), InputError);
  ASSERT_EQ(::link(file("in.h5").c_str(), file("hard.h5").c_str()), 0);
  EXPECT_THROW(refuse_output_over_input(file("hard.h5"), "-o", {file("in.h5")}), InputError);
  ASSERT_EQ(::symlink(file("in.h5").c_str(), file("soft.h5").c_str()), 0);
  EXPECT_THROW(refuse_output_over_input(file("soft.h5"), "-o", {file("in.h5")}), InputError);
  EXPECT_NO_THROW(refuse_output_over_input(file("out.h5"), "-o", {file("in.h5")}));
  // A folder output: refused when it holds an input, accepted beside it.
  EXPECT_THROW(refuse_output_over_input(dir, "-o", {file("in.h5")}, true), InputError);
  EXPECT_NO_THROW(refuse_output_over_input(file("out"), "-o", {file("in.h5")}, true));
  try {
    refuse_output_over_input(file("in.h5"), "--json", {file("in.h5")});
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "--json");
    EXPECT_EQ(e.value(), file("in.h5"));
  }
}

// A folder that exists but takes no file is refused before any work (the hostile review found
// young, fracture and conduct writing their curves and fields, then failing on --json at the
// end). As root, mode bits do not stop a write: the folder is made immutable (chattr +i) there.
TEST_F(Output, UnwritableFolderIsRefusedBeforeAnyWork) {
  const std::string ro = file("ro");
  ASSERT_EQ(::mkdir(ro.c_str(), 0755), 0);
  EXPECT_NO_THROW(check_outputs({}, {{"--json", ro + "/s.json"}}));
  EXPECT_TRUE(test::entries(ro).empty());  // the probe is gone
  ASSERT_EQ(::mkfifo((ro + "/fifo").c_str(), 0600), 0);  // written through, so no probe for it
  const bool immutable = ::geteuid() == 0 && std::system(("chattr +i '" + ro + "' 2>/dev/null").c_str()) == 0;
  if (!immutable && (::geteuid() == 0 || ::chmod(ro.c_str(), 0555) != 0)) GTEST_SKIP() << "cannot make a read-only folder here";
  try {
    check_outputs({}, {{"--curve", file("c.csv")}, {"--json", ro + "/s.json"}});
    ADD_FAILURE() << "an unwritable folder was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "--json");
    EXPECT_NE(std::string(e.what()).find("cannot be written"), std::string::npos) << e.what();
  }
  // A FIFO (or /dev/stdout) in a folder that takes no file is still an output: it is written
  // through, not replaced (a user without write access to /dev would be refused otherwise).
  EXPECT_NO_THROW(check_outputs({}, {{"--json", ro + "/fifo"}}));
  if (immutable) EXPECT_EQ(std::system(("chattr -i '" + ro + "'").c_str()), 0);
  else ::chmod(ro.c_str(), 0755);
}

TEST(OutputsOutside, RelativeInsideOnly) {
  EXPECT_NO_THROW(refuse_output_outside("a/b.h5", "out", "s.yaml", "output.packing"));
  for (const char* bad : {"../x.h5", "../../x.h5", "/etc/x.h5", ".", "a/../..", ""})
    EXPECT_THROW(refuse_output_outside(bad, "out", "s.yaml", "output.packing"), InputError) << bad;
}

TEST(MemoryRequest, RefusedWithNeedAndHave) {
  const double have = static_cast<double>(usable_memory_bytes());
  EXPECT_GT(have, 1e8);
  EXPECT_NO_THROW(check_memory_request(1e6, "s.yaml", "count", "1000", "1000 particles"));
  try {
    check_memory_request(1e15, "s.yaml", "particles.count", "1e12", "10^12 particles");
    FAIL() << "no exception";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("s.yaml"), std::string::npos) << m;
    EXPECT_NE(m.find("particles.count"), std::string::npos) << m;
    EXPECT_NE(m.find("1 PB"), std::string::npos) << m;
    EXPECT_NE(m.find("this machine has"), std::string::npos) << m;
  }
  EXPECT_THROW(check_memory_request(std::nan(""), "f", "x", "nan", "x"), InputError);
  EXPECT_EQ(bytes_text(1.5e9), "1.5 GB");
}

TEST(UtcNow, Iso8601) {
  EXPECT_TRUE(std::regex_match(utc_now(), std::regex(R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ)"))) << utc_now();
}

}  // namespace
}  // namespace tomodem
